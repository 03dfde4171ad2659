// The error dynamics of the Kalman filter's state (filter/kalman/state_layout.hpp), accumulated
// into the transition over an update interval:
//
//   phi'  = -omega_ie x phi + d_omega_in(dv, dp) - C_b_n J_g dtheta
//   dv'   = f_n x phi - 2 omega_ie x dv + (2g/R) dp_d e_d + C_b_n J_a dtheta
//   dp'   = dv
//   dtheta' = 0 (coefficients constant; bias families wander with the profile's bias noise,
//               unless the layout has the wander's states)
//   w'    = -w / tau + noise (the bias instability's Gauss-Markov wander, when a state: it adds
//           to the compensated inputs like a bias, -C_b_n w_g on phi, C_b_n w_a on dv)
//
// with the INS error matrix of filter/strapdown/ins_error_model.hpp written in the layout's
// navigation indices, J the error model's Jacobian (models/imu_error_model.hpp) for the coefficient
// states, and dtheta = true - estimated coefficients. The transition has the structure
// [[Phi_nn, Phi_nc], [0, I]].
//
// Two rates. The error model's Jacobian J follows every IMU sample (the table's turns change it
// within a sample's time): its integral over a substep of about kTransitionSubstep is summed per
// sample, and with the substep's mean attitude gives the integral of the coefficient coupling
// B = [-C_b_n A_g^-1 J_g; C_b_n A_a^-1 J_a]. The INS error matrix A (Earth rate, gravity, the
// specific force in n) changes slowly; per substep h its mean is applied to second order:
//   Phi    <- Phi_h Phi,           Phi_h = I + A h + (A h)^2 / 2,
//   Phi_nc <- Phi_h Phi_nc + (I + A h / 2) int B,
//   Q      <- Phi_h Q Phi_h^T + (I + A h / 2) q h (I + A h / 2)^T,
// which matches the per-sample product (I + A dt) ... to second order in A h (about 1e-6 of the
// attitude-to-velocity coupling at h = 0.1 s; checked against the perturbed navigator in
// tests/test_error_dynamics.cpp). Fixed-size storage: nothing is allocated per sample.
#pragma once

#include <Eigen/Core>

#include "filter/kalman/state_layout.hpp"
#include "filter/strapdown/ins_error_model.hpp"
#include "models/imu_error_model.hpp"
#include "models/noise_model.hpp"

namespace sinscal {

// Fixed-size storage for the navigation rows: kMaxNavStates rows, of which the layout's nav_size
// are used (the layout's indices); with the vertical velocity off the last row and column are
// inert (zero dynamics, no coupling).
using NavMatrix = Eigen::Matrix<double, kMaxNavStates, kMaxNavStates, Eigen::RowMajor>;
using NavCoefficientMatrix = Eigen::Matrix<double, kMaxNavStates, Eigen::Dynamic, Eigen::RowMajor,
                                           kMaxNavStates, kMaxCoefficients>;

/// The transition's substep (s): the INS error matrix's mean over it is applied to second
/// order (a sample interval longer than it is one substep).
constexpr double kTransitionSubstep = 0.2;

class ErrorPropagator {
 public:
  ErrorPropagator(const StateLayout& layout, const InsSiteTerms& site, const NoiseModel& noise);
  /// One IMU interval of length dt: the navigator's attitude after it, the compensated
  /// kinematics (omega_ib_b, omega_dot_ib_b, f_ib_b, t), the rate of change of the specific
  /// force and the model the samples were compensated with (its Jacobian) with its
  /// linear_inverses().
  void step(const Eigen::Matrix3d& C_b_n, const KinematicSample& k, const Eigen::Vector3d& f_dot,
            const ImuErrorModel& model, const ImuErrorModel::LinearInverses& inverses, double dt) {
    step(C_b_n, k, f_dot, model, inverses, dt, C_b_n * k.f_ib_b);
  }
  /// The same with `f_n`, the specific force of the INS error matrix's f_n x phi term, given in
  /// navigation axes: along the table's known motion, the motion's own (without the sensor
  /// noise, whose product with an attitude error the data do not observe informs of nothing).
  void step(const Eigen::Matrix3d& C_b_n, const KinematicSample& k, const Eigen::Vector3d& f_dot,
            const ImuErrorModel& model, const ImuErrorModel::LinearInverses& inverses, double dt,
            const Eigen::Vector3d& f_n);
  /// P <- Phi P Phi^T + Q over the accumulated interval, then starts a new interval.
  void propagate(Eigen::MatrixXd& P);
  /// Completes the current substep: the accessors below then hold every sample stepped.
  void flush();
  /// Time accumulated since the last propagate() (s).
  double accumulated() const { return accumulated_; }
  /// The accumulated transition (layout indices): navigation errors from navigation errors
  /// (nav_size x nav_size) and from the coefficient states (nav_size x coefficient states), as of
  /// the last completed substep (flush()).
  Eigen::MatrixXd Phi_nn() const { return Phi_nn_.topLeftCorner(n_, n_); }
  Eigen::MatrixXd Phi_nc() const { return Phi_nc_.topRows(n_); }
  Eigen::MatrixXd Q_nn() const { return Q_nn_.topLeftCorner(n_, n_); }

 private:
  void reset();
  StateLayout layout_;
  InsSiteTerms site_;
  NoiseModel noise_;
  int n_ = 0, m_ = 0;     // navigation states, states after them (coefficients, base attitude)
  int coefficients_ = 0;  // coefficient states (the first of the m_)
  std::vector<int> coefficient_catalog_;  // catalog index of each coefficient state, in order
  Eigen::VectorXd wander_;                // per coefficient state: random-walk density (SI^2/s)
  NavMatrix Phi_nn_, Q_nn_, work_nn_, half_nn_;
  Eigen::Matrix<double, kMaxNavStates, kMaxNavStates> A_;  // column-major: ins_error_matrix()
  // The transition from the coefficients and work buffers of its products.
  NavCoefficientMatrix Phi_nc_, half_nc_, work_nc_;
  Eigen::MatrixXd work_T_;      // propagate(): the navigation rows of Phi P
  int delay_column_ = -1;       // the time delay's coefficient state (after n_), or -1
  int wander_column_ = -1;      // the bias wander's first state (after n_), or -1
  NavCoefficientMatrix B_sum_;  // flush(): the coupling's integral over the substep
  // The substep's integrals of the Jacobian and of the attitude, and the model's inverses.
  ImuErrorModel::JacobianColumns J_sum_;
  Eigen::Matrix3d C_sum_ = Eigen::Matrix3d::Zero();
  ImuErrorModel::LinearInverses inverses_;
  // The substep so far: its length and the integral of the specific force in n.
  double substep_ = 0.0;
  Eigen::Vector3d f_n_sum_ = Eigen::Vector3d::Zero();
  // The non-zero entries of A h of the substep (the INS error matrix is sparse: products with
  // it cost its entries, not 81 multiplications per column).
  int nonzero_ = 0;
  int nz_row_[kMaxNavStates * kMaxNavStates] = {};
  int nz_col_[kMaxNavStates * kMaxNavStates] = {};
  double nz_value_[kMaxNavStates * kMaxNavStates] = {};
  /// out = in + scale A h in, rows of `in` combined by the non-zero entries.
  template <class Matrix>
  void step_product(const Matrix& in, Matrix& out, double scale = 1.0) const;
  /// out = Phi_h in (second order in A h), `half` a work buffer.
  template <class Matrix>
  void transition_product(const Matrix& in, Matrix& half, Matrix& out) const;
  ImuErrorModel::JacobianColumns J_;
  double accumulated_ = 0.0;
};

}  // namespace sinscal
