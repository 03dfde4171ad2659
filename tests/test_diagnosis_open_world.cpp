// The table diagnosis in an open world (issue 33): effects outside the family catalog, injected
// into the log by test code (tests/out_of_catalog.hpp). Never a catalog family's name first; the
// residual reported "unexplained" with where it shows.
//
// The matrix at more seeds is a documented measurement (hidden test, [.]):
//   SINSCAL_OPEN_WORLD_SEEDS=30 build/tests/sinscal_tests "[open_world_matrix]"
// with SINSCAL_OPEN_WORLD_FILTER=TEXT (effects whose name contains it) and
// SINSCAL_OPEN_WORLD_PLANS=rot19.ini,seed8.ini and SINSCAL_OPEN_WORLD_SCALE=S (every effect S
// times its size; 0: clean sessions), SINSCAL_OPEN_WORLD_VERBOSE=1 (every seed's story, refusals,
// where the residual shows, terms), SINSCAL_OPEN_WORLD_SEED0=N (the first seed, 9000);
// results in docs/accuracy.md (nav-fog) and docs/measured/open-world.md (MEMS, the effects the
// library does not anticipate).
#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>

#include "out_of_catalog.hpp"

using namespace sinscal;
using namespace sinscal::test;

namespace {

constexpr double kOpenWorldRate = 20.0;  // Hz, as the diagnosis matrix
// The rot19 accelerometer product at half the matrix's size: about 8 library sigmas in the
// turns' velocity rows (105 +- 6.3 ug/g^2 at its size, seed 9000).
constexpr double kAccelTurnScale = 0.5;

struct OpenWorldScore {
  int seeds = 0, wrong_first = 0, unexplained = 0, quiet = 0, errors = 0;
  int right_term = 0;      // the effect's library term reported, within 3 sigma of the truth
  int wrong_term = 0;      // a library term reported, but not the effect's within 3 sigma
  int alternative = 0;     // a catalog family and the effect's library term first, as a set the
                           // plan cannot separate (TableFinding::library_alternative): not counted
                           // in wrong_first, the family is not given as the name
  int paired_without = 0;  // a catalog family and library terms first, the effect's not among them
  std::string first_miss, first_terms;
};

// The library's terms: whether the effect's is among them within 3 sigma (1), another term
// only (-1), or none (0).
int score_terms(const TableDiagnosis& d, const OpenWorldEffect& e, double scale = 1.0) {
  if (!d.unexplained.library || d.unexplained.library->terms.empty()) return 0;
  const auto right = [&](const LibraryTerm& t) {
    return !e.sensor.empty() && t.sensor == e.sensor && t.axis == e.axis &&
           t.formula.rfind(e.formula, 0) == 0 &&
           std::abs(t.value - scale * e.value) < 3.0 * t.sigma;
  };
  for (const auto& t : d.unexplained.library->terms) {
    if (right(t)) return 1;
    for (const auto& a : t.aliases)  // the plan cannot tell them apart: reported together
      if (right(a)) return 1;
  }
  return -1;
}

// The finding is a set the plan cannot separate of its family and the effect's library term
// (TableFinding::library_alternative), not the family alone.
bool is_pair_with(const TableFinding& f, const OpenWorldEffect& e) {
  return !e.formula.empty() && f.picked_by == "catalog" && f.alternative_term &&
         f.library_alternative.find(e.formula) != std::string::npos &&
         std::any_of(f.ambiguous_with.begin(), f.ambiguous_with.end(),
                     [&](const std::string& a) { return a.find(e.formula) != std::string::npos; });
}

// The pair's term is the effect's, within 3 sigma.
bool right_pair_term(const TableFinding& f, const OpenWorldEffect& e, double scale) {
  if (!f.alternative_term) return false;
  const LibraryTerm& t = *f.alternative_term;
  return t.sensor == e.sensor && t.axis == e.axis && t.formula.rfind(e.formula, 0) == 0 &&
         std::abs(t.value - scale * e.value) < 3.0 * t.sigma;
}

// One seed's outcome: its story, refused findings with their reasons, the library's terms
// (SINSCAL_OPEN_WORLD_VERBOSE set: a cell examined seed by seed).
void print_seed(std::uint64_t seed, const DiagnosisOutcome& o, int term) {
  std::printf("  seed %llu: term %d, unexplained %d: %s\n", static_cast<unsigned long long>(seed),
              term, o.result.unexplained.present ? 1 : 0, o.story.c_str());
  for (const auto& f : o.result.findings)
    if (!f.library_alternative.empty())
      std::printf("    alternative to %s: %s\n", f.family.c_str(), f.library_alternative.c_str());
  for (const auto& r : o.result.rejected)
    std::printf("    refused %s (round %d): %s\n", r.finding.family.c_str(), r.finding.round,
                r.reason.c_str());
  std::printf(
      "    held-out predictive chi2 %.4g on %d inputs (99 %% quantile %.4g); dwells chi2 %.4g on "
      "%d dof (%.4g)\n",
      o.result.check.heldout_chi2, o.result.check.heldout_inputs, o.result.check.heldout_quantile,
      o.result.check.dwells_chi2, o.result.check.dwells_dof, o.result.check.dwells_quantile);
  for (const auto& w : o.result.unexplained.signature) std::printf("    where: %s\n", w.c_str());
  if (o.result.unexplained.library)
    for (const auto& t : o.result.unexplained.library->terms)
      std::printf("    library: %s\n", t.text().c_str());
}

// The matrix's sensor profile: SINSCAL_OPEN_WORLD_PROFILE, or nav-fog.ini.
std::string open_world_profile() {
  const char* p = std::getenv("SINSCAL_OPEN_WORLD_PROFILE");
  return p ? p : "nav-fog.ini";
}

OpenWorldScore run_effect(const std::string& plan, std::size_t effect, int seeds,
                          std::uint64_t seed0, double scale,
                          const std::string& profile = open_world_profile()) {
  OpenWorldScore s;
  for (int k = 0; k < seeds; ++k) {
    const std::uint64_t seed = seed0 + static_cast<std::uint64_t>(k);
    ++s.seeds;
    DiagnosisOutcome o;
    try {
      const HiddenCase c = open_world_case(plan, profile, effect, seed, kOpenWorldRate, scale);
      o = diagnose_hidden(c, {});
    } catch (const std::exception& e) {
      ++s.errors;
      if (s.first_miss.empty()) s.first_miss = "seed " + std::to_string(seed) + ": " + e.what();
      continue;
    }
    const OpenWorldEffect e = open_world_effects(0.0)[effect];
    const int term = score_terms(o.result, e, scale);
    s.right_term += term > 0 ? 1 : 0;
    s.wrong_term += term < 0 ? 1 : 0;
    if (term != 0 && s.first_terms.empty())
      for (const auto& t : o.result.unexplained.library->terms) s.first_terms += t.text() + "; ";
    const bool pair = !o.result.findings.empty() && is_pair_with(o.result.findings.front(), e);
    const bool wrong = !o.result.findings.empty() && !pair;
    s.alternative += pair ? 1 : 0;
    s.paired_without +=
        !pair && !o.result.findings.empty() && o.result.findings.front().alternative_term ? 1 : 0;
    if (term <= 0 && pair && right_pair_term(o.result.findings.front(), e, scale)) {
      ++s.right_term;
      s.wrong_term -= term < 0 ? 1 : 0;
    }
    if (std::getenv("SINSCAL_OPEN_WORLD_VERBOSE")) print_seed(seed, o, term);
    s.wrong_first += wrong ? 1 : 0;
    s.unexplained += o.result.unexplained.present ? 1 : 0;
    s.quiet += o.result.findings.empty() && !o.result.unexplained.present ? 1 : 0;
    if ((wrong || (!o.result.unexplained.present && !pair)) && s.first_miss.empty()) {
      std::string where;
      for (const auto& w : o.result.unexplained.signature) where += " | " + w;
      for (const auto& w : o.result.stops) where += " | stop: " + w;
      s.first_miss = "seed " + std::to_string(seed) + ": " + o.story + where;
    }
  }
  return s;
}

}  // namespace

TEST_CASE("Open world: out-of-catalog effects on rot19 and seed8, measured",
          "[.][open_world_matrix]") {
  const char* env_seeds = std::getenv("SINSCAL_OPEN_WORLD_SEEDS");
  const char* env_filter = std::getenv("SINSCAL_OPEN_WORLD_FILTER");
  const char* env_plans = std::getenv("SINSCAL_OPEN_WORLD_PLANS");
  const char* env_scale = std::getenv("SINSCAL_OPEN_WORLD_SCALE");
  const double scale = env_scale ? std::atof(env_scale) : 1.0;
  const int seeds = env_seeds ? std::atoi(env_seeds) : 30;
  const char* env_seed0 = std::getenv("SINSCAL_OPEN_WORLD_SEED0");
  const std::uint64_t seed0 = env_seed0 ? std::strtoull(env_seed0, nullptr, 10) : 9000;
  std::vector<std::string> plans;
  std::stringstream parts(env_plans ? env_plans : "rot19.ini,seed8.ini");
  for (std::string p; std::getline(parts, p, ',');) plans.push_back(p);
  std::printf(
      "| plan | effect | seeds | catalog name first | a family and the effect's term first, not "
      "separable | unexplained | right library term | other library term | quiet | errors |\n"
      "|---|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& plan : plans)
    for (std::size_t k = 0; k < open_world_effects(0.0).size(); ++k) {
      const OpenWorldEffect e = open_world_effects(0.0)[k];
      if (env_filter && e.name.find(env_filter) == std::string::npos) continue;
      const OpenWorldScore s = run_effect(plan, k, seeds, seed0, scale);
      std::printf("| %s | %s | %d | %d | %d | %d | %d | %d | %d | %d |\n", plan.c_str(),
                  e.name.c_str(), s.seeds, s.wrong_first, s.alternative, s.unexplained,
                  s.right_term, s.wrong_term, s.quiet, s.errors);
      if (!s.first_miss.empty()) std::printf("    first miss: %s\n", s.first_miss.c_str());
      if (!s.first_terms.empty()) std::printf("    library: %s\n", s.first_terms.c_str());
      std::fflush(stdout);
    }
}

// CI: one seed of six cells of the matrix (seeds outside the measured ones). An anisoelastic
// gyro term on seed8 and a gyro g^2 term on rot19 are found by the library within 3 sigma (a
// sign or a column wrong turns them red); a cross-axis accelerometer product on seed8 (named
// time_delay before issue 33) names no catalog family and is reported unexplained, with its term
// within 3 sigma (the turns' velocity rows tell it from its alias on seed8's dwells, accel z
// f_x f_y: 11 of 30 before them, 30 of 30 with them). The seed8 g^2
// term (named gyro.bias_drift before the held-out test) and a gyro bias step half-way on rot19
// (named gyro.bias_drift on 22 of 30) name no family: the held-out dwells and the library's
// contest refuse the drift, and the library reports the term within 3 sigma (measured 10 of 10
// and 30 of 30, docs/accuracy.md; a sign of the held-out statistic flipped turns them red). A gyro
// rate nonlinearity omega_y^2 on rot19 acts only in the turns: the turns' attitude residual finds
// it (its regressor's sign or the gyro integration's frame wrong turns it red); the catalog's
// gyro.scale_asym, which predicts the held-out turns as well on a plan whose turns share one rate
// profile, may be named first, but then only as a set the plan cannot separate with the library
// term (the term in ambiguous_with, what separates them: turns at a second rate).
TEST_CASE("Open world: out-of-catalog effects are unexplained, or their library term",
          "[diagnosis][open_world][long]") {
  struct Case {
    std::string plan;
    std::size_t effect;
    bool term;     // the library must find the effect's term
    bool catalog;  // a catalog family may be named, with the effect's term as its alternative
  };
  for (const Case& k : {Case{"seed8.ini", 5, true, false}, Case{"rot19.ini", 1, true, false},
                        Case{"seed8.ini", 0, true, false}, Case{"rot19.ini", 6, true, true},
                        Case{"seed8.ini", 1, true, false}, Case{"rot19.ini", 4, true, false}}) {
    const OpenWorldEffect e = open_world_effects(0.0)[k.effect];
    const HiddenCase c = open_world_case(k.plan, "nav-fog.ini", k.effect, 77, kOpenWorldRate);
    const DiagnosisOutcome o = diagnose_hidden(c, {});
    std::string terms;
    if (o.result.unexplained.library)
      for (const auto& t : o.result.unexplained.library->terms) terms += t.text() + "; ";
    INFO(k.plan << " " << e.name << ": " << o.story << " | library: " << terms);
    if (!k.catalog) CHECK(o.result.findings.empty());
    for (const auto& f : o.result.findings) {
      CHECK(f.library_alternative.find(e.formula) != std::string::npos);
      CHECK(is_pair_with(f, e));  // reported as the pair the plan cannot separate
    }
    CHECK(o.result.unexplained.present);
    if (!k.term) continue;
    CHECK(score_terms(o.result, e) == 1);
    // How to add the term as one family-table entry, for each kind of term (the term reported:
    // the effect's, or a term the plan cannot tell from it with the effect's as its alias).
    REQUIRE(o.result.unexplained.library);
    REQUIRE_FALSE(o.result.unexplained.library->terms.empty());
    const std::string& how = o.result.unexplained.library->how_to_add;
    CHECK(how.find(o.result.unexplained.library->terms.front().formula) != std::string::npos);
    CHECK(how.find("family table") != std::string::npos);
  }
}

// What rot19 cannot separate, a plan separates whose turns run at two rates
// (config/plans/rot19-2rates.ini: every second turn at half the rate, so omega_y^2 and |omega_y|
// integrate to different ratios over its turns). A gyro rate nonlinearity omega_y^2 there is not
// given gyro.scale_asym's name, alone or as a pair with its term: the library's term explains the
// held-out turns better (the contest refuses the family), the residual is unexplained and the
// term reported within 3 sigma. A true gyro.scale_asym (20-40 ppm) on the same plan is still
// named gyro.scale_asym first, within 3 sigma, and not paired with a library term.
TEST_CASE("Open world: turns at two rates tell omega_y^2 from the gyro scale asymmetry",
          "[diagnosis][open_world][two_rates][long]") {
  const std::size_t effect = 6;  // gyro y += 3000 ppm/(rad/s) omega_y^2
  const OpenWorldEffect e = open_world_effects(0.0)[effect];
  const HiddenCase c =
      open_world_case("rot19-2rates.ini", "nav-fog.ini", effect, 77, kOpenWorldRate);
  const DiagnosisOutcome o = diagnose_hidden(c, {});
  std::string terms;
  if (o.result.unexplained.library)
    for (const auto& t : o.result.unexplained.library->terms) terms += t.text() + "; ";
  INFO("omega_y^2: " << o.story << " | library: " << terms);
  CHECK(o.result.findings.empty());
  CHECK(o.result.unexplained.present);
  CHECK(score_terms(o.result, e) == 1);

  const HiddenCase t = hidden_case("two_rates", "rot19-2rates.ini", "nav-fog.ini",
                                   {{"gyro", "scale_asym = 20 40 ppm"}}, 77, kOpenWorldRate);
  const DiagnosisOutcome a = diagnose_hidden(t, {"gyro.scale_asym"});
  INFO("gyro.scale_asym: " << a.story);
  REQUIRE_FALSE(a.result.findings.empty());
  CHECK(a.result.findings.front().family == "gyro.scale_asym");
  CHECK(a.result.findings.front().ambiguous_with.empty());
  CHECK(a.false_names.empty());
  CHECK(a.magnitudes_checked > 0);
  CHECK(a.worst_sigma < 3.0);
}

// The accelerometers' velocity over each turn (the library's turns rows: the specific force
// rotated to NED from the dwell's known attitude, from rest to rest). An accelerometer product
// f_y f_z is zero on every rot19 dwell (each has one body axis vertical), so only the turns can
// find it: at half the matrix's size (about 8 library sigmas) it is unexplained
// with its term within 3 sigma, and no catalog family is named first. A sign of the velocity
// rows' accelerometer columns flipped finds the term at minus its value (red); a clean session's
// turns hold their noise model (the velocity rows' covariance: the table's attitude times
// gravity over the turn, the velocity random walk).
TEST_CASE("Open world: the accelerometers' velocity over the turns finds a product",
          "[diagnosis][open_world][accel_turns][long]") {
  const std::size_t effect = 0;  // accel x += 100 ug/g^2 f_y f_z
  const OpenWorldEffect e = open_world_effects(0.0)[effect];
  const HiddenCase c =
      open_world_case("rot19.ini", "nav-fog.ini", effect, 77, kOpenWorldRate, kAccelTurnScale);
  const DiagnosisOutcome o = diagnose_hidden(c, {});
  std::string terms;
  if (o.result.unexplained.library)
    for (const auto& t : o.result.unexplained.library->terms) terms += t.text() + "; ";
  INFO("rot19 f_y f_z x" << kAccelTurnScale << ": " << o.story << " | library: " << terms);
  for (const auto& f : o.result.findings) CHECK(is_pair_with(f, e));
  CHECK(o.result.unexplained.present);
  CHECK(score_terms(o.result, e, kAccelTurnScale) == 1);

  for (const char* plan : {"rot19.ini", "seed8.ini"}) {
    const HiddenCase clean = hidden_case("clean", plan, "nav-fog.ini", {}, 77, kOpenWorldRate);
    const DiagnosisOutcome q = diagnose_hidden(clean, {});
    INFO(plan << " clean: " << q.story);
    CHECK(q.result.findings.empty());
    CHECK_FALSE(q.result.unexplained.present);
  }
}

// A turns' finding is named only when the held-out turns gain by the chi-square quantile of its
// dof (refusal_of). With any gain accepted, a MEMS gyro x scale that grows with f_z (3000 ppm/g)
// on seed8 was named accel.scale_asym or accel.lever_arm first on 15 of 30 seeds (docs/accuracy.md,
// stop 43); with the quantile on 2 of 30. Twelve seeds outside the measured ones may hold at most
// allowed_misses(12) wrong names at the acceptance's 1 in 30: 2; at the old rate (one half) a run
// passes 1.9 % of the time.
TEST_CASE("Open world: a turns' family is named only on a significant held-out gain",
          "[diagnosis][open_world][long]") {
  const auto effects = open_world_effects(0.0);
  const auto it = std::find_if(effects.begin(), effects.end(), [](const OpenWorldEffect& e) {
    return e.name == "gyro x scale += 100 ppm/g f_z";
  });
  REQUIRE(it != effects.end());
  const auto effect = static_cast<std::size_t>(it - effects.begin());
  const int seeds = 12;
  const OpenWorldScore s = run_effect("seed8.ini", effect, seeds, 9100, 30.0, "mems.ini");
  INFO("first miss: " << s.first_miss);
  CHECK(s.errors == 0);
  CHECK(s.wrong_first <= allowed_misses(seeds, 29.0 / 30.0));
}

// A MEMS gyro nonlinearity of its output, k omega_x|omega_x| (k = 1571 ppm/(deg/s), the matrix's
// size times 30), on rot19. The output carries the gyro's bias b (0.1-0.5 deg/s), so the effect is
// k omega|omega| + 2 k b |omega| + k b^2: on rot19's one rate profile the scale factor absorbs the
// first share and the second is gyro.scale_asym's signature (named on 12 of 30 seeds, within 1.3
// sigma of 2 k b on every one). The library's rate terms are functions of the output (the
// linearization model's, bias included): the effect's term is then aliased with the family, and
// every library term the held-out contest finds as good joins the set the plan cannot separate.
// A family paired with library terms never leaves the effect's out (with the rate terms of the
// true rate: the set {gyro.scale_asym, omega_x^2} on 12 of 30 seeds, the term found on none; with
// only the best term in the set: omega_x^3 or omega_x^2 stated on 9 of 11 sets); at most
// allowed_misses(12) = 2 catalog names first at the acceptance's 1 in 30 (measured 1 of 30: a
// gyro.scale_asym alone); the effect's term found on some seed (17 of 30 measured; the true
// rate's column, which the scale factor absorbs whole, found it on none).
TEST_CASE("Open world: a MEMS gyro's output nonlinearity is not named gyro.scale_asym alone",
          "[diagnosis][open_world][mems][long]") {
  const std::size_t effect = 2;  // gyro x += 3000 ppm/(rad/s) omega_x |omega_x|
  REQUIRE(open_world_effects(0.0)[effect].formula == "omega_x |omega_x|");
  const int seeds = 12;
  const OpenWorldScore s = run_effect("rot19.ini", effect, seeds, 9100, 30.0, "mems.ini");
  INFO("first miss: " << s.first_miss << " | sets " << s.alternative << ", right term "
                      << s.right_term << ", unexplained " << s.unexplained);
  CHECK(s.errors == 0);
  CHECK(s.paired_without == 0);
  CHECK(s.wrong_first <= allowed_misses(seeds, 29.0 / 30.0));
  CHECK(s.right_term >= 1);
}

// A time family is named only when the residual's time structure is not the orientation's
// (TableRounds::time_or_orientation, filter/diagnosis/time_structure.hpp). seed8 visits each
// orientation once, in an order that makes accel x's drift, with the y misalignment projected
// out, the product f_y f_z on its four roll dwells (+1, -1, +1, -1 in time): a MEMS f_y f_z x3
// was named accel.bias_drift first (with a 748 s periodic term as its alternative) on 5 of 30
// seeds; with the library's orientation terms as the drift's rivals on 1 of 30
// (docs/methods/diagnosis.md "Time or orientation"). Twelve of the measured seeds, at most
// allowed_misses(12) = 2 wrong at the acceptance's 1 in 30: 1 with the rival (9001), 3 without it
// (9001, 9004, 9008: red, checked).
TEST_CASE("Open world: a drift is not named where an orientation term explains it as well",
          "[diagnosis][open_world][time_structure][long]") {
  const std::size_t effect = 0;  // accel x += 100 ug/g^2 f_y f_z
  const int seeds = 12;
  const OpenWorldScore s = run_effect("seed8.ini", effect, seeds, 9000, 3.0, "mems.ini");
  INFO("first miss: " << s.first_miss);
  CHECK(s.errors == 0);
  CHECK(s.wrong_first <= allowed_misses(seeds, 29.0 / 30.0));
}
