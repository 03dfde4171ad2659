// Attitude representations: direction-cosine matrices, quaternions, rotation vectors, Euler angles
// in named conventions. `C_b_n` maps body-frame vectors to the navigation frame (NED):
// v_n = C_b_n * v_b. Rotations are active and right-handed. See docs/conventions.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>

namespace sinscal {

/// Skew-symmetric matrix [v x]: skew(a) * b == a.cross(b).
Eigen::Matrix3d skew(const Eigen::Vector3d& v);
/// Rotation matrix of angle `angle_rad` about unit axis `axis` (Rodrigues).
Eigen::Matrix3d rotation(const Eigen::Vector3d& axis, double angle_rad);
/// Rotation matrix of a rotation vector (angle * unit axis).
Eigen::Matrix3d dcm_from_rotvec(const Eigen::Vector3d& rotvec);
/// Rotation vector of a rotation matrix (the logarithm; angle in [0, pi]).
Eigen::Vector3d rotvec_from_dcm(const Eigen::Matrix3d& C);
/// Unit quaternion of a rotation vector; accurate to rounding for all angles (series below 1e-2).
Eigen::Quaterniond quat_from_rotvec(const Eigen::Vector3d& rotvec);
/// Rotation vector of a unit quaternion.
Eigen::Vector3d rotvec_from_quat(const Eigen::Quaterniond& q);

/// Named conventions for orientation angles (heading, pitch, roll) and the body axes they assume.
enum class AngleConvention {
  /// Aerospace: body x forward, y right, z down; C_b_n = Rz(heading) Ry(pitch) Rx(roll) in NED.
  NedFrd,
  /// The source paper: body x forward, y up, z right; navigation North-Up-East;
  /// C_b^NUE = R_Y(-heading) R_Z(pitch) R_X(roll). Angles such as pitch 225 deg are literal.
  Paper,
  /// PSINS (the reference MATLAB toolbox): body x right, y forward, z up; navigation
  /// East-North-Up; yaw counter-clockwise from North (yaw = -heading);
  /// C_b^ENU = R_Z(yaw) R_X(pitch) R_Y(roll), then C_b_n = C_enu_ned() C_b^ENU.
  EnuRfu,
};

/// "ned-frd" | "paper" | "enu-rfu"
AngleConvention parse_angle_convention(const std::string& name);
std::string to_string(AngleConvention convention);

/// Heading, pitch, roll (rad) in a convention. `heading` is clockwise from North seen from above
/// in every convention (enu-rfu's counter-clockwise yaw is -heading).
struct EulerAngles {
  double heading = 0.0;
  double pitch = 0.0;
  double roll = 0.0;
};

/// Body-to-NED matrix of angles in a convention.
Eigen::Matrix3d C_b_n_from_euler(AngleConvention convention, const EulerAngles& angles);
/// Angles of a body-to-NED matrix in a convention (pitch within +-90 deg).
EulerAngles euler_from_C_b_n(AngleConvention convention, const Eigen::Matrix3d& C_b_n);

/// Matrix taking North-Up-East components to North-East-Down components.
Eigen::Matrix3d C_nue_ned();
/// Matrix taking East-North-Up components to North-East-Down components (its own inverse).
Eigen::Matrix3d C_enu_ned();

/// Attitude error phi_n (rad, NED) of a computed attitude against the true one, defined by
/// C_b_n_computed = R(-phi_n) * C_b_n_true  (small: C_b_n_computed = (I - [phi_n x]) C_b_n_true).
Eigen::Vector3d attitude_error_n(const Eigen::Matrix3d& C_b_n_computed,
                                 const Eigen::Matrix3d& C_b_n_true);

}  // namespace sinscal
