#include "filter/kalman/measurements.hpp"

#include <cmath>

#include "models/attitude.hpp"

namespace sinscal {

void Measurement::append(const Measurement& other) {
  states.insert(states.end(), other.states.begin(), other.states.end());
  minus_states.insert(minus_states.end(), other.minus_states.begin(), other.minus_states.end());
  minus_states_2.insert(minus_states_2.end(), other.minus_states_2.begin(),
                        other.minus_states_2.end());
  z.insert(z.end(), other.z.begin(), other.z.end());
  sigma.insert(sigma.end(), other.sigma.begin(), other.sigma.end());
}

Eigen::MatrixXd Measurement::H(int n) const {
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(rows(), n);
  for (int i = 0; i < rows(); ++i) {
    const auto r = static_cast<std::size_t>(i);
    h(i, states[r]) = 1.0;
    if (minus_states[r] >= 0) h(i, minus_states[r]) = -1.0;
    if (minus_states_2[r] >= 0) h(i, minus_states_2[r]) = -1.0;
  }
  return h;
}

namespace {
Measurement of_block(const Block& b, const Eigen::Vector3d& value, double sigma) {
  Measurement m;
  for (int i = 0; i < b.size; ++i) {
    m.states.push_back(b.index + i);
    m.minus_states.push_back(-1);
    m.minus_states_2.push_back(-1);
    m.z.push_back(value(i));
    m.sigma.push_back(sigma);
  }
  return m;
}
}  // namespace

Measurement zero_velocity(const StateLayout& l, const NavState& x, double sigma) {
  return of_block(l.velocity, x.v_n, sigma);  // the true velocity is zero
}

Measurement known_position(const StateLayout& l, const NavState& x, const Site& site,
                           double sigma) {
  return of_block(l.position, nav_error(x, x.C_b_n(), Eigen::Vector3d::Zero(), site).dp_n, sigma);
}

Measurement known_attitude(const StateLayout& l, const NavState& x,
                           const Eigen::Matrix3d& C_b_n_known, double sigma,
                           const Eigen::Matrix3d& C_base, const Eigen::Matrix3d& C_dwell) {
  // True attitude R(d_dwell) C_dwell R(d_base) C_base C_b_n_known, computed R(-phi) times the
  // true one: the rotation vector of (C_dwell C_base C_b_n_known) C_b_n_computed^T is
  // phi - d_base - d_dwell to first order.
  Measurement m =
      of_block(l.attitude, attitude_error_n(x.C_b_n(), C_dwell * C_base * C_b_n_known), sigma);
  if (StateLayout::on(l.base))
    for (int i = 0; i < 3; ++i) m.minus_states[static_cast<std::size_t>(i)] = l.base.index + i;
  if (StateLayout::on(l.dwell_orientation))
    for (int i = 0; i < 3; ++i)
      m.minus_states_2[static_cast<std::size_t>(i)] = l.dwell_orientation.index + i;
  return m;
}

void feed_back_base(const StateLayout& l, const Eigen::VectorXd& dx, Eigen::Matrix3d& C_base) {
  if (!StateLayout::on(l.base)) return;
  C_base = dcm_from_rotvec(dx.segment<3>(l.base.index)) * C_base;
}

void feed_back_dwell_orientation(const StateLayout& l, const Eigen::VectorXd& dx,
                                 Eigen::Matrix3d& C_dwell) {
  if (!StateLayout::on(l.dwell_orientation)) return;
  C_dwell = dcm_from_rotvec(dx.segment<3>(l.dwell_orientation.index)) * C_dwell;
}

void inject_dwell_orientation_error(const StateLayout& l, const Eigen::VectorXd& dx,
                                    Eigen::Matrix3d& C_dwell) {
  if (!StateLayout::on(l.dwell_orientation)) return;
  C_dwell = dcm_from_rotvec(-dx.segment<3>(l.dwell_orientation.index)) * C_dwell;
}

void inject_base_error(const StateLayout& l, const Eigen::VectorXd& dx, Eigen::Matrix3d& C_base) {
  if (!StateLayout::on(l.base)) return;
  C_base = dcm_from_rotvec(-dx.segment<3>(l.base.index)) * C_base;
}

void inject_error(const StateLayout& l, const InsSiteTerms& site, const Eigen::VectorXd& dx,
                  NavState& x, ImuErrorModel& model) {
  const Eigen::Vector3d phi = dx.segment<3>(l.attitude.index);
  x.q_b_n = (quat_from_rotvec(-phi) * x.q_b_n).normalized();
  for (int i = 0; i < l.velocity.size; ++i) x.v_n(i) += dx(l.velocity.index + i);
  const Eigen::Vector3d dp = dx.segment<3>(l.position.index);
  x.lat_rad += dp.x() / site.R_N;
  x.lon_rad += dp.y() / (site.R_E * std::cos(site.lat_rad));
  x.h_m -= dp.z();
  auto refs = model.coefficient_refs();
  for (std::size_t c = 0; c < l.state_of.size(); ++c)
    if (l.state_of[c] >= 0) *refs[c].second -= dx(l.state_of[c]);
}

void feed_back(const StateLayout& l, const InsSiteTerms& site, const Eigen::VectorXd& dx,
               NavState& x, ImuErrorModel& model) {
  const Eigen::Vector3d phi = dx.segment<3>(l.attitude.index);
  x.q_b_n = (quat_from_rotvec(phi) * x.q_b_n).normalized();
  for (int i = 0; i < l.velocity.size; ++i) x.v_n(i) -= dx(l.velocity.index + i);
  const Eigen::Vector3d dp = dx.segment<3>(l.position.index);
  x.lat_rad -= dp.x() / site.R_N;
  x.lon_rad -= dp.y() / (site.R_E * std::cos(site.lat_rad));
  x.h_m += dp.z();
  auto refs = model.coefficient_refs();
  for (std::size_t c = 0; c < l.state_of.size(); ++c)
    if (l.state_of[c] >= 0) *refs[c].second += dx(l.state_of[c]);
}

}  // namespace sinscal
