// Plan design: hand plans scaled to a table time, the seeds that make the search at least as
// good as each of them (filter/design/search.hpp). docs/methods/design.md "Seeds".
#pragma once

#include <optional>
#include <string>

#include "rig/plan.hpp"

namespace sinscal {

/// `plan` with every dwell (the start dwell and the pauses of a rotation plan, the dwells of an
/// orientation plan) times one factor, none below `min_dwell` (s), so that the whole lasts
/// `duration` s (to 0.05 s); its moves and turns unchanged. The plan's own text with those
/// lines rewritten in seconds, named `<name>-<duration>s`. Empty when the moves and the shortest
/// dwells alone take longer, or for a plan with `repeat` or a pause of 0 (not a dwell).
std::optional<Plan> dwell_scaled(const Plan& plan, double duration, double min_dwell);

}  // namespace sinscal
