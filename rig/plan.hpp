// Calibration plans (config/plans/*.ini) and the motion they command. Format: docs/formats.md.
//   type = orientations: static orientations (heading, pitch, roll in a named convention) each
//     with a dwell, reached by two-axis table moves at a move rate and acceleration;
//   type = rotations: a start attitude and dwell, then rotations about body axes (+x ... -z) or
//     table axes (+outer, -inner, ...), each with an angle, a duration or rate, and a pause; or a
//     rate-table segment: a constant rate about a body axis for a time (`hold`) or a whole number
//     of revolutions, without a known angle (calibrate --method rate-table uses its mean output).
// `[table] axes = 3`: a three-axis table, any attitude reachable.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "models/attitude.hpp"
#include "models/earth.hpp"
#include "rig/motion.hpp"
#include "rig/table.hpp"

namespace sinscal {

struct PlanOrientation {
  std::string label;
  EulerAngles angles;  // rad, in the plan's convention
  double dwell = 0.0;  // s
};

struct RotationStep {
  enum class Axis { Body, Outer, Inner };
  Axis kind = Axis::Body;
  Eigen::Vector3d axis_b = Eigen::Vector3d::UnitX();  // unit, Body kind only
  double sign = 1.0;                                  // Outer / Inner kinds
  std::string axis_name;                              // as written: "+y", "-outer"
  double angle = 0.0;     // rad (positive; the direction is in the axis)
  double duration = 0.0;  // s; 0: from `rate`
  double rate = 0.0;      // rad/s peak rate when duration is 0
  double pause = 0.0;     // s static after the rotation
  /// A rate-table segment: `rate` held for `hold` s (the angle follows: rate * hold plus the
  /// ramps' rate^2 / acceleration) or `revolutions` whole turns (angle 2 pi revolutions).
  bool constant_rate = false;
  double hold = 0.0;    // s at the constant rate (0: given by revolutions)
  int revolutions = 0;  // whole turns (0: given by hold)
};

/// Size limits of a plan (docs/formats.md): orientations or turns, and the duration of the whole
/// plan (dwells, moves, turns, pauses). `[plan] allow_large = true` raises them.
struct PlanLimits {
  std::size_t max_entries = 100000;
  double max_duration = 7.0 * 86400.0;  // s
  bool large = false;
  static PlanLimits standard() { return {}; }
  static PlanLimits raised() { return {10000000, 366.0 * 86400.0, true}; }
  /// How to raise a limit, for messages ("" when raised already).
  std::string hint() const {
    return large ? std::string()
                 : " ('allow_large = true' in [plan] raises the limits to 10,000,000 entries and "
                   "366 days)";
  }
};

struct Plan {
  enum class Type { Orientations, Rotations };
  std::string name;
  std::string path;
  std::string text;  // the file as read (copied into simulated sessions)
  Type type = Type::Orientations;
  AngleConvention convention = AngleConvention::NedFrd;
  Site site;
  bool has_site = false;
  TableGeometry table;
  double move_rate = 0.0;   // rad/s (orientations)
  double move_accel = 0.0;  // rad/s^2 (both types)
  std::vector<PlanOrientation> orientations;
  EulerAngles start;         // rotations
  double start_dwell = 0.0;  // s
  std::vector<RotationStep> steps;
  PlanLimits limits;

  /// Loads and validates a plan; throws ConfigError naming file, line and key.
  static Plan load(const std::string& path);
  static Plan parse(const std::string& path, const std::string& text);
};

/// Errors of the table, for simulations. Every commanded axis angle (orientation plans) or
/// rotation angle and the start attitude (rotation plans) is off by a random angle of sigma
/// `angle_sigma`; the inner axis leans by `non_orthogonality` from its nominal direction
/// (towards the outer axis). The start attitude of a rotation plan is off by `start_sigma` per
/// axis. The known attitudes of the dwells stay the plan's.
struct TableErrors {
  double angle_sigma = 0.0;  // rad, error of each commanded table angle
  /// rad: an independent error of the IMU's attitude about each navigation axis at every dwell:
  /// the table-error model of the estimators (rig/table.hpp TableAttitudeError). Orientation
  /// plans: a wobble of the dwell (mounting repeatability). Rotation plans: every turn about a
  /// body axis ends at its dwell's known attitude turned by an independent error (the turn
  /// carries the correction, so the motion stays continuous and the gyros see it), and the
  /// start is off by it unless start_sigma is given.
  double attitude_sigma = 0.0;
  double start_sigma = -1.0;       // rad, start attitude of rotation plans (< 0: angle_sigma)
  double non_orthogonality = 0.0;  // rad
  std::uint64_t seed = 0;
  /// The table's base: a constant rotation of the whole table in the navigation frame,
  /// C_b_n_true = R(base) C_b_n(plan), R(base) = dcm_from_rotvec(base_n()) (docs/conventions.md
  /// "Table base and mounting"). Level about North and East, heading about Down (rad).
  double base_level_north = 0.0;
  double base_level_east = 0.0;
  double base_heading = 0.0;
  /// The IMU's mounting on the platform: C_b_p = dcm_from_rotvec(mounting_b), the rotation vector
  /// of the IMU's axes relative to the platform's nominal ones (rad, body axes):
  /// C_b_n_true = C_p_n C_b_p.
  Eigen::Vector3d mounting_b = Eigen::Vector3d::Zero();
  /// How the table's turns depart from the commanded trapezoids (rig/motion.hpp): limits, servo,
  /// smoothing, ripple; its start_offset delays the whole motion in the log (the simulator).
  TableDynamics dynamics;
  Eigen::Vector3d base_n() const { return {base_level_north, base_level_east, base_heading}; }
  bool has_installation_errors() const { return base_n().norm() > 0.0 || mounting_b.norm() > 0.0; }
};

class IniFile;

/// The [site] section of a plan or session: `latitude` (required), `longitude`, `height`
/// (default 0), each within SiteLimits (models/earth.hpp); an error is a ConfigError naming the
/// file, line and key.
Site read_site(const IniFile& ini);

/// The motion a plan commands at `site`; with table errors, the truth differs from the plan (the
/// base and mounting rotate the true attitude only: the dwells' known attitudes and the table's
/// angles stay the plan's).
Motion build_motion(const Plan& plan, const Site& site, const TableErrors& errors = {});

}  // namespace sinscal
