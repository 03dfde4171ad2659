// sinscal design --optimize: the search for the shortest plan on a table whose predicted sigmas
// meet every target (filter/design/search.hpp), confirmed by a covariance pass at the design
// rate, compared with reference plans, written as a plan file that simulate and calibrate run.
#include <unistd.h>  // isatty: the progress line on a terminal only

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <limits>
#include <mutex>
#include <optional>
#include <thread>

#include "apps/design.hpp"
#include "filter/design/anneal.hpp"
#include "filter/design/bound.hpp"
#include "filter/design/hand_plans.hpp"
#include "filter/design/search.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

namespace {

struct Compared {
  std::string name, file;
  double duration = 0.0;
  Excess excess;
  bool within_table = true;
};

Compared compare_plan(const Plan& plan, const std::string& file, const CalibratorOptions& ko,
                      const TableSpec& table, const std::map<std::string, double>& targets,
                      double rate_hz) {
  DesignOptions d;
  d.rate_hz = rate_hz;
  const PlanPrediction p = predict_plan(plan, ko, targets, d);
  Compared c{plan.name, file, p.duration, excess(p.run.estimates, targets), true};
  c.within_table =
      check_against_table(build_motion(plan, plan.site), table, ko.static_margin).empty();
  return c;
}

std::string comparison_table(const std::vector<Compared>& rows) {
  std::string out = "\nComparison (predicted at the design rate, the same targets):\n";
  char line[256];
  std::snprintf(line, sizeof line, "%-14s %10s %6s %8s  %-24s %s\n", "plan", "duration", "meets",
                "J", "worst family", "sigma/target");
  out += line;
  for (const auto& r : rows) {
    std::snprintf(line, sizeof line, "%-14s %8.1f s %6s %8.3f  %-24s %.2f%s\n", r.name.c_str(),
                  r.duration, r.excess.J <= 0.0 ? "yes" : "no", r.excess.J,
                  r.excess.worst_family.c_str(), r.excess.worst_ratio,
                  r.within_table ? "" : "  (beyond the table's limits)");
    out += line;
  }
  return out;
}

// The relaxation's bound at the found plan's duration, the gap to it, and the table time below
// which no plan of the library's segments meets every target.
struct BoundReport {
  DesignBound at_plan;
  double time_for_targets = 0.0;
  double cpu_s = 0.0;
  int segments = 0, orientations = 0;
};

// None when no targeted family is a state of the filter (nothing to bound).
std::optional<BoundReport> bound_report(const CalibratorOptions& ko, const TableSpec& table,
                                        const Site& site, const SearchOptions& so,
                                        double duration) {
  const std::clock_t c0 = std::clock();
  const InformationLibrary lib = information_library(ko, table, site, so.targets, so.rate_hz);
  if (std::none_of(lib.targeted.begin(), lib.targeted.end(), [](bool t) { return t; }))
    return std::nullopt;
  BoundReport b;
  b.at_plan = relaxed_bound(lib, duration);
  b.time_for_targets = bound_time_for_targets(lib);
  b.cpu_s = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  b.segments = static_cast<int>(lib.segments.size());
  b.orientations = lib.orientations;
  return b;
}

void print_bound(const BoundReport& b, const Excess& found) {
  std::printf(
      "\nBound (convex relaxation over %d segments at %d orientations, %.1f s CPU): no plan of "
      "%.1f s does better than worst sigma/target %.2f (relaxed design %.2f, %s); the found plan's "
      "%.2f (%s) is %.0f %% above it. No plan meets every target in less than %.0f s.\n",
      b.segments, b.orientations, b.cpu_s, b.at_plan.budget_s, b.at_plan.lower, b.at_plan.upper,
      b.at_plan.family.c_str(), found.worst_ratio, found.worst_family.c_str(),
      100.0 * (found.worst_ratio / b.at_plan.lower - 1.0), b.time_for_targets);
}

nlohmann::ordered_json bound_json(const BoundReport& b, const Excess& found) {
  return {{"budget_s", b.at_plan.budget_s},
          {"lower_worst_ratio", b.at_plan.lower},
          {"relaxed_worst_ratio", b.at_plan.upper},
          {"relaxed_worst_family", b.at_plan.family},
          {"found_worst_ratio", found.worst_ratio},
          {"gap", found.worst_ratio / b.at_plan.lower - 1.0},
          {"time_for_targets_lower_s", b.time_for_targets},
          {"segments", b.segments},
          {"orientations", b.orientations},
          {"iterations", b.at_plan.iterations},
          {"cpu_s", b.cpu_s}};
}

nlohmann::ordered_json search_json(const SearchResult& r, const SearchOptions& so, double cpu,
                                   const std::vector<Compared>& rows) {
  nlohmann::ordered_json path = nlohmann::ordered_json::array();
  for (const auto& s : r.path)
    path.push_back({{"duration_s", s.duration},
                    {"J", s.J},
                    {"worst_ratio", s.worst_ratio},
                    {"worst_family", s.worst_family}});
  nlohmann::ordered_json seeds = nlohmann::ordered_json::array();
  for (const auto& [name, ratio] : r.candidates)
    seeds.push_back({{"plan", name}, {"worst_ratio", ratio}});
  nlohmann::ordered_json moves = nlohmann::ordered_json::array();
  for (const auto& [what, ratio] : r.structure)
    moves.push_back({{"move", what}, {"worst_ratio", ratio}});
  nlohmann::ordered_json cmp = nlohmann::ordered_json::array();
  for (const auto& c : rows)
    cmp.push_back({{"plan", c.name},
                   {"file", c.file},
                   {"duration_s", c.duration},
                   {"meets_targets", c.excess.J <= 0.0},
                   {"J", c.excess.J},
                   {"worst_family", c.excess.worst_family},
                   {"worst_ratio", c.excess.worst_ratio},
                   {"within_table", c.within_table}});
  return {{"search",
           {{"beam", so.beam},
            {"search_rate_hz", so.rate_hz},
            {"budget_s", so.budget_s},
            {"evaluations", r.evaluations},
            {"cpu_s", cpu},
            {"duration_before_refinement_s", r.duration_before_refinement},
            {"meets_targets", r.meets},
            {"origin", r.origin},
            {"seeds", seeds},
            {"structure_evaluations", r.structure_evaluations},
            {"structure_limit", r.structure_limit},
            {"structure_moves", moves},
            {"path", path}}},
          {"comparison", cmp}};
}

// The structure moves' account: the moves accepted with the worst ratio after each.
std::string structure_text(const SearchResult& r, int requested) {
  std::string out =
      "Structure moves (" + std::to_string(r.structure_evaluations) + " covariance passes" +
      (r.structure_limit < requested ? ", at most " + std::to_string(r.structure_limit) +
                                           " by the cost of one pass at this budget"
                                     : "") +
      "): " + std::to_string(r.structure.size()) + " accepted";
  if (r.origin == "structure moves")
    out += ", worst sigma/target " + fmt("%.4f", r.excess.worst_ratio) + " at the search rate";
  out += r.origin == "structure moves" ? ", their plan is the best within the budget.\n"
                                       : ", none better than the plan before them.\n";
  for (const auto& [what, ratio] : r.structure)
    out += "  " + what + ": worst sigma/target " + fmt("%.3f", ratio) + "\n";
  return out + "\n";
}

// Whether `path` is the reference plan or a --compare plan (not a second seed).
bool same_file_given(const std::string& path, const DesignCliOptions& o) {
  std::error_code ec;
  if (std::filesystem::equivalent(path, o.plan, ec)) return true;
  return std::any_of(o.compare.begin(), o.compare.end(), [&](const std::string& f) {
    std::error_code e;
    return std::filesystem::equivalent(path, f, e);
  });
}

// A plan needs about this many turns to observe the full model (docs/methods/design.md); a table
// too slow to make them within the search's longest plan is refused before the search.
constexpr int kTurnsNeeded = 9;
// A target this far below what noise averaging allows over the longest plan (the reference
// plan's sigma scaled by sqrt(T_ref / T_max)) is not reachable: refused before the search.
constexpr double kUnreachableFactor = 100.0;

// The table's time for a 90 deg turn at its rate and acceleration limits.
double quarter_turn_s(const TableSpec& table) {
  const double angle = units::pi / 2.0;
  const double a = table.max_acceleration, w = table.max_rate;
  if (!(a > 0.0 && w > 0.0)) return std::numeric_limits<double>::infinity();
  return angle * a > w * w ? angle / w + w / a : 2.0 * std::sqrt(angle / a);
}

// Refuses, before the search, a table too slow for any plan within the search's limit and
// targets no plan within it can reach (from the reference plan's predicted sigmas).
void refuse_unsearchable(const SearchOptions& so, const TableSpec& table, const Plan& reference,
                         const PlanPrediction& ref) {
  const double turn = quarter_turn_s(table);
  if (!(kTurnsNeeded * turn <= so.max_duration))
    throw UsageError(table.name + ": the table turns 90 deg in " + fmt("%.0f", turn) + " s: the " +
                     std::to_string(kTurnsNeeded) +
                     " turns a calibration needs take longer than "
                     "the search's longest plan (" +
                     fmt("%.0f", so.max_duration) + " s)");
  const auto& cat = coefficient_catalog();
  const double scale = std::sqrt(std::max(ref.duration, 1.0) / so.max_duration);
  for (const auto& [family, target] : so.targets) {
    double best = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < cat.size(); ++i)
      if (cat[i].family == family &&
          ref.run.estimates[i].status == CoefficientEstimate::Status::Estimated)
        best = std::min(best, ref.run.estimates[i].sigma * scale / kUnreachableFactor);
    if (!(std::isfinite(best) && target < best)) continue;
    const CoefficientFamily& info = coefficient_family_info(family);
    const double u = info.si_per_unit();
    throw UsageError("target of " + family + " " + fmt("%.3g", target / u) + " " + info.unit() +
                     " is below " + fmt("%.3g", best / u) + " " + info.unit() + ", " +
                     fmt("%g", kUnreachableFactor) + " times under what " + reference.name +
                     " would reach if noise averaging alone went on to the search's longest "
                     "plan (" +
                     fmt("%.0f", so.max_duration) + " s): no plan can meet it");
  }
}

// On a terminal, a line on standard error every second while the search runs: elapsed time and
// the bound. The search itself (filter/design/search.hpp) has no progress callback yet.
class SearchProgress {
 public:
  explicit SearchProgress(std::string bound) : bound_(std::move(bound)) {
    if (!::isatty(STDERR_FILENO)) return;
    thread_ = std::thread([this] { tick(); });
  }
  ~SearchProgress() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    if (thread_.joinable()) {
      thread_.join();
      std::fprintf(stderr, "\r\033[K");
    }
  }
  SearchProgress(const SearchProgress&) = delete;
  SearchProgress& operator=(const SearchProgress&) = delete;

 private:
  void tick() {
    const auto t0 = std::chrono::steady_clock::now();
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, std::chrono::seconds(1), [this] { return done_; })) {
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::fprintf(stderr, "\rsearching: %.0f s elapsed (%s)\033[K", s, bound_.c_str());
      std::fflush(stderr);
    }
  }
  std::string bound_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;
};

// --anneal: the annealing from the search's plan (filter/design/anneal.hpp) and its CPU time.
struct AnnealReport {
  AnnealResult result;
  int iterations = 0;
  double cpu_s = 0.0;
};

std::optional<AnnealReport> annealed_result(SearchResult& r, const DesignCliOptions& o,
                                            const CalibratorOptions& ko, const TableSpec& table,
                                            const Site& site, const SearchOptions& so) {
  if (o.anneal <= 0 || !(so.budget_s > 0.0)) return std::nullopt;
  AnnealOptions a;
  a.iterations = o.anneal;
  const std::clock_t c0 = std::clock();
  const SearchProgress progress("annealing, " + std::to_string(o.anneal) + " iterations");
  const auto result = anneal_search_result(r, ko, table, site, so, a);
  if (!result) return std::nullopt;
  return AnnealReport{*result, o.anneal, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC};
}

std::string anneal_text(const AnnealReport& a, const SearchResult& r) {
  return "Simulated annealing (" + std::to_string(a.iterations) + " iterations, " +
         std::to_string(a.result.evaluations) + " covariance passes, " + fmt("%.1f", a.cpu_s) +
         " s CPU): worst sigma/target " + fmt("%.4f", a.result.start.worst_ratio) + " -> " +
         fmt("%.4f", a.result.excess.worst_ratio) + " (" + a.result.excess.worst_family + "), " +
         std::to_string(a.result.accepted) + " moves taken (" +
         std::to_string(a.result.accepted_worse) + " worse)" +
         (r.origin == "annealing" ? "; its plan is the best within the budget.\n\n"
                                  : "; none better than the plan before it.\n\n");
}

nlohmann::ordered_json anneal_json(const AnnealReport& a) {
  return {{"iterations", a.iterations},
          {"evaluations", a.result.evaluations},
          {"cpu_s", a.cpu_s},
          {"start_worst_ratio", a.result.start.worst_ratio},
          {"worst_ratio", a.result.excess.worst_ratio},
          {"worst_family", a.result.excess.worst_family},
          {"accepted", a.result.accepted},
          {"accepted_worse", a.result.accepted_worse}};
}

}  // namespace

int design_optimize(const DesignCliOptions& o) {
  const Plan reference = Plan::load(o.plan);
  if (!reference.has_site)
    throw UsageError(o.plan + ": the reference plan has no [site]: the search needs the site");
  const SensorProfile profile = SensorProfile::load(o.sensor);
  const TableSpec table = TableSpec::load(o.table);
  const CalibratorOptions ko = design_options(o, profile, &table);
  SearchOptions so;
  so.budget_s = o.budget_s;
  so.beam = o.beam;
  so.structure_evaluations = o.structure_moves;
  so.rate_hz = o.search_rate_hz;
  // With --require only, the search targets the required families alone.
  if (o.require.empty() || !o.targets.empty()) so.targets = design_targets(o, profile);
  if (!o.require.empty()) {
    DesignOptions d;
    d.rate_hz = so.rate_hz;
    try {
      so.targets =
          required_targets(so.targets, o.require, predict_plan(reference, ko, {}, d).run.estimates);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--require: ") + e.what());
    }
  }
  if (so.targets.empty() && !o.targets.empty())
    throw UsageError("--targets " + o.targets + ": no targets in it");
  if (so.targets.empty())
    throw UsageError(o.sensor + ": no [targets] in the profile: give --targets or --require");
  {
    DesignOptions d;
    d.rate_hz = so.rate_hz;
    refuse_unsearchable(so, table, reference, predict_plan(reference, ko, so.targets, d));
  }
  std::filesystem::create_directories(o.out);
  const std::string plan_path = o.out + "/optimized.ini";
  std::vector<std::pair<std::string, std::string>> inputs = {
      {"plan", o.plan}, {"sensor", o.sensor}, {"table", o.table}};
  for (const auto& f : o.compare) inputs.emplace_back("--compare plan", f);
  if (o.targets.find('=') == std::string::npos) inputs.emplace_back("targets", o.targets);
  refuse_overwrite(inputs, {{"optimized.ini", plan_path},
                            {"best_unmet.ini", o.out + "/best_unmet.ini"},
                            {"design.json", o.out + "/design.json"},
                            {"sigma.jsonl", o.out + "/sigma.jsonl"}});
  // Every plan given is a seed: the search is at least as good as each, scaled to the budget.
  so.seeds.push_back(reference);
  for (const auto& f : o.compare) so.seeds.push_back(Plan::load(f));
  // And the searched plans bundled beside the reference plan (config/plans/searched-*.ini).
  const std::filesystem::path plans_dir = std::filesystem::path(o.plan).parent_path();
  for (Plan& p : searched_plans_in(plans_dir.empty() ? "." : plans_dir.string()))
    if (!same_file_given(p.path, o)) so.seeds.push_back(std::move(p));
  const std::string work_bound =
      "plans up to " + fmt("%.0f", so.max_duration) + " s" +
      (so.budget_s > 0.0 ? ", budget " + fmt("%.0f", so.budget_s) + " s" : "") + ", beam " +
      std::to_string(so.beam) + ", " + std::to_string(so.targets.size()) + " targeted families";
  std::printf("Searching the shortest plan that meets the targets: %s\n", work_bound.c_str());
  std::fflush(stdout);
  const std::clock_t c0 = std::clock();
  SearchResult r = [&] {
    const SearchProgress progress(work_bound);
    return search_plan(ko, table, reference.site, SearchSpace{}, so);
  }();
  const std::string moves_text =
      structure_text(r, so.structure_evaluations);  // before the annealing changes the origin
  const std::optional<AnnealReport> annealed = annealed_result(r, o, ko, table, reference.site, so);
  const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  // A plan that misses a target is not written as the optimized plan.
  const std::string written = r.meets ? plan_path : o.out + "/best_unmet.ini";
  write_atomically(written, [&](std::ostream& s) { s << r.text; });
  const Plan best = Plan::load(written);
  DesignOptions d;
  d.rate_hz = o.rate_hz;
  const PlanPrediction p = predict_plan(best, ko, so.targets, d);
  std::printf(
      "Searched rotation plans on %s: %d covariance passes, %.1f s CPU; %.1f s before "
      "refinement, %.1f s after.\n\n",
      table.name.c_str(), r.evaluations, cpu, r.duration_before_refinement, p.duration);
  if (!r.structure.empty() || r.structure_evaluations > 0) std::printf("%s", moves_text.c_str());
  if (annealed) std::printf("%s", anneal_text(*annealed, r).c_str());
  if (r.origin != "beam" && r.origin != "structure moves" && r.origin != "annealing")
    std::printf(
        "The best plan within the budget is %s, a given plan as it is or with its dwells "
        "scaled: better than the beam's on the worst sigma/target.\n\n",
        r.origin.c_str());
  const DesignInputs in{written,    o.sensor,          o.table,   "optimized", profile.name,
                        table.name, ko.attitude_sigma, o.rate_hz, cpu};
  std::cout << design_tables(p, in);
  std::vector<Compared> rows = {compare_plan(best, written, ko, table, so.targets, o.rate_hz),
                                compare_plan(reference, o.plan, ko, table, so.targets, o.rate_hz)};
  for (const auto& f : o.compare)
    rows.push_back(compare_plan(Plan::load(f), f, ko, table, so.targets, o.rate_hz));
  rows.front().name = "optimized";
  std::cout << comparison_table(rows);
  const std::optional<BoundReport> bound = bound_report(ko, table, reference.site, so, p.duration);
  if (bound) print_bound(*bound, rows.front().excess);
  if (!r.meets)
    std::printf(
        "\nNo plan found%s meets every target: the best leaves %s at %.2f times its "
        "target.\n",
        so.budget_s > 0.0 ? " within the budget" : " within the search's limit",
        r.excess.worst_family.c_str(), r.excess.worst_ratio);
  nlohmann::ordered_json extra = search_json(r, so, cpu, rows);
  if (annealed) extra["search"]["annealing"] = anneal_json(*annealed);
  if (bound) extra["bound"] = bound_json(*bound, rows.front().excess);
  if (!o.require.empty()) {
    std::cout << required_table(o.require, p, so.targets);
    extra["search"]["required"] = required_json(o.require, p, so.targets);
  }
  write_design_files(o.out, p, in, extra);
  if (!r.meets) {
    std::cout << "Wrote " << written << " (the best plan found; it does not meet the targets), "
              << "not " << plan_path << "\n";
    return kTargetsNotMet;
  }
  std::cout << "Wrote " << plan_path << " (runs unchanged through simulate and calibrate)\n";
  return 0;
}

}  // namespace sinscal::cli
