// Plan design, fourth part: simulated annealing over a searched rotation plan's structure within a
// time budget (the structure moves' move set, filter/design/structure_moves.hpp, and time moved
// between the dwells), on the same smooth worst sigma / target, with a seeded random number
// generator and geometric cooling; the best plan seen is kept. Also the "north carousel" start.
// docs/methods/design.md "Simulated annealing".
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "filter/design/search.hpp"

namespace sinscal {

struct AnnealOptions {
  int iterations = 0;  // proposals (each scored by one covariance pass when it fits the budget)
  unsigned seed = 36;  // of the random number generator: equal seeds give equal results
  /// Temperatures on the natural log of the smooth worst ratio (Excess::soft_worst), the first
  /// iteration's and the last's, geometric in between: at 0.01 a proposal 1 % worse is taken
  /// with probability 1/e.
  double t_start = 0.01;
  double t_end = 1e-4;
  /// The share of proposals that move time between the dwells instead of changing the structure:
  /// one dwell gains `dwell_step` of itself or gives `dwell_step` of its time above the shortest
  /// dwell, the others give or gain in proportion (structure_moves.hpp `fitted`).
  double dwell_share = 0.3;
  double dwell_step = 0.25;
};

struct AnnealResult {
  PlanGenome genome;  // the best plan seen (the smallest worst sigma / target), the start's fit
  Excess excess;      // included
  Excess start;       // of the start fitted to the budget
  int evaluations = 0;
  int accepted = 0;                                  // proposals taken
  int accepted_worse = 0;                            // of which with a larger smooth worst ratio
  std::vector<std::pair<int, double>> improvements;  // iteration, best worst ratio after it
};

/// The temperature at iteration `k` of `o.iterations` (geometric from t_start to t_end).
double anneal_temperature(const AnnealOptions& o, int k);

/// The Metropolis rule on the log of the smooth worst ratio: a candidate no worse than the
/// current state is taken; a worse one when `u` (uniform in [0, 1)) is below
/// exp(-(ln candidate - ln current) / temperature).
bool anneal_accepts(double current_soft, double candidate_soft, double temperature, double u);

/// Simulated annealing from `start` fitted to `budget` s (with its own dwells): each iteration
/// proposes one structure move (drawn uniformly from structure_moves' list for the current plan)
/// or one time move between the dwells, refitted to the budget and scored by `score`, taken by
/// anneal_accepts. None when the start does not fit the budget.
std::optional<AnnealResult> anneal(const PlanGenome& start, double budget, const TableSpec& table,
                                   const Site& site, const AnnealOptions& o,
                                   const std::function<Excess(const PlanGenome&)>& score);

/// design --optimize --anneal: the annealing from the search's result `r` (its plan as a genome,
/// the search's covariance pass as the score, `search.budget_s` as the budget). Its best plan
/// replaces `r`'s (plan, text, excess, meets; origin "annealing") when its worst sigma / target is
/// smaller; `r.evaluations` counts its passes. None without a budget or when `r`'s plan is not a
/// genome (structure_moves.hpp genome_of).
std::optional<AnnealResult> anneal_search_result(SearchResult& r, const CalibratorOptions& options,
                                                 const TableSpec& table, const Site& site,
                                                 const SearchOptions& search,
                                                 const AnnealOptions& o);

/// The north carousel: body z north and x up at the start (ned-frd heading 0, pitch 90), then
/// each body axis in turn points north while the table turns about it in `step` turns, a full
/// revolution forwards and one back (z, then y after a 90 deg turn about the vertical x, then x
/// after a 90 deg turn about the horizontal z); every dwell `dwell` s. 45 deg steps: 50 turns.
/// Throws std::invalid_argument unless 360 deg is a whole number of steps of 1 to 180 deg.
PlanGenome north_carousel(double step, double dwell);

}  // namespace sinscal
