// What the estimators know of a session's plan: its static dwells (plan time, the attitude the
// table sets), its duration and the table's nominal geometry. Made from the plan alone: the
// simulation's truth (the attitudes the table really reached) is not in it, so an estimator that
// takes a timeline cannot see it. A log refines it (static intervals detected in the data, the
// attitude its table-angle columns give).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "models/earth.hpp"
#include "rig/table.hpp"

namespace sinscal {

struct Plan;

/// A static interval of the plan: when it is and the attitude the plan says the table sets.
struct PlanDwell {
  int index = 0;  // 1-based
  std::string label;
  double t_start = 0.0;  // s, plan time
  double t_end = 0.0;    // s
  Eigen::Matrix3d C_b_n_known = Eigen::Matrix3d::Identity();
};

struct PlanTimeline {
  std::vector<PlanDwell> dwells;
  double duration = 0.0;   // s, the plan's end
  bool rotations = false;  // a rotation plan (turns about body or table axes)
  TableGeometry table;     // the plan's nominal table (attitude from table-angle columns)

  /// The timeline of a plan at a site (the table's moves timed as the plan says).
  static PlanTimeline of(const Plan& plan, const Site& site);
};

}  // namespace sinscal
