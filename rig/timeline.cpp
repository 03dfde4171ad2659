#include "rig/timeline.hpp"

#include "rig/motion.hpp"
#include "rig/plan.hpp"

namespace sinscal {

PlanTimeline PlanTimeline::of(const Plan& plan, const Site& site) {
  // The motion the plan commands, without table errors: its dwells' known parts only.
  const Motion motion = build_motion(plan, site);
  PlanTimeline t;
  for (const Dwell& d : motion.dwells()) t.dwells.push_back(static_cast<const PlanDwell&>(d));
  t.duration = motion.duration();
  t.rotations = plan.type == Plan::Type::Rotations;
  t.table = plan.table;
  return t;
}

}  // namespace sinscal
