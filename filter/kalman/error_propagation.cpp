#include "filter/kalman/error_propagation.hpp"

#include <cmath>

#include "models/coefficient_families.hpp"

namespace sinscal {

namespace {
// Density (SI^2/s) of the random walk that the bias noise of a triad drives: bias instability (a
// Gauss-Markov process of sigma b and correlation time tau, driven by white noise of density
// 2 b^2 / tau) plus the rate / acceleration random walk. Without the decay this is conservative
// over runs longer than tau.
double bias_wander(const TriadNoise& tn) {
  const double gm = tn.correlation_time > 0.0
                        ? 2.0 * tn.bias_instability * tn.bias_instability / tn.correlation_time
                        : 0.0;
  return gm + tn.random_walk * tn.random_walk;
}
}  // namespace

ErrorPropagator::ErrorPropagator(const StateLayout& layout, const InsSiteTerms& site,
                                 const NoiseModel& noise)
    : layout_(layout),
      site_(site),
      noise_(noise),
      n_(layout.nav_size),
      m_(layout.size - n_),
      coefficients_(layout.coefficient_states()) {
  if (n_ > kMaxNavStates || m_ > kMaxCoefficients)
    throw std::logic_error("state layout larger than the filter's fixed storage");
  wander_ = Eigen::VectorXd::Zero(m_);
  for (const auto& cb : layout_.coefficients) {
    const CoefficientFamily& f = coefficient_family_info(cb.family);
    for (int k = 0; k < cb.block.size; ++k) {
      coefficient_catalog_.push_back(cb.catalog[static_cast<std::size_t>(k)]);
      if (f.wanders_with_bias_noise) {
        const TriadNoise& tn = f.output == FamilyOutput::Gyro ? noise_.gyro : noise_.accel;
        // With the wander's states the bias instability is theirs; the random walk stays.
        wander_(cb.block.index - n_ + k) =
            StateLayout::on(layout_.wander) ? tn.random_walk * tn.random_walk : bias_wander(tn);
      }
    }
  }
  A_.setZero();
  work_nc_.setZero(kMaxNavStates, m_);
  B_sum_.setZero(kMaxNavStates, m_);
  half_nc_.setZero(kMaxNavStates, m_);
  J_sum_.setZero(6, coefficients_);
  if (const auto* delay = layout_.block("time_delay")) delay_column_ = delay->block.index - n_;
  if (StateLayout::on(layout_.wander)) wander_column_ = layout_.wander.index - n_;
  reset();
}

template <class Matrix>
void ErrorPropagator::step_product(const Matrix& in, Matrix& out, double scale) const {
  out = in;
  for (int k = 0; k < nonzero_; ++k)
    out.row(nz_row_[k]) += (scale * nz_value_[k]) * in.row(nz_col_[k]);
}

template <class Matrix>
void ErrorPropagator::transition_product(const Matrix& in, Matrix& half, Matrix& out) const {
  // Phi_h X = X + A h (X + A h / 2 X): half holds X + A h / 2 X.
  step_product(in, half, 0.5);
  step_product(half, out);
  out += in - half;
}

void ErrorPropagator::reset() {
  Phi_nn_.setIdentity();
  Phi_nc_.setZero(kMaxNavStates, m_);
  Q_nn_.setZero();
  accumulated_ = 0.0;
}

void ErrorPropagator::step(const Eigen::Matrix3d& C, const KinematicSample& k,
                           const Eigen::Vector3d& f_dot, const ImuErrorModel& model,
                           const ImuErrorModel::LinearInverses& inverses, double dt,
                           const Eigen::Vector3d& f_n) {
  model.jacobian(k, f_dot, coefficient_catalog_, J_);
  J_sum_ += J_ * dt;
  C_sum_ += C * dt;
  inverses_ = inverses;
  f_n_sum_ += f_n * dt;
  substep_ += dt;
  accumulated_ += dt;
  if (substep_ >= kTransitionSubstep - 1e-9) flush();
}

void ErrorPropagator::flush() {
  if (!(substep_ > 0.0)) return;
  const double h = substep_;
  const Block& a = layout_.attitude;
  const Block& v = layout_.velocity;
  A_.setZero();
  ins_error_matrix(site_, f_n_sum_ / h, ErrorModelKind::Coupled, layout_.nav(), A_);
  nonzero_ = 0;
  for (int j = 0; j < kMaxNavStates; ++j)
    for (int i = 0; i < kMaxNavStates; ++i)
      if (A_(i, j) != 0.0) {
        nz_row_[nonzero_] = i;
        nz_col_[nonzero_] = j;
        nz_value_[nonzero_++] = A_(i, j) * h;
      }
  // Phi <- Phi_h Phi: X + A h (X + A h / 2 X).
  transition_product(Phi_nn_, half_nn_, work_nn_);
  Phi_nn_ = work_nn_;
  // The coefficient coupling's integral over the substep (the model and its inverses are constant
  // within it: the filter updates between substeps): B = [-C A_g^-1 J_g; C A_a^-1 J_a] with the
  // substep's mean attitude and Jacobian (during a turn at 15 deg/s the attitude moves 1.5 deg per
  // substep: the product of the means errs by the covariance of the two over it, below 1e-4 of
  // the column). Gyro errors rotate the attitude (phi' = -C dw_b), accelerometer errors add to the
  // velocity (dv' = C df_b); an output error J dtheta is an error A^-1 J dtheta of the compensated
  // input (A the triad's linear part as estimated: a mounting makes it a rotation of up to
  // degrees); the time delay acts on the compensated input already. The base attitude (after the
  // coefficients) does not enter the dynamics: its columns stay 0.
  const Eigen::Matrix3d C_mean = C_sum_ / h;
  const Eigen::Matrix3d C_gyro = C_mean * inverses_.gyro, C_accel = C_mean * inverses_.accel;
  B_sum_.setZero(kMaxNavStates, m_);
  B_sum_.block(a.index, 0, 3, coefficients_).noalias() = -C_gyro * J_sum_.topRows<3>();
  B_sum_.block(v.index, 0, v.size, coefficients_).noalias() =
      (C_accel * J_sum_.bottomRows<3>()).topRows(v.size);
  if (delay_column_ >= 0)
    B_sum_.block(v.index, delay_column_, v.size, 1).noalias() =
        (C_mean * J_sum_.bottomRows<3>().col(delay_column_)).topRows(v.size);
  // The bias wander acts on the compensated inputs (its states are in their axes): -C h on the
  // attitude, C h on the velocity. Its decay within the update interval (h / tau, 1 % at 1 s
  // against a MEMS unit's 100 s) is left out of the coupling; propagate() applies it to P.
  if (wander_column_ >= 0) {
    B_sum_.block(a.index, wander_column_, 3, 3) = -C_mean * h;
    B_sum_.block(v.index, wander_column_ + 3, v.size, 3) = (C_mean * h).topRows(v.size);
  }
  J_sum_.setZero();
  C_sum_.setZero();
  // Phi_nc <- Phi_h Phi_nc + (I + A h / 2) int B = X + S + A h (X + S / 2 + A h / 2 X).
  step_product(Phi_nc_, half_nc_, 0.5);
  half_nc_ += 0.5 * B_sum_;
  step_product(half_nc_, work_nc_);
  work_nc_ += Phi_nc_ + B_sum_ - half_nc_;
  Phi_nc_ = work_nc_;
  // Q <- Phi_h Q Phi_h^T + (I + A h / 2) q h (I + A h / 2)^T.
  auto both_sides = [this](NavMatrix& M, bool second_order) {
    // M <- T M T^T with T = Phi_h (second order) or I + A h / 2.
    for (int side = 0; side < 2; ++side) {
      if (second_order) {
        transition_product(M, half_nn_, work_nn_);
      } else {
        step_product(M, work_nn_, 0.5);
      }
      M = work_nn_.transpose();
    }
  };
  NavMatrix q = NavMatrix::Zero();
  q.diagonal().segment(a.index, 3).array() = noise_.gyro.white * noise_.gyro.white * h;
  q.diagonal().segment(v.index, v.size).array() = noise_.accel.white * noise_.accel.white * h;
  both_sides(Q_nn_, true);
  both_sides(q, false);
  Q_nn_ += q;
  f_n_sum_.setZero();
  substep_ = 0.0;
}

void ErrorPropagator::propagate(Eigen::MatrixXd& P) {
  flush();
  const int n = n_, m = m_;
  // P <- Phi P Phi^T + Q with Phi = [[Phi_nn, Phi_nc], [0, I]]: the block after the navigation
  // states is unchanged (but for the wander), the navigation rows become T = Phi [P_n; P_c]
  // (top rows), and their block with themselves T_n Phi_nn^T + T_c Phi_nc^T.
  const auto Phi_nn = Phi_nn_.topLeftCorner(n, n);
  const auto Phi_nc = Phi_nc_.topRows(n);
  work_T_.noalias() = Phi_nn * P.topRows(n);
  work_T_.noalias() += Phi_nc * P.bottomRows(m);
  Eigen::MatrixXd& T = work_T_;
  P.topRightCorner(n, m) = T.rightCols(m);
  P.bottomLeftCorner(m, n) = T.rightCols(m).transpose();
  NavMatrix top;
  top.topLeftCorner(n, n).noalias() = T.leftCols(n) * Phi_nn.transpose();
  top.topLeftCorner(n, n).noalias() += T.rightCols(m) * Phi_nc.transpose();
  top.topLeftCorner(n, n) += Q_nn_.topLeftCorner(n, n);
  P.topLeftCorner(n, n) = 0.5 * (top.topLeftCorner(n, n) + top.topLeftCorner(n, n).transpose());
  P.diagonal().tail(m) += wander_ * accumulated_;
  if (wander_column_ >= 0) {
    // The Gauss-Markov wander: Phi's block on it is exp(-h / tau) (not I), so its rows and
    // columns scale by it, and its stationary variance b^2 refills what the decay took.
    for (int i = 0; i < 6; ++i) {
      const TriadNoise& tn = i < 3 ? noise_.gyro : noise_.accel;
      if (!(tn.correlation_time > 0.0)) continue;
      const double d = std::exp(-accumulated_ / tn.correlation_time);
      const int s = n + wander_column_ + i;
      P.row(s) *= d;
      P.col(s) *= d;
      P(s, s) += tn.bias_instability * tn.bias_instability * (1.0 - d * d);
    }
  }
  reset();
}

}  // namespace sinscal
