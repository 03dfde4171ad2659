// The table diagnosis' Monte Carlo matrix (docs/accuracy.md "The diagnosis matrix"): every family
// of the family table that a profile can lack, hidden alone in rot19 and seed8 sessions of the
// nav-fog and mems profiles, plus pairs of a dwell effect and a turn effect, plus clean sessions;
// each cell's magnitudes a band of the family's detection sigma on that plan and profile, each
// coefficient's sign random. Scored strictly: the hidden family (or an ambiguous set holding it)
// named first, no family the data lack named anywhere, every determined magnitude within 3
// sigma; each row also counts the seeds whose residual is "unexplained" and the quiet ones (no
// finding, nothing unexplained: what a clean cell must be).
//
// The full matrix is a documented command (hidden test, [.]):
//   SINSCAL_MATRIX_SEEDS=30 build/tests/sinscal_tests "[matrix]"
// with SINSCAL_MATRIX_FILTER=TEXT (cells whose name contains it; TEXT$: ends with it),
// SINSCAL_MATRIX_BAND=strong|limit (5-10 or 3-5 detection sigmas; default both),
// SINSCAL_MATRIX_PLANS=a.ini,b.ini (default rot19.ini,seed8.ini), SINSCAL_MATRIX_VERBOSE=1 (every
// seed's story, refusals and stops) and SINSCAL_MATRIX_OUT=FILE (rows appended). CI runs a slice
// ([matrix_slice]).
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>

#include "catalog.hpp"
#include "diagnosis_cases.hpp"

using namespace sinscal;
using namespace sinscal::test;

namespace {

constexpr double kMatrixRate = 20.0;  // Hz: the detection sigmas scale with the noise densities

struct Cell {
  std::string plan, profile;          // config/plans/..., config/sensors/...
  std::vector<std::string> families;  // hidden; none: a clean session
  std::string name() const {
    std::string n =
        plan.substr(0, plan.find('.')) + " " + profile.substr(0, profile.find('.')) + " ";
    if (families.empty()) return n + "clean";
    for (std::size_t i = 0; i < families.size(); ++i) n += (i ? "+" : "") + families[i];
    return n;
  }
};

// The family's profile key as a section and a key ("accel.k2" -> [accel] k2).
ProfileLine profile_line(const std::string& family, double lo_si, double hi_si) {
  const CoefficientFamily& info = coefficient_family_info(family);
  const auto dot = info.profile_key.find('.');
  char b[160];
  std::snprintf(b, sizeof b, "%s = %.6g %.6g %s", info.profile_key.substr(dot + 1).c_str(),
                lo_si / info.si_per_unit(), hi_si / info.si_per_unit(), info.unit().c_str());
  return {info.profile_key.substr(0, dot), b};
}

// The family's detection sigma on the plan and profile (SI): the median sigma of its components
// in the dwells' fit with it added to the diagnosis's dwells' model (the base and the profile's
// extended families; families with a static signature), else in the filter run with it switched
// on (the effects of the turns, and families the profile's own take on the dwells), on a clean
// session. SINSCAL_MATRIX_VERBOSE prints it and its source.
double detection_sigma(const std::string& plan, const std::string& profile,
                       const std::string& family) {
  static std::map<std::string, double> cache;
  const std::string key = plan + "|" + profile + "|" + family;
  if (cache.count(key)) return cache[key];
  // The profile without the family (as the sessions' filter profile), a session without it.
  const HiddenCase c = hidden_case("matrix_sigma", plan, profile, {profile_line(family, 0.0, 0.0)},
                                   999, kMatrixRate);
  const CaseCalibration cc = calibrate_case(c);
  const TurnModel& model = cc.model;
  const ClosedFormReport& cal = cc.calibration;
  // The dwells' model as the diagnosis has it (its noise model, the base and the profile's
  // extended families). Without the profile's families the MEMS profile's K2 was missing, which
  // takes accel.scale_asym's whole dwell signature on plans of axis-aligned dwells (|f| and f^2
  // at -g, 0, +g): the cell was sized at a sigma the diagnosis never has (issue 33).
  Stage2Options o = dwells_model(cal.stage2_options, &model);
  const std::vector<int> components = family_coefficients(family);
  const auto first = static_cast<Eigen::Index>(o.parameters.size());
  o.parameters.insert(o.parameters.end(), components.begin(), components.end());
  const Stage2Result r = solve_stage2(cal.stage1, c.session.site, o);
  std::vector<double> sigmas;
  const std::vector<double> priors = grade_priors(model.base);  // the session's grade
  for (std::size_t j = 0; j < components.size(); ++j) {
    const auto i = first + static_cast<Eigen::Index>(j);
    const double s = std::sqrt(r.cov(i, i));
    const double prior = priors[static_cast<std::size_t>(components[j])];
    if (r.observable[static_cast<std::size_t>(i)] && s < prior / 3.0) sigmas.push_back(s);
  }
  const char* source = "dwells";
  if (sigmas.empty()) {
    source = "filter";
    CalibratorOptions ko = model.base;
    ko.layout.set(family, true);
    const KalmanRun run = run_kalman(c.session, ko);
    for (int k : components) {
      const auto& e = run.estimates[static_cast<std::size_t>(k)];
      if (e.observed()) sigmas.push_back(e.sigma);
    }
  }
  // None: neither test determines the family on this plan and profile (its default prior, the
  // prior of a profile without it, is below what the data resolve): the cell cannot be run.
  if (sigmas.empty()) {
    if (std::getenv("SINSCAL_MATRIX_VERBOSE"))
      std::printf("  detection sigma %s on %s %s: determined by neither test\n", family.c_str(),
                  plan.c_str(), profile.c_str());
    return cache[key] = std::numeric_limits<double>::quiet_NaN();
  }
  std::sort(sigmas.begin(), sigmas.end());
  if (std::getenv("SINSCAL_MATRIX_VERBOSE")) {
    std::printf("  detection sigma %s on %s %s: %.4g SI (%zu components, %s)\n", family.c_str(),
                plan.c_str(), profile.c_str(), sigmas[sigmas.size() / 2], sigmas.size(), source);
  }
  return cache[key] = sigmas[sigmas.size() / 2];
}

struct CellScore {
  int seeds = 0, first_right = 0, false_named = 0, all_named = 0, magnitudes = 0, covered = 0;
  int ambiguous_first = 0;
  int unexplained = 0;  // seeds whose final residual is "unexplained" (Unexplained::present)
  int quiet = 0;        // seeds with no finding and nothing unexplained
  int errors = 0;       // diagnoses that failed (a filter run that stopped or diverged)
  std::string worst_story;
};

// One seed's outcome, its refused findings with their reasons and its stops
// (SINSCAL_MATRIX_VERBOSE set: a cell's misses examined seed by seed).
void print_seed(std::uint64_t seed, const DiagnosisOutcome& o) {
  std::printf("  seed %llu: first right %d, all named %d: %s\n",
              static_cast<unsigned long long>(seed), o.first_right ? 1 : 0, o.all_named ? 1 : 0,
              o.story.c_str());
  for (const auto& f : o.result.findings)
    if (!f.pick_note.empty()) std::printf("    %s: %s\n", f.family.c_str(), f.pick_note.c_str());
  for (const auto& r : o.result.rejected)
    std::printf("    refused %s (round %d): %s\n", r.finding.family.c_str(), r.finding.round,
                r.reason.c_str());
  for (const auto& w : o.result.stops) std::printf("    stop: %s\n", w.c_str());
  if (o.result.unexplained.present)
    for (const auto& w : o.result.unexplained.signature)
      std::printf("    unexplained: %s\n", w.c_str());
  std::printf(
      "    held-out predictive chi2 %.4g on %d inputs (99 %% quantile %.4g); dwells chi2 %.4g on "
      "%d dof (%.4g)\n",
      o.result.check.heldout_chi2, o.result.check.heldout_inputs, o.result.check.heldout_quantile,
      o.result.check.dwells_chi2, o.result.check.dwells_dof, o.result.check.dwells_quantile);
}

// Runs `seeds` sessions of the cell, magnitudes in [lo, hi] detection sigmas.
CellScore run_cell(const Cell& cell, int seeds, double lo, double hi, std::uint64_t seed0) {
  std::vector<ProfileLine> lines;
  CellScore score;
  for (const auto& f : cell.families) {
    const double s = detection_sigma(cell.plan, cell.profile, f);
    if (!std::isfinite(s)) {
      score.worst_story = "not run: " + f +
                          " is determined by neither test on this plan and profile (its "
                          "default prior is below what the data resolve)";
      return score;
    }
    lines.push_back(profile_line(f, lo * s, hi * s));
  }
  for (int k = 0; k < seeds; ++k) {
    const HiddenCase c = hidden_case("matrix", cell.plan, cell.profile, lines,
                                     seed0 + static_cast<std::uint64_t>(k), kMatrixRate);
    ++score.seeds;
    DiagnosisOutcome o;
    try {
      o = diagnose_hidden(c, cell.families);
    } catch (const std::exception& e) {
      ++score.errors;
      if (score.worst_story.empty())
        score.worst_story = "seed " + std::to_string(seed0 + static_cast<std::uint64_t>(k)) +
                            ": diagnosis failed: " + e.what();
      continue;
    }
    const bool right = cell.families.empty() ? o.result.findings.empty() : o.first_right;
    score.first_right += right ? 1 : 0;
    score.ambiguous_first += o.ambiguous_first ? 1 : 0;
    score.false_named += o.false_names.empty() ? 0 : 1;
    score.all_named += o.all_named ? 1 : 0;
    score.unexplained += o.result.unexplained.present ? 1 : 0;
    score.quiet += o.result.findings.empty() && !o.result.unexplained.present ? 1 : 0;
    if (o.magnitudes_checked > 0) {
      ++score.magnitudes;
      score.covered += o.worst_sigma < 3.0 ? 1 : 0;
    }
    if (std::getenv("SINSCAL_MATRIX_VERBOSE")) print_seed(seed0 + static_cast<std::uint64_t>(k), o);
    if ((!right || !o.false_names.empty()) && score.worst_story.empty())
      score.worst_story =
          "seed " + std::to_string(seed0 + static_cast<std::uint64_t>(k)) + ": " + o.story;
  }
  return score;
}

std::string row(const Cell& cell, const char* band, const CellScore& s) {
  char b[512];
  std::snprintf(b, sizeof b, "| %s | %s | %d/%d | %d | %d | %d | %d | %d/%d | %s | %d |",
                cell.name().c_str(), band, s.first_right, s.seeds, s.ambiguous_first, s.false_named,
                s.unexplained, s.quiet, s.covered, s.magnitudes,
                cell.families.size() > 1 ? std::to_string(s.all_named).c_str() : "-", s.errors);
  return b;
}

// A part of SINSCAL_MATRIX_FILTER: a substring of the cell's name; ending in '$', its end
// ("mems accel.k2$": the cell alone, not its pair with the time delay).
bool filter_matches(const std::string& name, std::string part) {
  if (part.empty() || part.back() != '$') return name.find(part) != std::string::npos;
  part.pop_back();
  return name.size() >= part.size() &&
         name.compare(name.size() - part.size(), part.size(), part) == 0;
}

std::vector<Cell> matrix_cells() {
  std::vector<Cell> cells;
  const std::vector<std::string> families = {
      "accel.k2",        "gyro.scale_asym", "accel.scale_asym", "gyro.g_sensitivity",
      "accel.lever_arm", "time_delay",      "gyro.bias_drift",  "accel.bias_drift"};
  // SINSCAL_MATRIX_PLANS: other plans of config/plans, comma-separated (rot19-2rates.ini: turns
  // at two rates, docs/methods/diagnosis.md).
  const char* env_plans = std::getenv("SINSCAL_MATRIX_PLANS");
  std::vector<std::string> plans;
  std::stringstream parts(env_plans ? env_plans : "rot19.ini,seed8.ini");
  for (std::string p; std::getline(parts, p, ',');) plans.push_back(p);
  for (const std::string profile : {"nav-fog.ini", "mems.ini"})
    for (const std::string& plan : plans) {
      cells.push_back({plan, profile, {}});
      for (const auto& f : families) cells.push_back({plan, profile, {f}});
      // Pairs: a dwell effect and a turn effect together.
      cells.push_back({plan, profile, {"accel.k2", "time_delay"}});
      cells.push_back({plan, profile, {"gyro.g_sensitivity", "accel.lever_arm"}});
      cells.push_back({plan, profile, {"gyro.bias_drift", "gyro.scale_asym"}});
    }
  return cells;
}

}  // namespace

TEST_CASE("Diagnosis matrix: every family hidden, both plans, both profiles", "[.][matrix]") {
  const char* env_seeds = std::getenv("SINSCAL_MATRIX_SEEDS");
  const char* env_filter = std::getenv("SINSCAL_MATRIX_FILTER");
  const char* env_band = std::getenv("SINSCAL_MATRIX_BAND");
  const char* env_out = std::getenv("SINSCAL_MATRIX_OUT");
  const int seeds = env_seeds ? std::atoi(env_seeds) : 30;
  const std::string band = env_band ? env_band : "";
  std::printf(
      "| cell | band | named first | of which an ambiguous set | false name | unexplained | quiet "
      "| magnitudes within 3 sigma | pair both named | failed |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n");
  const auto cells = matrix_cells();
  for (std::size_t index = 0; index < cells.size(); ++index) {
    const Cell& cell = cells[index];
    // The filter: substrings separated by '|', a cell runs when its name holds one of them.
    if (env_filter) {
      bool any = false;
      std::stringstream parts(env_filter);
      std::string part;
      while (std::getline(parts, part, '|')) any = any || filter_matches(cell.name(), part);
      if (!any) continue;
    }
    const std::vector<std::pair<const char*, std::pair<double, double>>> bands =
        cell.families.empty()
            ? std::vector<std::pair<const char*, std::pair<double, double>>>{{"-", {0.0, 0.0}}}
            : std::vector<std::pair<const char*, std::pair<double, double>>>{
                  {"strong", {5.0, 10.0}}, {"limit", {3.0, 5.0}}};
    for (const auto& [name, range] : bands) {
      if (!band.empty() && name != band && !cell.families.empty()) continue;
      // Independent seeds per cell and band (no noise draw shared between cells).
      const CellScore s = run_cell(cell, seeds, range.first, range.second,
                                   5000 + 1000 * index + (std::string(name) == "limit" ? 500 : 0));
      const std::string r = row(cell, name, s);
      std::printf("%s\n", r.c_str());
      if (!s.worst_story.empty()) std::printf("    first miss: %s\n", s.worst_story.c_str());
      std::fflush(stdout);
      if (env_out) {
        std::FILE* f = std::fopen(env_out, "a");
        if (f) {
          std::fprintf(f, "%s\n", r.c_str());
          if (!s.worst_story.empty())
            std::fprintf(f, "    first miss: %s\n", s.worst_story.c_str());
          std::fclose(f);
        }
      }
    }
  }
}

// CI's slice: the hardest cells a few seeds each, every seed right (a dwell effect under the
// turns' test, an effect of the turns on the 8-orientation plan, a pair, a clean session).
TEST_CASE("Diagnosis matrix slice: dwell effect under the turns' test, pair, clean",
          "[diagnosis][matrix_slice][long]") {
  const std::vector<Cell> slice = {
      {"rot19.ini", "nav-fog.ini", {"accel.k2"}},
      {"seed8.ini", "nav-fog.ini", {"time_delay"}},
      {"rot19.ini", "nav-fog.ini", {"gyro.g_sensitivity", "accel.lever_arm"}},
      {"rot19.ini", "nav-fog.ini", {}}};
  for (const auto& cell : slice) {
    const CellScore s = run_cell(cell, 2, 5.0, 10.0, 7000);
    INFO(row(cell, "strong", s) << " " << s.worst_story);
    CHECK(s.first_right == s.seeds);
    CHECK(s.false_named == 0);
    CHECK(s.covered == s.magnitudes);
    CHECK(s.errors == 0);
    if (cell.families.size() > 1) CHECK(s.all_named == s.seeds);
  }
}

// CI's MEMS slice (issue 33, item 5): hidden K2 on rot19, hidden g-sensitivity on seed8, hidden
// accelerometer scale asymmetry on rot19 (sized by the dwells without the profile's K2 it was
// named on 0 of 30: the dwells' K2 takes its signature, the turns' sigma is 7 times the band's
// size; detection_sigma), 4 seeds each at 5-10 detection sigmas. Thresholds from the acceptance's
// 95 % (allowed_misses: a cell at that rate fails at most 1 % of the time): named first, no false
// name, no failed diagnosis.
TEST_CASE("Diagnosis matrix MEMS slice: hidden K2, g-sensitivity and accelerometer asymmetry",
          "[diagnosis][matrix_slice][mems][long]") {
  const int seeds = 4, allowed = allowed_misses(seeds);
  const std::vector<Cell> slice = {{"rot19.ini", "mems.ini", {"accel.k2"}},
                                   {"seed8.ini", "mems.ini", {"gyro.g_sensitivity"}},
                                   {"rot19.ini", "mems.ini", {"accel.scale_asym"}}};
  for (const auto& cell : slice) {
    const CellScore s = run_cell(cell, seeds, 5.0, 10.0, 7100);
    INFO(row(cell, "strong", s) << " " << s.worst_story << " (allowed misses " << allowed << ")");
    REQUIRE(s.seeds == seeds);  // the cell ran: its family is determined on this plan and profile
    CHECK(s.seeds - s.first_right <= allowed);
    CHECK(s.false_named <= allowed);
    CHECK(s.errors == 0);
  }
}
