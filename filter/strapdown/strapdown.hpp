// Strapdown navigator in the local NED frame.
//
// Per IMU interval (increments dtheta_b, dv_b over dt):
//   attitude  C_b_n(k) = R(-zeta) C_b_n(k-1) R(phi), phi = dtheta + 1/12 dtheta_prev x dtheta
//             (two-sample coning), zeta = (omega_ie_n + omega_en_n) dt (navigation-frame turn);
//   velocity  dv_b' = dv + 1/2 dtheta x dv (rotation) + 1/12 (dtheta_prev x dv + dv_prev x dtheta)
//             (two-sample sculling) + 1/6 dtheta x (dtheta x dv) (second-order rotation),
//             v_n += (I - 1/2 [zeta x]) C_b_n(k-1) dv_b' + (g_n - (2 omega_ie_n + omega_en_n) x
//             v_n) dt;
//   position  latitude, longitude, height by the trapezoidal rule; the vertical channel free or
//   held.
// Earth terms from models/earth.hpp (GeographicLib) through LocalEarth.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "models/earth.hpp"

namespace sinscal {

struct NavState {
  double t = 0.0;                                             // s
  Eigen::Quaterniond q_b_n = Eigen::Quaterniond::Identity();  // body to NED
  Eigen::Vector3d v_n = Eigen::Vector3d::Zero();              // m/s, NED, relative to the Earth
  double lat_rad = 0.0;
  double lon_rad = 0.0;
  double h_m = 0.0;
  Eigen::Matrix3d C_b_n() const { return q_b_n.toRotationMatrix(); }
  /// At rest at `site` with attitude C_b_n (the start of every static navigation).
  static NavState at_rest(const Eigen::Matrix3d& C_b_n, const Site& site);
};

struct StrapdownOptions {
  bool vertical_held = false;  // hold height and vertical velocity at their initial values
};

class Strapdown {
 public:
  explicit Strapdown(const Earth& earth = Earth::wgs84(), const StrapdownOptions& options = {});
  /// Starts from a state; the coning and sculling memory is cleared.
  void reset(const NavState& state);
  /// One interval of increments (rad, m/s, body axes) of length dt (s).
  void step(const Eigen::Vector3d& dtheta_b, const Eigen::Vector3d& dv_b, double dt);
  const NavState& state() const { return x_; }
  /// Replaces the state (a filter's feedback) keeping the coning and sculling memory.
  void correct(const NavState& state) { x_ = state; }

 private:
  LocalEarth earth_;
  StrapdownOptions options_;
  NavState x_;
  double h_held_ = 0.0;
  bool have_prev_ = false;
  Eigen::Vector3d dtheta_prev_ = Eigen::Vector3d::Zero(), dv_prev_ = Eigen::Vector3d::Zero();
};

/// Navigation errors of a computed state against a true one: velocity (m/s, NED), attitude
/// phi_n (rad, NED, C_b_n_computed = R(-phi_n) C_b_n_true) and position (m, NED).
struct NavError {
  double t = 0.0;
  Eigen::Vector3d dv_n = Eigen::Vector3d::Zero();
  Eigen::Vector3d phi_n = Eigen::Vector3d::Zero();
  Eigen::Vector3d dp_n = Eigen::Vector3d::Zero();
};

NavError nav_error(const NavState& computed, const Eigen::Matrix3d& C_b_n_true,
                   const Eigen::Vector3d& v_n_true, const Site& site_true,
                   const Earth& earth = Earth::wgs84());

}  // namespace sinscal
