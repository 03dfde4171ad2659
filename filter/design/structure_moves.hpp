// Plan design, third part: structure moves of a searched rotation plan within a time budget
// (split a turn into two half turns with a dwell between, insert a turn, remove one, change a
// turn's axis, angle or order), each followed by the dwells refitted to the budget, accepted when
// the worst sigma / target falls. docs/methods/design.md "Structure moves".
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "filter/design/search.hpp"

namespace sinscal {

/// One change of a genome's structure.
struct StructureMove {
  enum class Kind { SplitAll, Split, Insert, Remove, Axis, Angle, Swap };
  Kind kind = Kind::Split;
  std::size_t index = 0;  // the turn (Insert: the position it takes)
  int axis = 0;           // Insert, Axis: 0..5 (+x -x +y -y +z -z)
  double angle = 0.0;     // rad: Insert, Angle
  std::string describe() const;
};

/// A rotation plan as a genome: its start (a body axis up or down, ned-frd), its turns about
/// body axes with their angles, and its dwells (floored to the search's 0.1 s grid; the turns'
/// durations become the table's limits when written). None for a plan the search does not write
/// (orientations, turns about table axes, rate segments, another start).
std::optional<PlanGenome> genome_of(const Plan& plan, const TableSpec& table);

/// `g` with its dwells (the start dwell and the pauses) set from `dwells` so that the plan lasts
/// `budget` s, on the 0.1 s grid (to within one grid step): each dwell keeps at least
/// `min_dwell`, and the time above it is shared in proportion to `dwells`' time above it. None
/// when the turns and the shortest dwells alone take longer.
std::optional<PlanGenome> fitted(const PlanGenome& g, const std::vector<double>& dwells,
                                 double budget, double min_dwell, const TableSpec& table,
                                 const Site& site);
/// The same with `g`'s own dwells.
std::optional<PlanGenome> fitted(const PlanGenome& g, double budget, double min_dwell,
                                 const TableSpec& table, const Site& site);

/// `g` changed by `m` (before refitting): a split turn's halves are separated by the turn's own
/// pause; an inserted turn is followed by the shortest dwell. Throws std::invalid_argument for a
/// move that does not apply (index out of range, removing the last turn).
PlanGenome applied(const PlanGenome& g, const StructureMove& m, double min_dwell);

/// Every move of `g`: first the global ones (every turn above 60 deg split in two, a 45 deg turn
/// about the vertical first), then the local ones in an order shuffled by `seed` (reproducible).
std::vector<StructureMove> structure_moves(const PlanGenome& g, unsigned seed);

struct StructureStep {
  std::string move;
  double worst_ratio = 0.0;
  int evaluations = 0;  // spent when it was accepted
};

struct StructureResult {
  PlanGenome genome;
  Excess excess;
  int evaluations = 0;
  std::vector<StructureStep> path;  // the moves accepted, in order
};

/// The structure moves' passes at a budget: `requested` at most, and no more than a fixed amount
/// of work, kStructureWork, shared by passes whose cost is taken as that of one prediction: the
/// samples of a plan of `budget` s at `rate_hz` times the square of the filter's `states`
/// (propagating and updating the covariance). A deterministic rule (the same passes on every
/// machine, so a result is reproducible), set so that design --optimize stays within 60 s of CPU
/// at any budget up to 1000 s with nav-fog-extended (docs/methods/design.md "Structure moves").
/// At least 1 when `requested` is positive.
constexpr double kStructureWork = 3.2e10;  // samples x states^2, over all passes
int structure_pass_limit(int requested, double budget, double rate_hz, int states);

/// Local search over the structure within `budget` s from the best of `starts` (each fitted to
/// the budget): moves tried in structure_moves' order, the first that lowers the worst sigma /
/// target taken, then time moved between the dwells; ends at a plan no move improves or after
/// `max_evaluations` scores. `score` is the covariance pass of a genome. None when no start fits
/// the budget.
std::optional<StructureResult> structure_search(
    const std::vector<PlanGenome>& starts, double budget, const TableSpec& table, const Site& site,
    int max_evaluations, const std::function<Excess(const PlanGenome&)>& score);

}  // namespace sinscal
