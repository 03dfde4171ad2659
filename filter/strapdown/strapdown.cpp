#include "filter/strapdown/strapdown.hpp"

#include <cmath>

#include "models/attitude.hpp"

namespace sinscal {

NavState NavState::at_rest(const Eigen::Matrix3d& C_b_n, const Site& site) {
  NavState x;
  x.q_b_n = Eigen::Quaterniond(C_b_n).normalized();
  x.lat_rad = site.lat_rad;
  x.lon_rad = site.lon_rad;
  x.h_m = site.h_m;
  return x;
}

Strapdown::Strapdown(const Earth& earth, const StrapdownOptions& options)
    : earth_(earth), options_(options) {}

void Strapdown::reset(const NavState& state) {
  x_ = state;
  x_.q_b_n.normalize();
  h_held_ = state.h_m;
  have_prev_ = false;
}

void Strapdown::step(const Eigen::Vector3d& dtheta, const Eigen::Vector3d& dv, double dt) {
  if (!have_prev_) {  // no history: assume the previous interval was like this one
    dtheta_prev_ = dtheta;
    dv_prev_ = dv;
    have_prev_ = true;
  }
  const Eigen::Vector3d phi = dtheta + dtheta_prev_.cross(dtheta) / 12.0;
  const Eigen::Vector3d rot = 0.5 * dtheta.cross(dv);
  const Eigen::Vector3d scul = (dtheta_prev_.cross(dv) + dv_prev_.cross(dtheta)) / 12.0;
  const Eigen::Vector3d second = dtheta.cross(dtheta.cross(dv)) / 6.0;
  const Eigen::Vector3d dv_b = dv + rot + scul + second;
  dtheta_prev_ = dtheta;
  dv_prev_ = dv;

  // Earth terms at the mid-interval position, extrapolated with the current velocity.
  const EarthTerms& e0 = earth_.at(x_.lat_rad, x_.h_m);
  const double RN = e0.R_N + x_.h_m;
  const double lat_mid = x_.lat_rad + 0.5 * dt * x_.v_n.x() / RN;
  const double h_mid = x_.h_m - 0.5 * dt * x_.v_n.z();
  const EarthTerms& e = earth_.at(lat_mid, h_mid);
  const double RNm = e.R_N + h_mid, REm = e.R_E + h_mid;
  auto transport = [&](const Eigen::Vector3d& v) {
    return Eigen::Vector3d(v.y() / REm, -v.x() / RNm, -v.y() * e.tan_lat / REm);
  };

  const Eigen::Matrix3d C = x_.q_b_n.toRotationMatrix();
  const Eigen::Vector3d omega_en_n0 = transport(x_.v_n);
  const Eigen::Vector3d zeta0 = (e.omega_ie_n + omega_en_n0) * dt;
  const Eigen::Vector3d dv_sf_n = C * dv_b;
  const Eigen::Vector3d dv_sf = dv_sf_n - 0.5 * zeta0.cross(dv_sf_n);
  // Coriolis and gravity at the mid-interval velocity (predicted).
  Eigen::Vector3d v_mid = x_.v_n + 0.5 * (dv_sf + e.g_n * dt);
  if (options_.vertical_held) v_mid.z() = 0.0;
  const Eigen::Vector3d omega_en_n = transport(v_mid);
  const Eigen::Vector3d dv_cor = (e.g_n - (2.0 * e.omega_ie_n + omega_en_n).cross(v_mid)) * dt;
  const Eigen::Vector3d v_old = x_.v_n;
  x_.v_n += dv_sf + dv_cor;
  if (options_.vertical_held) x_.v_n.z() = 0.0;

  // Position (trapezoidal).
  const Eigen::Vector3d v_avg = 0.5 * (v_old + x_.v_n);
  x_.lat_rad += v_avg.x() / RNm * dt;
  x_.lon_rad += v_avg.y() / (REm * e.cos_lat) * dt;
  x_.h_m = options_.vertical_held ? h_held_ : x_.h_m - v_avg.z() * dt;

  // Attitude: body turn phi, navigation-frame turn zeta (mid-interval transport rate).
  const Eigen::Vector3d zeta = (e.omega_ie_n + omega_en_n) * dt;
  x_.q_b_n = quat_from_rotvec(-zeta) * x_.q_b_n * quat_from_rotvec(phi);
  x_.q_b_n.normalize();
  x_.t += dt;
}

NavError nav_error(const NavState& x, const Eigen::Matrix3d& C_b_n_true,
                   const Eigen::Vector3d& v_n_true, const Site& site, const Earth& earth) {
  NavError err;
  err.t = x.t;
  err.dv_n = x.v_n - v_n_true;
  err.phi_n = attitude_error_n(x.C_b_n(), C_b_n_true);
  err.dp_n.x() = (x.lat_rad - site.lat_rad) * (earth.radius_meridian(site.lat_rad) + site.h_m);
  err.dp_n.y() = std::remainder(x.lon_rad - site.lon_rad, 2.0 * M_PI) *
                 (earth.radius_transverse(site.lat_rad) + site.h_m) * std::cos(site.lat_rad);
  err.dp_n.z() = -(x.h_m - site.h_m);
  return err;
}

}  // namespace sinscal
