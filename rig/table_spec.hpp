// A calibration table as a lab owns it (config/tables/*.ini, docs/formats.md): its axes, the rate
// and acceleration its drives reach, how long it takes to settle after a move, how well it sets
// an attitude, and whether the IMU's reference point sits on its axes. Plan design reads it; a
// plan that asks more than the table gives is refused with the segment and the figures.
#pragma once

#include <string>
#include <vector>

#include "rig/motion.hpp"
#include "rig/plan.hpp"

namespace sinscal {

struct TableSpec {
  std::string name;
  std::string path;
  int axes = 2;                   // 2: tilt-rotation (outer, inner); 3: three-axis
  double max_rate = 0.0;          // rad/s, each axis
  double max_acceleration = 0.0;  // rad/s^2, each axis
  double settling_time = 0.0;     // s after a move before the table holds its attitude
  double attitude_sigma = 0.0;    // rad per axis and dwell (rig/table.hpp TableAttitudeError)
  /// The IMU's reference point on the table's axes: it stays put while the table turns, so the
  /// zero-velocity updates continue through the turns.
  bool reference_on_axes = true;
  /// How its turns depart from the commanded trapezoids (simulate --table; docs/formats.md
  /// "Table files"): max_rate and max_acceleration above, and the optional keys jerk_time,
  /// smoothing, servo_frequency, servo_damping, ripple_frequency, ripple_damping, rate_ripple,
  /// rate_ripple_period.
  TableDynamics dynamics;

  static TableSpec load(const std::string& path);
  static TableSpec parse(const std::string& path, const std::string& text);
};

/// A way the motion of a plan exceeds the table (empty when it fits).
struct TableViolation {
  int segment = 0;  // 1-based motion segment
  double t0 = 0.0;  // s, its start
  std::string what;
};
/// The motion's segments against the table's rate and acceleration limits (the peak of each
/// profile; rotations about body axes count as one axis each) and its settling time (every dwell
/// after a move must last at least the settling time plus `margin`).
std::vector<TableViolation> check_against_table(const Motion& motion, const TableSpec& table,
                                                double margin);

}  // namespace sinscal
