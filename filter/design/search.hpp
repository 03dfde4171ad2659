// Plan design, second part: the search for the shortest rotation plan whose predicted sigmas meet
// every target on a given table (or the plan of smallest excess within a time budget): a beam
// search over turns by incremental covariance passes, then a refinement.
// docs/methods/design.md "Search for the shortest plan".
#pragma once

#include <map>
#include <string>
#include <vector>

#include "filter/design/prediction.hpp"
#include "rig/table_spec.hpp"

namespace sinscal {

/// One turn of a searched plan.
struct TurnChoice {
  int axis = 0;        // 0..5: +x -x +y -y +z -z (body axes)
  double angle = 0.0;  // rad, positive
  double pause = 0.0;  // s, the dwell after it
};

/// A searched plan before it is written as a plan file.
struct PlanGenome {
  int start = 0;             // 0..5: body +x, -x, +y, -y, +z, -z up at the start
  double start_dwell = 0.0;  // s
  std::vector<TurnChoice> turns;
};

struct SearchSpace {
  std::vector<int> starts = {0, 1, 2, 3, 4, 5};
  std::vector<double> start_dwells = {10.0, 30.0};  // s
  std::vector<double> angles;                       // rad (default: 90 and 180 deg)
  std::vector<double> pauses;  // s (default: the shortest dwell the table allows, and 10 s)
};

struct SearchOptions {
  std::map<std::string, double> targets;  // by family, SI
  double budget_s = 0.0;  // > 0: the best plan no longer than this; 0: the shortest that meets
  double max_duration = 1800.0;  // s: the search gives up beyond (no budget)
  int beam = 4;
  double rate_hz = 20.0;  // of the ideal IMU in the search (the result is confirmed at 50 Hz)
  std::string name = "optimized";
  /// enumerate_plans: rank by the worst sigma / target instead of J.
  bool minimax = false;
  /// With a budget: hand plans the result must be at least as good as on the worst sigma /
  /// target. Each, as it is when it fits the budget and with its dwells scaled to the budget
  /// (dwell_scaled), is a candidate beside the beam's plan, and the best is improved by moving
  /// time between its dwells (at most `improvement_passes` evaluations, 0: none).
  std::vector<Plan> seeds;
  int improvement_passes = 60;
  /// With a budget: covariance passes the structure moves may spend after the seeds
  /// (filter/design/structure_moves.hpp), from the best plan so far, the beam's and each seed's
  /// turns at the table's limits; 0: none. At most structure_pass_limit's at the budget.
  int structure_evaluations = 0;
  /// search_budgets: each budget's result is a seed of the next budget (carried up).
  bool carry_up = true;
};

/// The shortest dwell after a turn the search uses on `table` (its settling, one update, the
/// margin), on the search's 0.1 s grid.
double shortest_pause(const TableSpec& table);

/// The plan file of a genome on `table` at `site` (docs/formats.md, type = rotations): turns at
/// the table's acceleration, durations rounded up to 0.1 s so that every segment starts on a
/// sample of the search's rates.
std::string plan_text(const PlanGenome& genome, const TableSpec& table, const Site& site,
                      const std::string& name);
Plan plan_of(const PlanGenome& genome, const TableSpec& table, const Site& site,
             const std::string& name);

/// The objective J of the estimates (catalog order, SI) against the targets; also the worst
/// ratio sigma / target over every targeted coefficient and the family it belongs to.
struct Excess {
  double J = 0.0;
  double worst_ratio = 0.0;
  std::string worst_family;
  /// A smooth worst ratio: the 16-norm of the families' worst ratios (the structure moves rank
  /// by it, so that one of two balanced families may fall before the other).
  double soft_worst = 0.0;
};
Excess excess(const std::vector<CoefficientEstimate>& estimates,
              const std::map<std::string, double>& targets);

struct SearchStep {
  double duration = 0.0;  // s, of the plan so far
  double J = 0.0;
  double worst_ratio = 0.0;
  std::string worst_family;
};

struct SearchResult {
  PlanGenome best;
  Plan plan;                    // the result as a plan: `best`'s (plan_of), or a seed's
  std::string text;             // its plan file
  std::string origin = "beam";  // "beam", or the seed it comes from
  std::vector<std::pair<std::string, double>> candidates;  // seeds tried: name, worst ratio
  Excess excess;                                           // of the best, from the search's pass
  bool meets = false;                                      // every target met
  int evaluations = 0;           // covariance passes, incremental and full
  std::vector<SearchStep> path;  // the best plan's growth, turn by turn (before refinement)
  double duration_before_refinement = 0.0;
  /// The structure moves accepted (what, worst ratio after it) and the passes they spent.
  std::vector<std::pair<std::string, double>> structure;
  int structure_evaluations = 0;
  int structure_limit = 0;  // the passes the moves were allowed (structure_pass_limit)
};

/// `--require`: a family the plan must determine gets the target kRequiredFraction of its prior
/// sigma (the rule of "observed" is 1/sqrt(2) of it; half leaves a margin), or its own target
/// when that is smaller. Whether the found plan observes it (also outside every unobservable
/// combination) is confirmed by the final pass.
constexpr double kRequiredFraction = 0.5;
/// `targets` with the `required` families added, their priors from `estimates` (any pass's: the
/// prior does not depend on the plan). Throws std::invalid_argument naming a family that is not
/// an estimated family of the options.
std::map<std::string, double> required_targets(std::map<std::string, double> targets,
                                               const std::vector<std::string>& required,
                                               const std::vector<CoefficientEstimate>& estimates);

/// The search. Throws std::invalid_argument for an empty space or no targets.
SearchResult search_plan(const CalibratorOptions& options, const TableSpec& table, const Site& site,
                         const SearchSpace& space, const SearchOptions& search);

/// The search at each of `budgets` (s), shortest first, in that order: with
/// `search.carry_up`, the plan found at each budget is a seed of the next one (as it is and with
/// its dwells scaled to the budget, named searched-<budget>s; a seed's plan as it is is a
/// candidate), so the worst sigma / target never grows with the budget. One result per budget,
/// in ascending order.
std::vector<SearchResult> search_budgets(const CalibratorOptions& options, const TableSpec& table,
                                         const Site& site, const SearchSpace& space,
                                         SearchOptions search, std::vector<double> budgets);

/// The excess of one genome by a full covariance pass (the search's rate).
Excess evaluate_genome(const PlanGenome& genome, const CalibratorOptions& options,
                       const TableSpec& table, const Site& site, const SearchOptions& search);

/// Exhaustive search over every sequence of `turns` turns of the space (one start, one start
/// dwell, each turn from the angles and pauses): the smallest J, for the optimality gap of the
/// beam on cases small enough to enumerate. Also returns how many sequences were scored.
std::pair<PlanGenome, Excess> enumerate_plans(const CalibratorOptions& options,
                                              const TableSpec& table, const Site& site,
                                              const SearchSpace& space, const SearchOptions& search,
                                              int turns, int* scored = nullptr);
/// The beam search restricted to exactly `turns` turns from the same space (no refinement): the
/// plan it finds for the gap.
std::pair<PlanGenome, Excess> beam_plans(const CalibratorOptions& options, const TableSpec& table,
                                         const Site& site, const SearchSpace& space,
                                         const SearchOptions& search, int turns);

}  // namespace sinscal
