// The Kalman filter's measurements of its error state (filter/kalman/state_layout.hpp) and the
// feedback of an estimated error into the navigator and the coefficients.
//
// Error-state convention (docs/conventions.md): the navigation errors are computed minus true,
// phi_n with C_b_n_computed = R(-phi_n) C_b_n_true, dv_n = v_computed - v_true, dp_n the position
// error in metres north, east, down; the coefficient errors are true minus estimated. Every
// measurement here observes one state directly (H is a selection), and its value is the
// navigation error against what the table knows: zero velocity, the known position, the table's
// attitude.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "filter/kalman/state_layout.hpp"
#include "filter/strapdown/ins_error_model.hpp"
#include "filter/strapdown/strapdown.hpp"
#include "models/imu_error_model.hpp"

namespace sinscal {

/// z = H x + v, v ~ N(0, diag(sigma^2)); row i observes state `states[i]` minus the states
/// `minus_states[i]` and `minus_states_2[i]` that are not -1 (H: +1 and -1 entries).
struct Measurement {
  std::vector<int> states;
  std::vector<int> minus_states;    // one per row, -1: none
  std::vector<int> minus_states_2;  // one per row, -1: none
  std::vector<double> z;
  std::vector<double> sigma;
  int rows() const { return static_cast<int>(states.size()); }
  bool empty() const { return states.empty(); }
  /// Adds the rows of another measurement (updates made together).
  void append(const Measurement& other);
  /// The measurement matrix for a state of size n.
  Eigen::MatrixXd H(int n) const;
};

/// Zero velocity: the IMU reference point at rest (table still, or turning about it).
Measurement zero_velocity(const StateLayout& layout, const NavState& x, double sigma);
/// The known position of the site (the table does not move).
Measurement known_position(const StateLayout& layout, const NavState& x, const Site& site,
                           double sigma);
/// The attitude the table gives (C_b_n_known, relative to the table's base), per axis of the
/// navigation frame. With the base attitude in the layout, the attitude in the navigation frame
/// is C_base C_b_n_known (C_base: the base's estimate) and the rows observe phi_n - d_base. With
/// the dwell's orientation error in the layout as well, it is C_dwell C_base C_b_n_known
/// (C_dwell: that error's estimate) and the rows observe phi_n - d_base - d_dwell.
Measurement known_attitude(const StateLayout& layout, const NavState& x,
                           const Eigen::Matrix3d& C_b_n_known, double sigma,
                           const Eigen::Matrix3d& C_base = Eigen::Matrix3d::Identity(),
                           const Eigen::Matrix3d& C_dwell = Eigen::Matrix3d::Identity());
/// The base estimate that carries the estimated error `dx` (its base block): C_base <- R(d_base)
/// C_base; inject_base_error() is its inverse. Nothing without a base block.
void feed_back_base(const StateLayout& layout, const Eigen::VectorXd& dx, Eigen::Matrix3d& C_base);
/// The same for the dwell's orientation error (its block): C_dwell <- R(d_dwell) C_dwell, and
/// its inverse.
void feed_back_dwell_orientation(const StateLayout& layout, const Eigen::VectorXd& dx,
                                 Eigen::Matrix3d& C_dwell);
void inject_dwell_orientation_error(const StateLayout& layout, const Eigen::VectorXd& dx,
                                    Eigen::Matrix3d& C_dwell);
void inject_base_error(const StateLayout& layout, const Eigen::VectorXd& dx,
                       Eigen::Matrix3d& C_base);

/// The navigation state and model that carry the error `dx` (layout's states) on top of the true
/// ones: the inverse of feed_back(). Tests and Monte Carlo use it to inject known errors.
void inject_error(const StateLayout& layout, const InsSiteTerms& site, const Eigen::VectorXd& dx,
                  NavState& x, ImuErrorModel& model);
/// Removes an estimated error `dx` from the navigator's state and the model's coefficients (the
/// filter's feedback after every update; the error state is then reset to zero).
void feed_back(const StateLayout& layout, const InsSiteTerms& site, const Eigen::VectorXd& dx,
               NavState& x, ImuErrorModel& model);

}  // namespace sinscal
