#include "models/attitude.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sinscal {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Eigen::Matrix3d rotation(const Eigen::Vector3d& axis, double angle_rad) {
  const double s = std::sin(angle_rad), c = std::cos(angle_rad);
  const Eigen::Matrix3d K = skew(axis);
  return Eigen::Matrix3d::Identity() + s * K + (1.0 - c) * K * K;
}

Eigen::Matrix3d dcm_from_rotvec(const Eigen::Vector3d& rotvec) {
  return quat_from_rotvec(rotvec).toRotationMatrix();
}

Eigen::Vector3d rotvec_from_dcm(const Eigen::Matrix3d& C) {
  return rotvec_from_quat(Eigen::Quaterniond(C));
}

Eigen::Quaterniond quat_from_rotvec(const Eigen::Vector3d& rotvec) {
  const double a2 = rotvec.squaredNorm();
  double c = 0.0, s_over_a = 0.0;  // cos(a/2), sin(a/2)/a
  if (a2 < 1e-4) {
    // Series; the first omitted terms are below 1e-19 for a < 1e-2.
    c = 1.0 - a2 / 8.0 + a2 * a2 / 384.0 - a2 * a2 * a2 / 46080.0;
    s_over_a = 0.5 - a2 / 48.0 + a2 * a2 / 3840.0 - a2 * a2 * a2 / 645120.0;
  } else {
    const double a = std::sqrt(a2);
    c = std::cos(0.5 * a);
    s_over_a = std::sin(0.5 * a) / a;
  }
  return Eigen::Quaterniond(c, s_over_a * rotvec.x(), s_over_a * rotvec.y(), s_over_a * rotvec.z());
}

Eigen::Vector3d rotvec_from_quat(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double s = q.vec().norm();
  if (s < 1e-8) return 2.0 * q.vec() / q.w() * (1.0 - s * s / (3.0 * q.w() * q.w()));
  return 2.0 * std::atan2(s, q.w()) / s * q.vec();
}

AngleConvention parse_angle_convention(const std::string& name) {
  if (name == "ned-frd") return AngleConvention::NedFrd;
  if (name == "paper") return AngleConvention::Paper;
  if (name == "enu-rfu") return AngleConvention::EnuRfu;
  throw std::invalid_argument("unknown angle convention '" + name +
                              "' (known: ned-frd, paper, enu-rfu)");
}

std::string to_string(AngleConvention convention) {
  switch (convention) {
    case AngleConvention::Paper:
      return "paper";
    case AngleConvention::EnuRfu:
      return "enu-rfu";
    case AngleConvention::NedFrd:
      break;
  }
  return "ned-frd";
}

Eigen::Matrix3d C_nue_ned() {
  Eigen::Matrix3d T;
  T << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return T;
}

Eigen::Matrix3d C_enu_ned() {
  Eigen::Matrix3d T;
  T << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  return T;
}

Eigen::Matrix3d C_b_n_from_euler(AngleConvention convention, const EulerAngles& e) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(),
                        z = Eigen::Vector3d::UnitZ();
  switch (convention) {
    case AngleConvention::NedFrd:
      return rotation(z, e.heading) * rotation(y, e.pitch) * rotation(x, e.roll);
    case AngleConvention::Paper:
      return C_nue_ned() * rotation(y, -e.heading) * rotation(z, e.pitch) * rotation(x, e.roll);
    case AngleConvention::EnuRfu:
      // PSINS a2mat: yaw (about Up), then pitch (about the body's right axis x), then roll
      // (about its forward axis y); yaw is counter-clockwise: yaw = -heading.
      return C_enu_ned() * rotation(z, -e.heading) * rotation(x, e.pitch) * rotation(y, e.roll);
  }
  throw std::invalid_argument("C_b_n_from_euler: unknown angle convention");
}

EulerAngles euler_from_C_b_n(AngleConvention convention, const Eigen::Matrix3d& C_b_n) {
  EulerAngles e;
  if (convention == AngleConvention::NedFrd) {
    e.pitch = -std::asin(std::clamp(C_b_n(2, 0), -1.0, 1.0));
    e.heading = std::atan2(C_b_n(1, 0), C_b_n(0, 0));
    e.roll = std::atan2(C_b_n(2, 1), C_b_n(2, 2));
  } else if (convention == AngleConvention::EnuRfu) {
    const Eigen::Matrix3d C = C_enu_ned() * C_b_n;  // body to East-North-Up
    e.pitch = std::asin(std::clamp(C(2, 1), -1.0, 1.0));
    if (std::hypot(C(0, 1), C(1, 1)) > 1e-9) {
      e.roll = std::atan2(-C(2, 0), C(2, 2));
      e.heading = -std::atan2(-C(0, 1), C(1, 1));  // minus the yaw
    } else {
      // Forward (y) vertical: only yaw + roll (pitch up) or yaw - roll (down) is defined; roll 0.
      e.roll = 0.0;
      e.heading = -std::atan2(C(1, 0), C(0, 0));
    }
  } else {
    const Eigen::Matrix3d C = C_nue_ned().transpose() * C_b_n;  // body to North-Up-East
    e.pitch = std::asin(std::clamp(C(1, 0), -1.0, 1.0));
    e.heading = std::atan2(C(2, 0), C(0, 0));
    e.roll = std::atan2(-C(1, 2), C(1, 1));
  }
  if (e.heading < 0.0) e.heading += 2.0 * M_PI;
  return e;
}

Eigen::Vector3d attitude_error_n(const Eigen::Matrix3d& C_b_n_computed,
                                 const Eigen::Matrix3d& C_b_n_true) {
  return rotvec_from_dcm(C_b_n_true * C_b_n_computed.transpose());
}

}  // namespace sinscal
