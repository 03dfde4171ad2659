// Plan design: hand plans scaled to a table time, the seeds that make the search at least as
// good as each of them (filter/design/search.hpp). docs/methods/design.md "Seeds".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "rig/plan.hpp"

namespace sinscal {

/// A plan's dwells (s): a rotation plan's start dwell then its pauses, or an orientation plan's
/// dwells.
std::vector<double> plan_dwells(const Plan& plan);
/// `plan` (from `dwell_scaled`, whose text states every dwell once) with the dwells `dwells`,
/// in plan_dwells' order. Throws std::invalid_argument for a count that differs.
Plan with_dwells(const Plan& plan, const std::vector<double>& dwells);

/// `plan` with its name set to `name` (the plan's text rewritten as with_dwells does).
Plan renamed(const Plan& plan, const std::string& name);

/// The searched plans bundled in `dir` (the files searched-*.ini, in the order of their names):
/// seeds of design --optimize beside the hand plans. None when `dir` holds none.
std::vector<Plan> searched_plans_in(const std::string& dir);

/// `plan` with every dwell (the start dwell and the pauses of a rotation plan, the dwells of an
/// orientation plan) times one factor, none below `min_dwell` (s), so that the whole lasts
/// `duration` s (to 0.05 s); its moves and turns unchanged. The plan's own text with those
/// lines rewritten in seconds, named `<name>-<duration>s`. Empty when the moves and the shortest
/// dwells alone take longer, or for a plan with `repeat` or a pause of 0 (not a dwell).
std::optional<Plan> dwell_scaled(const Plan& plan, double duration, double min_dwell);

}  // namespace sinscal
