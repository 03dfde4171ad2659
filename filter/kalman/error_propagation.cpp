#include "filter/kalman/error_propagation.hpp"

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
      if (f.wanders_with_bias_noise)
        wander_(cb.block.index - n_ + k) =
            bias_wander(f.output == FamilyOutput::Gyro ? noise_.gyro : noise_.accel);
    }
  }
  A_.setZero();
  B_.setZero(kMaxNavStates, m_);
  work_nc_.setZero(kMaxNavStates, m_);
  reset();
}

template <class Matrix>
void ErrorPropagator::step_product(const Matrix& in, Matrix& out) const {
  out = in;
  for (int k = 0; k < nonzero_; ++k) out.row(nz_row_[k]) += nz_value_[k] * in.row(nz_col_[k]);
}

void ErrorPropagator::reset() {
  Phi_nn_.setIdentity();
  Phi_nc_.setZero(kMaxNavStates, m_);
  Q_nn_.setZero();
  accumulated_ = 0.0;
}

void ErrorPropagator::step(const Eigen::Matrix3d& C, const KinematicSample& k,
                           const Eigen::Vector3d& f_dot, const ImuErrorModel& model, double dt,
                           const Eigen::Vector3d& f_n) {
  const Block& a = layout_.attitude;
  const Block& v = layout_.velocity;
  A_.setZero();
  ins_error_matrix(site_, f_n, ErrorModelKind::Coupled, layout_.nav(), A_);
  model.jacobian(k, f_dot, coefficient_catalog_, J_);
  // Coefficient coupling: gyro errors rotate the attitude (phi' = -C dw_b), accelerometer errors
  // add to the velocity (dv' = C df_b).
  // The base attitude (after the coefficients) does not enter the dynamics: its columns stay 0.
  // An output error J dtheta is an error A^-1 J dtheta of the compensated input (A the triad's
  // linear part as estimated: a mounting makes it a rotation of up to degrees); the time delay
  // acts on the compensated input already.
  const Eigen::Matrix3d C_gyro = C * model.gyro.linear().inverse();
  const Eigen::Matrix3d C_accel = C * model.accel.linear().inverse();
  B_.block(a.index, 0, 3, coefficients_).noalias() = -(C_gyro.lazyProduct(J_.topRows<3>()));
  B_.block(v.index, 0, v.size, coefficients_).noalias() =
      (C_accel.lazyProduct(J_.bottomRows<3>())).topRows(v.size);
  if (const auto* delay = layout_.block("time_delay"))
    B_.block(v.index, delay->block.index - n_, v.size, 1).noalias() =
        (C * J_.bottomRows<3>().col(delay->block.index - n_)).topRows(v.size);
  nonzero_ = 0;
  for (int j = 0; j < kMaxNavStates; ++j)
    for (int i = 0; i < kMaxNavStates; ++i)
      if (A_(i, j) != 0.0) {
        nz_row_[nonzero_] = i;
        nz_col_[nonzero_] = j;
        nz_value_[nonzero_++] = A_(i, j) * dt;
      }
  // Phi <- (I + A dt) Phi, Phi_nc <- (I + A dt) Phi_nc + B dt.
  step_product(Phi_nn_, work_nn_);
  Phi_nn_ = work_nn_;
  step_product(Phi_nc_, work_nc_);
  Phi_nc_ = work_nc_ + B_ * dt;
  // Noise entered earlier in the interval is carried by the later steps (into position, and from
  // attitude into velocity): Q <- (I + A dt) Q (I + A dt)^T + q dt.
  step_product(Q_nn_, work_nn_);
  const NavMatrix left_transposed = work_nn_.transpose();
  step_product(left_transposed, work_nn_);
  Q_nn_ = work_nn_.transpose();
  Q_nn_.diagonal().segment(a.index, 3).array() += noise_.gyro.white * noise_.gyro.white * dt;
  Q_nn_.diagonal().segment(v.index, v.size).array() += noise_.accel.white * noise_.accel.white * dt;
  accumulated_ += dt;
}

void ErrorPropagator::propagate(Eigen::MatrixXd& P) {
  const int n = n_, m = m_;
  // P <- Phi P Phi^T + Q with Phi = [[Phi_nn, Phi_nc], [0, I]].
  Eigen::MatrixXd T = P;
  const Eigen::MatrixXd Phi_nn = Phi_nn_.topLeftCorner(n, n), Phi_nc = Phi_nc_.topRows(n);
  T.topRows(n) = Phi_nn * P.topRows(n) + Phi_nc * P.bottomRows(m);
  Eigen::MatrixXd Pn = T;
  Pn.leftCols(n) = T.leftCols(n) * Phi_nn.transpose() + T.rightCols(m) * Phi_nc.transpose();
  Pn.topLeftCorner(n, n) += Q_nn_.topLeftCorner(n, n);
  Pn.diagonal().tail(m) += wander_ * accumulated_;
  P = 0.5 * (Pn + Pn.transpose());
  reset();
}

}  // namespace sinscal
