#include "filter/installation/installation.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "models/attitude.hpp"

namespace sinscal {

namespace {
// Gauss-Newton of the alignment: iterations and the step (rad) below which it has converged;
// numerical derivatives with this step (rad or SI, every parameter is small).
constexpr int kAlignmentIterations = 20;
constexpr double kAlignmentConverged = 1e-12;
constexpr double kDerivativeStep = 1e-7;
constexpr int kParameters = 12;  // mounting, base, accelerometer bias, gyro bias
// An alignment needs the gravity direction in this many dwells at different attitudes.
constexpr int kMinAlignmentDwells = 3;
// Below this reciprocal condition the normal equations are singular (attitudes too alike).
constexpr double kMinRcond = 1e-14;

using Parameters = Eigen::Matrix<double, kParameters, 1>;

Eigen::VectorXd residuals(const std::vector<AlignmentDwell>& means, const Eigen::Vector3d& f_n,
                          const Eigen::Vector3d& omega_ie_n, double accel_sigma, double gyro_sigma,
                          const Parameters& p) {
  const Eigen::Matrix3d C_p_b = dcm_from_rotvec(p.segment<3>(0)).transpose();
  const Eigen::Matrix3d C_n_base = dcm_from_rotvec(p.segment<3>(3)).transpose();
  Eigen::VectorXd r(6 * static_cast<int>(means.size()));
  for (std::size_t k = 0; k < means.size(); ++k) {
    const Eigen::Matrix3d C = C_p_b * means[k].C_b_n_known.transpose() * C_n_base;
    const int i = 6 * static_cast<int>(k);
    r.segment<3>(i) = (means[k].f_b - C * f_n - p.segment<3>(6)) / accel_sigma;
    r.segment<3>(i + 3) = (means[k].omega_b - C * omega_ie_n - p.segment<3>(9)) / gyro_sigma;
  }
  return r;
}
}  // namespace

std::vector<AlignmentDwell> dwell_means(SampleSource& source, const PlanTimeline& timeline,
                                        double time_offset, double margin) {
  std::vector<AlignmentDwell> out;
  for (const auto& d : timeline.dwells) {
    AlignmentDwell m;
    m.dwell = d.index;
    m.C_b_n_known = d.C_b_n_known;
    out.push_back(m);
  }
  ImuSample s;
  std::size_t k = 0;
  while (k < timeline.dwells.size() && source.next(s)) {
    const double t = s.t - 0.5 * s.dt - time_offset;
    while (k < timeline.dwells.size() && t > timeline.dwells[k].t_end - margin) ++k;
    if (k == timeline.dwells.size() || t < timeline.dwells[k].t_start + margin) continue;
    out[k].f_b += s.dv_b / s.dt;
    out[k].omega_b += s.dtheta_b / s.dt;
    ++out[k].samples;
  }
  std::vector<AlignmentDwell> kept;
  for (auto& m : out)
    if (m.samples > 0) {
      m.f_b /= m.samples;
      m.omega_b /= m.samples;
      kept.push_back(m);
    }
  return kept;
}

Alignment align(const std::vector<AlignmentDwell>& means, const Site& site, double accel_sigma,
                double gyro_sigma) {
  Alignment a;
  a.dwells = static_cast<int>(means.size());
  if (a.dwells < kMinAlignmentDwells || !(accel_sigma > 0.0) || !(gyro_sigma > 0.0)) return a;
  const Earth& earth = Earth::wgs84();
  const Eigen::Vector3d f_n = -earth.gravity_n(site.lat_rad, site.h_m);
  const Eigen::Vector3d omega_ie_n = earth.omega_ie_n(site.lat_rad);
  auto r_of = [&](const Parameters& p) {
    return residuals(means, f_n, omega_ie_n, accel_sigma, gyro_sigma, p);
  };
  Parameters p = Parameters::Zero();
  Eigen::MatrixXd J(6 * a.dwells, kParameters);
  Eigen::Matrix<double, kParameters, kParameters> N;
  Eigen::VectorXd r;
  for (int it = 0; it < kAlignmentIterations; ++it) {
    r = r_of(p);
    for (int j = 0; j < kParameters; ++j) {
      Parameters q = p;
      q(j) += kDerivativeStep;
      J.col(j) = (r_of(q) - r) / kDerivativeStep;
    }
    N = J.transpose() * J;
    const Eigen::LDLT<Eigen::Matrix<double, kParameters, kParameters>> ldlt(N);
    if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > kMinRcond)) return a;
    const Parameters step = ldlt.solve(-J.transpose() * r);
    p += step;
    if (step.cwiseAbs().maxCoeff() < kAlignmentConverged) break;
  }
  r = r_of(p);
  const int dof = 6 * a.dwells - kParameters;
  const double scale = dof > 0 ? std::max(1.0, r.squaredNorm() / dof) : 1.0;
  const Eigen::Matrix<double, kParameters, kParameters> cov = scale * N.inverse();
  a.valid = p.allFinite();
  a.mounting_b = p.segment<3>(0);
  a.base_n = p.segment<3>(3);
  a.mounting_sigma_b = cov.diagonal().segment<3>(0).cwiseSqrt();
  a.base_sigma_n = cov.diagonal().segment<3>(3).cwiseSqrt();
  return a;
}

Eigen::Vector3d mounting_of(const ImuErrorModel& model) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(model.accel.linear(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU() * svd.matrixV().transpose();
  return rotvec_from_dcm(U.transpose());
}

namespace {
// The sigma of m_i = (M_jk - M_kj) / 2 from the covariance P, `index` giving the row of a
// misalignment in P (-1: not there).
Eigen::Vector3d antisymmetric_sigma(const std::function<int(std::size_t catalog)>& index,
                                    const Eigen::MatrixXd& P) {
  auto state = [&](const char* pair) {
    const std::string name = std::string("accel.misalignment.") + pair;
    const auto& cat = coefficient_catalog();
    for (std::size_t c = 0; c < cat.size(); ++c)
      if (cat[c].name == name) return index(c);
    return -1;
  };
  // m_i = (M_jk - M_kj) / 2 for (i, j, k) cyclic.
  const char* plus[3] = {"yz", "zx", "xy"};
  const char* minus[3] = {"zy", "xz", "yx"};
  Eigen::Vector3d sigma = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    const int a = state(plus[i]), b = state(minus[i]);
    double var = 0.0;
    if (a >= 0) var += P(a, a);
    if (b >= 0) var += P(b, b);
    if (a >= 0 && b >= 0) var -= 2.0 * P(a, b);
    sigma(i) = 0.5 * std::sqrt(std::max(var, 0.0));
  }
  return sigma;
}
}  // namespace

Eigen::Vector3d mounting_sigma(const StateLayout& layout, const Eigen::MatrixXd& P) {
  return antisymmetric_sigma([&](std::size_t c) { return layout.state_of[c]; }, P);
}

Eigen::Vector3d mounting_sigma(const std::vector<int>& parameters, const Eigen::MatrixXd& cov) {
  return antisymmetric_sigma(
      [&](std::size_t c) {
        const auto it = std::find(parameters.begin(), parameters.end(), static_cast<int>(c));
        return it == parameters.end() ? -1 : static_cast<int>(it - parameters.begin());
      },
      cov);
}

}  // namespace sinscal
