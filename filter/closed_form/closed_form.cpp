#include "filter/closed_form/closed_form.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>
#include <utility>

#include "filter/strapdown/dwell_navigation.hpp"
#include "models/attitude.hpp"
#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "rig/io/log_io.hpp"
#include "rig/plan.hpp"

namespace sinscal {

namespace {
// Input indices within u.
constexpr int kDfN = 0, kDfE = 1, kDfD = 2, kDwN = 3, kDwE = 4, kDwD = 5;
// Observed rows of the INS error state used by each channel.
constexpr int kRowPhiN = kInsNav.attitude.index + 0, kRowPhiE = kInsNav.attitude.index + 1,
              kRowPhiD = kInsNav.attitude.index + 2, kRowVN = kInsNav.velocity.index + 0,
              kRowVE = kInsNav.velocity.index + 1, kRowVD = kInsNav.velocity.index + 2;

InsState observed_state(const NavError& e) {
  InsState x;
  x << e.phi_n, e.dv_n, e.dp_n;
  return x;
}

/// Normal equations of one dwell's fit, per observed row (constant memory).
struct RowSums {
  double dd = 0.0;
  Vector6d gd = Vector6d::Zero();
  Matrix6d gg = Matrix6d::Zero();
};

struct DwellAccumulator {
  PlanDwell dwell;
  bool started = false;
  NavError prev;
  NavError at_point;
  double point_distance = 1e300;
  std::size_t steps = 0;
  std::map<int, RowSums> rows;
  // The samples' temperatures (deg C): sums for the means, first and last for the rate.
  std::size_t temperatures = 0;
  double sum_accel_c = 0.0, sum_gyro_c = 0.0;
  double t_first = 0.0, gyro_first_c = 0.0, t_last = 0.0, gyro_last_c = 0.0;
};

void add_temperature(DwellAccumulator& a, const ImuSample& s) {
  if (!s.has_temperature) return;
  if (a.temperatures == 0) {
    a.t_first = s.t;
    a.gyro_first_c = s.gyro_temperature_c;
  }
  ++a.temperatures;
  a.sum_accel_c += s.accel_temperature_c;
  a.sum_gyro_c += s.gyro_temperature_c;
  a.t_last = s.t;
  a.gyro_last_c = s.gyro_temperature_c;
}

std::vector<int> rows_of(const ChannelSet& c) {
  std::vector<int> r;
  if (c.north) r.insert(r.end(), {kRowVN, kRowPhiE});
  if (c.east) r.insert(r.end(), {kRowVE, kRowPhiN});
  if (c.vertical) r.push_back(kRowVD);
  if (c.heading) r.push_back(kRowPhiD);
  return r;
}

bool is_velocity_row(int r) {
  return r >= kInsNav.velocity.index && r < kInsNav.velocity.index + 3;
}

}  // namespace

std::array<bool, 6> ChannelSet::inputs() const {
  std::array<bool, 6> in{};
  in[kDfN] = in[kDwE] = north;
  in[kDfE] = in[kDwN] = east;
  in[kDfD] = vertical;
  in[kDwD] = heading;
  return in;
}

namespace {

void check_stage1(const std::vector<PlanDwell>& dwells, const Stage1Options& o) {
  if (!(o.arw > 0.0) || !(o.vrw > 0.0))
    throw std::invalid_argument(
        "stage 1 needs the gyro and accelerometer white-noise densities (arw, vrw) for its weights "
        "and sigmas: give a sensor profile in the session or set them");
  for (const auto& d : dwells)
    if (d.t_end - d.t_start < o.min_dwell)
      throw std::invalid_argument("dwell " + std::to_string(d.index) + " (" + d.label + ") lasts " +
                                  std::to_string(d.t_end - d.t_start) + " s, shorter than the " +
                                  std::to_string(o.min_dwell) + " s stage 1 needs");
}

// Navigates through every dwell and accumulates, per dwell and channel row, the sums of the
// one-step error-dynamics residuals (delta = x1 - Phi x0) and of the input rows (Gamma).
std::map<int, DwellAccumulator> accumulate_dwells(SampleSource& source,
                                                  const std::vector<PlanDwell>& dwells,
                                                  const Site& site, const Stage1Options& o,
                                                  double time_offset, const std::string& input) {
  const Earth& earth = Earth::wgs84();
  const InsErrorModel model = InsErrorModel::at(site, o.model, earth);
  const Eigen::Vector3d f_n = -earth.gravity_n(site.lat_rad, site.h_m);
  const std::vector<int> rows = rows_of(o.channels);
  InsF Phi;
  InsB Gamma;
  double h_cached = -1.0;

  std::map<int, DwellAccumulator> acc;
  DwellNavOptions nav_opt;
  nav_opt.output_interval = 0.0;
  nav_opt.time_offset = time_offset;
  nav_opt.input = input;
  nav_opt.strapdown = o.strapdown;
  DwellNavigation nav(dwells, site, nav_opt);
  nav.run(source, [&](const DwellNavRow& r) {
    DwellAccumulator& a = acc[r.dwell];
    if (r.sample != nullptr) add_temperature(a, *r.sample);
    if (!a.started) {
      a.started = true;
      a.dwell = *r.info;
      a.prev = r.error;
      return;
    }
    const double h = r.error.t - a.prev.t;
    if (h <= 0.0) return;
    if (std::abs(h - h_cached) > 1e-9 * h) {
      model.discretize(h, Phi, Gamma);
      h_cached = h;
    }
    const InsState x0 = observed_state(a.prev), x1 = observed_state(r.error);
    InsState delta = x1 - Phi * x0;
    InsB Gamma_k = Gamma;
    if (o.model == ErrorModelKind::Coupled) {
      // Second-order attitude terms, exact because phi is observed: the specific force is
      // rotated by R(-phi) (not I - [phi x]), and the inputs act in the computed frame,
      // (I - [phi x]) df_n and -(I - [phi x]) dw_n. The fit stays linear in u.
      const Eigen::Vector3d phi = 0.5 * (a.prev.phi_n + r.error.phi_n);
      delta.segment<3>(kInsNav.velocity.index) -=
          h * ((dcm_from_rotvec(-phi) - Eigen::Matrix3d::Identity()) * f_n - f_n.cross(phi));
      Gamma_k.block<3, 3>(kInsNav.velocity.index, ins_input::kAccel.index) -= h * skew(phi);
      Gamma_k.block<3, 3>(kInsNav.attitude.index, ins_input::kGyro.index) += h * skew(phi);
    }
    for (int row : rows) {
      RowSums& s = a.rows[row];
      const Vector6d g = Gamma_k.row(row).transpose();
      s.dd += delta(row) * delta(row);
      s.gd += g * delta(row);
      s.gg += g * g.transpose();
    }
    ++a.steps;
    const double target = o.point_time > 0.0 ? o.point_time : a.dwell.t_end - a.dwell.t_start;
    if (std::abs(r.error.t - target) <= a.point_distance) {
      a.point_distance = std::abs(r.error.t - target);
      a.at_point = r.error;
    }
    a.prev = r.error;
  });

  return acc;
}

// The paper's eq. 5 (uncoupled Schuler solutions at one time t).
void point_inputs(const DwellAccumulator& a, const Stage1Options& o, const Site& site,
                  EquivalentInputs& e) {
  const Earth& earth = Earth::wgs84();
  const double g = earth.gravity_n(site.lat_rad, site.h_m).norm();
  const double R_N = earth.radius_meridian(site.lat_rad) + site.h_m;
  const double R_E = earth.radius_transverse(site.lat_rad) + site.h_m;
  const NavError& x = a.at_point;
  const double t = x.t;
  auto channel = [&](double R, double& cot_half, double& ws) {
    ws = std::sqrt(g / R);
    cot_half = 0.5 * ws * std::sin(ws * t) / (1.0 - std::cos(ws * t));
  };
  double k_n, ws_n, k_e, ws_e;
  channel(R_N, k_n, ws_n);
  channel(R_E, k_e, ws_e);
  const double dtheta = x.phi_n.y(), dgamma = x.phi_n.x();
  // north: dfn = -g/2 dtheta + k dVn;  dwe(paper) = ws^2/(2g) dVn + k dtheta
  e.u(kDfN) = -0.5 * g * dtheta + k_n * x.dv_n.x();
  e.u(kDwE) = -(0.5 * ws_n * ws_n / g * x.dv_n.x() + k_n * dtheta);
  // east: dfe = g/2 dgamma + k dVe;  dwn(paper) = -ws^2/(2g) dVe + k dgamma
  e.u(kDfE) = 0.5 * g * dgamma + k_e * x.dv_n.y();
  e.u(kDwN) = -(-0.5 * ws_e * ws_e / g * x.dv_n.y() + k_e * dgamma);
  e.u(kDfD) = x.dv_n.z() / t;
  e.u(kDwD) = -x.phi_n.z() / t;
  // Sigma: the errors at t carry random walks of variance VRW^2 t and ARW^2 t.
  const double vv = o.vrw * o.vrw * t, va = o.arw * o.arw * t;
  e.cov(kDfN, kDfN) = 0.25 * g * g * va + k_n * k_n * vv;
  e.cov(kDwE, kDwE) = std::pow(0.5 * ws_n * ws_n / g, 2) * vv + k_n * k_n * va;
  e.cov(kDfN, kDwE) = e.cov(kDwE, kDfN) = -(-0.5 * g * k_n * va + k_n * 0.5 * ws_n * ws_n / g * vv);
  e.cov(kDfE, kDfE) = 0.25 * g * g * va + k_e * k_e * vv;
  e.cov(kDwN, kDwN) = std::pow(0.5 * ws_e * ws_e / g, 2) * vv + k_e * k_e * va;
  e.cov(kDfE, kDwN) = e.cov(kDwN, kDfE) = -(0.5 * g * k_e * va - k_e * 0.5 * ws_e * ws_e / g * vv);
  e.cov(kDfD, kDfD) = o.vrw * o.vrw / t;
  e.cov(kDwD, kDwD) = o.arw * o.arw / t;
}

// Weighted least squares of the inputs over the whole dwell, with the residual chi-square.
void fit_inputs(const DwellAccumulator& a, const Stage1Options& o, EquivalentInputs& e) {
  const std::array<bool, 6> sel = o.channels.inputs();
  const double T = e.duration;
  Matrix6d N = Matrix6d::Zero();
  Vector6d b = Vector6d::Zero();
  const double h = T / static_cast<double>(std::max<std::size_t>(a.steps, 1));
  auto weight = [&](int row) {
    return 1.0 / ((is_velocity_row(row) ? o.vrw * o.vrw : o.arw * o.arw) * h);
  };
  for (auto& [row, s] : a.rows) {
    N += weight(row) * s.gg;
    b += weight(row) * s.gd;
  }
  std::vector<int> idx;
  for (int i = 0; i < 6; ++i)
    if (sel[i]) idx.push_back(i);
  const int m = static_cast<int>(idx.size());
  Eigen::MatrixXd Ns(m, m);
  Eigen::VectorXd bs(m);
  for (int i = 0; i < m; ++i) {
    bs(i) = b(idx[i]);
    for (int j = 0; j < m; ++j) Ns(i, j) = N(idx[i], idx[j]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(Ns);
  const Eigen::VectorXd us = ldlt.solve(bs);
  const Eigen::MatrixXd cs = ldlt.solve(Eigen::MatrixXd::Identity(m, m));
  for (int i = 0; i < m; ++i) {
    e.u(idx[i]) = us(i);
    for (int j = 0; j < m; ++j) e.cov(idx[i], idx[j]) = cs(i, j);
  }
  double chi2 = 0.0, ssv = 0.0, ssa = 0.0;
  std::size_t nv = 0, na = 0;
  for (auto& [row, s] : a.rows) {
    const double rss = std::max(0.0, s.dd - 2.0 * e.u.dot(s.gd) + e.u.dot(s.gg * e.u));
    chi2 += weight(row) * rss;
    if (is_velocity_row(row)) {
      ssv += rss;
      nv += a.steps;
    } else {
      ssa += rss;
      na += a.steps;
    }
  }
  e.rms_velocity = nv ? std::sqrt(ssv / static_cast<double>(nv)) : 0.0;
  e.rms_attitude = na ? std::sqrt(ssa / static_cast<double>(na)) : 0.0;
  const double dof = static_cast<double>(nv + na) - m;
  e.chi2_per_dof = dof > 0 ? chi2 / dof : 0.0;
}

}  // namespace

Stage1Options default_stage1(const SensorProfile* profile) {
  Stage1Options o;
  o.model = ErrorModelKind::Coupled;
  o.channels = ChannelSet{true, true, true, true};
  if (profile) {
    o.arw = profile->noise.gyro.white;
    o.vrw = profile->noise.accel.white;
  }
  return o;
}

std::vector<EquivalentInputs> run_stage1(SampleSource& source, const std::vector<PlanDwell>& dwells,
                                         const Site& site, const Stage1Options& o,
                                         double time_offset, const std::string& input) {
  check_stage1(dwells, o);
  const std::map<int, DwellAccumulator> acc =
      accumulate_dwells(source, dwells, site, o, time_offset, input);
  std::vector<EquivalentInputs> out;
  for (const auto& [index, a] : acc) {
    EquivalentInputs e;
    e.dwell = a.dwell;
    e.duration = a.prev.t;
    e.samples = a.steps;
    e.estimated = o.channels.inputs();
    if (a.temperatures > 0) {
      const auto n = static_cast<double>(a.temperatures);
      e.has_temperature = true;
      e.accel_temperature_c = a.sum_accel_c / n;
      e.gyro_temperature_c = a.sum_gyro_c / n;
      e.gyro_temperature_rate =
          a.t_last > a.t_first ? (a.gyro_last_c - a.gyro_first_c) / (a.t_last - a.t_first) : 0.0;
    }
    if (o.method == Stage1Method::Point)
      point_inputs(a, o, site, e);
    else
      fit_inputs(a, o, e);
    out.push_back(e);
  }
  return out;
}

std::vector<int> stage2_parameters() {
  std::vector<int> out;
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i)
    if (coefficient_family_info(cat[i].family).base) out.push_back(static_cast<int>(i));
  return out;
}

Eigen::Matrix<double, 6, Eigen::Dynamic> equivalent_input_map(const Eigen::Matrix3d& C,
                                                              const Site& site,
                                                              const std::vector<int>& parameters,
                                                              double t,
                                                              const KinematicSample* temperature) {
  const Earth& earth = Earth::wgs84();
  KinematicSample k;
  if (temperature != nullptr) {
    k.accel_dtemp = temperature->accel_dtemp;
    k.gyro_dtemp = temperature->gyro_dtemp;
    k.gyro_dtemp_rate = temperature->gyro_dtemp_rate;
  }
  k.f_ib_b = -(C.transpose() * earth.gravity_n(site.lat_rad, site.h_m));
  k.omega_ib_b = C.transpose() * earth.omega_ie_n(site.lat_rad);
  k.t = t;
  ImuErrorModel::JacobianColumns J;
  ImuErrorModel{}.jacobian(k, Eigen::Vector3d::Zero(), parameters, J);
  Eigen::Matrix<double, 6, Eigen::Dynamic> H(6, J.cols());
  H.middleRows<3>(ins_input::kAccel.index) = C * J.bottomRows<3>();
  H.middleRows<3>(ins_input::kGyro.index) = C * J.topRows<3>();
  return H;
}

Eigen::Matrix<double, 6, Eigen::Dynamic> equivalent_input_map(const EquivalentInputs& in,
                                                              const Site& site,
                                                              const std::vector<int>& parameters,
                                                              double reference_temperature_c) {
  KinematicSample temperature;
  if (in.has_temperature) {
    temperature.accel_dtemp = in.accel_temperature_c - reference_temperature_c;
    temperature.gyro_dtemp = in.gyro_temperature_c - reference_temperature_c;
    temperature.gyro_dtemp_rate = in.gyro_temperature_rate;
  }
  return equivalent_input_map(in.dwell.C_b_n_known, site, parameters,
                              0.5 * (in.dwell.t_start + in.dwell.t_end), &temperature);
}

Matrix6d stage2_input_covariance(const EquivalentInputs& in, const Site& site,
                                 const TableAttitudeError& table) {
  const Earth& earth = Earth::wgs84();
  const Eigen::Vector3d f_n = -earth.gravity_n(site.lat_rad, site.h_m);
  const Eigen::Vector3d w_ie = earth.omega_ie_n(site.lat_rad);
  // A table attitude error eps (truth relative to the plan) aliases into the inputs as
  // df_n += f_n x eps, dw_n += omega_ie_n x eps.
  Eigen::Matrix<double, 6, 3> S;
  S.middleRows<3>(ins_input::kAccel.index) = skew(f_n);
  S.middleRows<3>(ins_input::kGyro.index) = skew(w_ie);
  return in.cov + S * table.covariance_n() * S.transpose();
}

namespace {

// The time a dwell's input averages over: the dwell's middle, the time navigated.
std::pair<double, double> averaged_interval(const EquivalentInputs& in) {
  const double mid = 0.5 * (in.dwell.t_start + in.dwell.t_end);
  const double half = 0.5 * (in.duration > 0.0 ? in.duration : in.dwell.t_end - in.dwell.t_start);
  return {mid - half, mid + half};
}

// Covariance of the means over [a0, a1] and [b0, b1] (a first, disjoint, or the same interval)
// of one axis' bias wander: a Gauss-Markov process (stationary sigma, correlation time tau) plus
// a random walk of density q from t = 0.
double mean_bias_covariance(std::pair<double, double> a, std::pair<double, double> b,
                            const TriadNoise& n) {
  if (a.first > b.first) std::swap(a, b);
  const double ta = std::max(a.second - a.first, 1e-9), tb = std::max(b.second - b.first, 1e-9);
  const bool same = a == b;
  double c = 0.0;
  if (n.bias_instability > 0.0 && n.correlation_time > 0.0) {
    const double tau = n.correlation_time, s2 = n.bias_instability * n.bias_instability;
    if (same) {
      const double x = ta / tau;  // (2 / x^2) (x - 1 + e^-x): the variance of a mean over x tau
      c += s2 * (x < 1e-4 ? 1.0 - x / 3.0 : 2.0 * (x - 1.0 + std::exp(-x)) / (x * x));
    } else {
      const double gap = std::max(0.0, b.first - a.second);
      c += s2 * tau * tau * -std::expm1(-ta / tau) * -std::expm1(-tb / tau) * std::exp(-gap / tau) /
           (ta * tb);
    }
  }
  if (n.random_walk > 0.0) {  // cov(W(s), W(t)) = min(s, t)
    const double q2 = n.random_walk * n.random_walk;
    c +=
        q2 * (same ? std::max(0.0, a.first) + ta / 3.0 : std::max(0.0, 0.5 * (a.first + a.second)));
  }
  return c;
}

}  // namespace

Matrix6d stage2_wander_covariance(const EquivalentInputs& a, const EquivalentInputs& b,
                                  const NoiseModel& noise) {
  Matrix6d out = Matrix6d::Zero();
  const auto ia = averaged_interval(a), ib = averaged_interval(b);
  const Eigen::Matrix3d R = a.dwell.C_b_n_known * b.dwell.C_b_n_known.transpose();
  out.block<3, 3>(ins_input::kAccel.index, ins_input::kAccel.index) =
      mean_bias_covariance(ia, ib, noise.accel) * R;
  out.block<3, 3>(ins_input::kGyro.index, ins_input::kGyro.index) =
      mean_bias_covariance(ia, ib, noise.gyro) * R;
  return out;
}

Eigen::VectorXd parameter_vector(const ImuErrorModel& model, const std::vector<int>& parameters) {
  const Eigen::VectorXd all = model.vector();
  Eigen::VectorXd out(static_cast<Eigen::Index>(parameters.size()));
  for (std::size_t k = 0; k < parameters.size(); ++k)
    out(static_cast<Eigen::Index>(k)) = all(parameters[k]);
  return out;
}

namespace {
// Normal equations of stage 2 over every dwell, the table's attitude error in each dwell's
// weights; the residual's chi-square at the solution comes from sum(u^T W u) - b^T theta.
struct NormalEquations {
  Eigen::MatrixXd J;
  Eigen::VectorXd b;
  double uWu = 0.0;
  int inputs = 0;
};

// One dwell's rows of stage 2: its estimated inputs, their model columns and covariance.
struct DwellRows {
  std::vector<int> idx;  // which of the 6 inputs
  Eigen::MatrixXd H, R;
  Eigen::VectorXd u;
};

DwellRows stage2_rows(const EquivalentInputs& in, const Site& site, const Stage2Options& o, int n) {
  const int nc = static_cast<int>(o.parameters.size());
  const Earth& earth = Earth::wgs84();
  Eigen::Matrix<double, 6, Eigen::Dynamic> H(6, n);
  H.leftCols(nc) = equivalent_input_map(in, site, o.parameters, o.reference_temperature_c);
  // The base's error aliases as the table's does: df_n += f_n x d_base, dw_n += omega_ie_n x
  // d_base (f_n = -g_n).
  if (o.base_attitude) {
    H.block<3, 3>(ins_input::kAccel.index, nc) = skew(-earth.gravity_n(site.lat_rad, site.h_m));
    H.block<3, 3>(ins_input::kGyro.index, nc) = skew(earth.omega_ie_n(site.lat_rad));
  }
  const Matrix6d R = stage2_input_covariance(in, site, o.table);
  DwellRows d;
  for (int i = 0; i < 6; ++i)
    if (in.estimated[static_cast<std::size_t>(i)]) d.idx.push_back(i);
  const int m = static_cast<int>(d.idx.size());
  d.H.resize(m, n);
  d.R.resize(m, m);
  d.u.resize(m);
  for (int i = 0; i < m; ++i) {
    d.H.row(i) = H.row(d.idx[static_cast<std::size_t>(i)]);
    d.u(i) = in.u(d.idx[static_cast<std::size_t>(i)]);
    for (int j = 0; j < m; ++j)
      d.R(i, j) = R(d.idx[static_cast<std::size_t>(i)], d.idx[static_cast<std::size_t>(j)]);
  }
  return d;
}

// Adds the rows (H, u, covariance R) to the normal equations.
void accumulate(NormalEquations& ne, const Eigen::MatrixXd& H, const Eigen::VectorXd& u,
                const Eigen::MatrixXd& R, const std::string& what) {
  const Eigen::LLT<Eigen::MatrixXd> llt(R);
  if (llt.info() != Eigen::Success)
    throw std::runtime_error("stage 2: the covariance of " + what + " is not positive definite");
  ne.J += H.transpose() * llt.solve(H);
  ne.b += H.transpose() * llt.solve(u);
  ne.uWu += u.dot(llt.solve(u));
  ne.inputs += static_cast<int>(u.size());
}

// Every dwell's rows stacked, their covariance with the bias wander between dwells.
void accumulate_correlated(NormalEquations& ne, const std::vector<EquivalentInputs>& inputs,
                           const std::vector<DwellRows>& rows, const Stage2Options& o) {
  Eigen::Index m = 0;
  std::vector<Eigen::Index> at;
  for (const auto& d : rows) {
    at.push_back(m);
    m += static_cast<Eigen::Index>(d.idx.size());
  }
  Eigen::MatrixXd H(m, ne.J.cols()), R = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd u(m);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const auto mi = static_cast<Eigen::Index>(rows[i].idx.size());
    H.middleRows(at[i], mi) = rows[i].H;
    u.segment(at[i], mi) = rows[i].u;
    R.block(at[i], at[i], mi, mi) = rows[i].R;
    for (std::size_t j = 0; j <= i; ++j) {
      const Matrix6d W = stage2_wander_covariance(inputs[i], inputs[j], o.bias_wander);
      for (Eigen::Index a = 0; a < mi; ++a)
        for (std::size_t b = 0; b < rows[j].idx.size(); ++b) {
          const double w = W(rows[i].idx[static_cast<std::size_t>(a)], rows[j].idx[b]);
          R(at[i] + a, at[j] + static_cast<Eigen::Index>(b)) += w;
          if (j != i) R(at[j] + static_cast<Eigen::Index>(b), at[i] + a) += w;
        }
    }
  }
  accumulate(ne, H, u, R, "the dwells' inputs with their bias wander");
}

bool wanders(const NoiseModel& n) {
  const auto triad = [](const TriadNoise& t) {
    return (t.bias_instability > 0.0 && t.correlation_time > 0.0) || t.random_walk > 0.0;
  };
  return triad(n.gyro) || triad(n.accel);
}

NormalEquations stage2_normal_equations(const std::vector<EquivalentInputs>& inputs,
                                        const Site& site, const Stage2Options& o) {
  const int n = static_cast<int>(o.parameters.size()) + (o.base_attitude ? 3 : 0);
  NormalEquations ne{Eigen::MatrixXd::Zero(n, n), Eigen::VectorXd::Zero(n)};
  std::vector<DwellRows> rows;
  rows.reserve(inputs.size());
  for (const auto& in : inputs) rows.push_back(stage2_rows(in, site, o, n));
  if (wanders(o.bias_wander)) {
    accumulate_correlated(ne, inputs, rows, o);
    return ne;
  }
  for (std::size_t i = 0; i < rows.size(); ++i)
    accumulate(ne, rows[i].H, rows[i].u, rows[i].R,
               "dwell " + std::to_string(inputs[i].dwell.index));
  return ne;
}

// "+0.577 accel.scale.x +0.577 ..." for a direction in parameter space.
std::string direction_text(const Eigen::VectorXd& dir, const std::vector<std::string>& names) {
  std::string text;
  for (Eigen::Index i = 0; i < dir.size(); ++i)
    if (std::abs(dir(i)) > 0.05) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "%s%+.3f %s", text.empty() ? "" : " ", dir(i),
                    names[static_cast<std::size_t>(i)].c_str());
      text += buf;
    }
  return text;
}

// The names of stage 2's parameters: the coefficients, then the base's three angles.
std::vector<std::string> parameter_names(const Stage2Options& o) {
  std::vector<std::string> names;
  for (int c : o.parameters)
    names.push_back(coefficient_catalog()[static_cast<std::size_t>(c)].name);
  if (o.base_attitude)
    names.insert(names.end(), {"table.base.north", "table.base.east", "table.base.down"});
  return names;
}

// Splits the base's three angles off the end of the solution.
void split_base(Stage2Result& r, int nc) {
  r.base_estimated = true;
  r.base_n = r.theta.tail<3>();
  r.base_cov = r.cov.bottomRightCorner<3, 3>();
  const auto first = static_cast<std::size_t>(nc);
  r.base_observable = r.observable[first] && r.observable[first + 1] && r.observable[first + 2];
  r.theta.conservativeResize(nc);
  r.cov.conservativeResize(nc, nc);
  r.observable.resize(static_cast<std::size_t>(nc));
}
}  // namespace

Stage2Result solve_stage2(const std::vector<EquivalentInputs>& inputs, const Site& site,
                          const Stage2Options& o) {
  const std::vector<std::string> names = parameter_names(o);
  const int n = static_cast<int>(names.size());
  const NormalEquations ne = stage2_normal_equations(inputs, site, o);
  // Jacobi scaling, then the eigen-decomposition names the unobservable directions.
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d(i) = ne.J(i, i) > 0.0 ? 1.0 / std::sqrt(ne.J(i, i)) : 1.0;
  const Eigen::MatrixXd Js = d.asDiagonal() * ne.J * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Js);
  const double lmax = es.eigenvalues().maxCoeff();
  Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd null_weight = Eigen::VectorXd::Zero(n);
  Stage2Result r;
  r.parameters = o.parameters;
  for (int k = 0; k < n; ++k) {
    const double l = es.eigenvalues()(k);
    const Eigen::VectorXd v = es.eigenvectors().col(k);
    if (l > o.null_tolerance * lmax) {
      pinv += v * v.transpose() / l;
      ++r.rank;
      continue;
    }
    null_weight += v.cwiseAbs2();
    Eigen::VectorXd dir = (d.asDiagonal() * v).normalized();
    Eigen::Index lead = 0;
    dir.cwiseAbs().maxCoeff(&lead);
    if (dir(lead) < 0.0) dir = -dir;
    r.unobservable_directions.push_back(direction_text(dir, names));
    r.null_vectors.push_back(dir);
  }
  r.theta = d.asDiagonal() * pinv * d.asDiagonal() * ne.b;
  r.cov = d.asDiagonal() * pinv * d.asDiagonal();
  r.theta_min_norm = r.theta;
  r.cov_min_norm = r.cov;
  r.dof = ne.inputs - r.rank;
  r.chi2_per_dof = r.dof > 0 ? std::max(0.0, ne.uWu - ne.b.dot(r.theta)) / r.dof : 0.0;
  r.observable.assign(static_cast<std::size_t>(n), true);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i)
    if (null_weight(i) > 1e-6) {
      r.observable[static_cast<std::size_t>(i)] = false;
      r.theta(i) = nan;
      r.cov.row(i).setConstant(nan);
      r.cov.col(i).setConstant(nan);
    }
  if (o.base_attitude) split_base(r, static_cast<int>(o.parameters.size()));
  return r;
}

PaperClosedForms paper_closed_forms(const std::vector<EquivalentInputs>& in, const Site& site) {
  if (in.size() != 8)
    throw std::invalid_argument("the paper's closed forms need the 8 orientations");
  const Earth& earth = Earth::wgs84();
  const double Om = earth.rate(), phi = site.lat_rad;
  const double g = earth.gravity_n(site.lat_rad, site.h_m).norm();
  const double s2 = std::sqrt(2.0);
  // Paper variables, 1-based as in the paper: dwn = -(gyro error North), dfn = accel error North.
  double dwn[9], dfn[9];
  for (int i = 1; i <= 8; ++i) {
    dwn[i] = -in[i - 1].u(ins_input::kGyro.index + 0);
    dfn[i] = in[i - 1].u(ins_input::kAccel.index + 0);
  }
  const double Os = Om * std::sin(phi), Oc = Om * std::cos(phi);
  PaperClosedForms p;
  p.w0x = (dwn[3] + dwn[7] - dwn[1] - dwn[5]) / 4.0;
  p.dkgx = -(dwn[1] + dwn[3] + dwn[5] + dwn[7]) / (4.0 * Oc);
  p.nu_xy = (dwn[3] + dwn[5] - dwn[1] - dwn[7]) / (2.0 * s2 * Os);
  p.nu_xz = (dwn[1] + dwn[3] - dwn[5] - dwn[7]) / (2.0 * s2 * Os);
  p.w0z = (dwn[2] + dwn[8] - dwn[4] - dwn[6]) / 4.0;
  p.dkgz = -(dwn[2] + dwn[4] + dwn[6] + dwn[8]) / (4.0 * Oc);
  p.nu_zx = (dwn[2] - dwn[8] + dwn[4] - dwn[6]) / (2.0 * s2 * Os);
  p.nu_zy = (dwn[2] - dwn[8] - dwn[4] + dwn[6]) / (2.0 * s2 * Os);
  p.f0x = (dfn[1] - dfn[3] + dfn[5] - dfn[7]) / 4.0;
  p.mu_xy = s2 / (4.0 * g) * (dfn[1] - dfn[3] - dfn[5] + dfn[7]);
  p.mu_xz = s2 / (4.0 * g) * (-dfn[1] - dfn[3] + dfn[5] + dfn[7]);
  p.f0z = (-dfn[2] + dfn[4] + dfn[6] - dfn[8]) / 4.0;
  p.mu_zx = s2 / (4.0 * g) * (-dfn[2] - dfn[4] + dfn[6] + dfn[8]);
  p.mu_zy = s2 / (4.0 * g) * (-dfn[2] + dfn[4] - dfn[6] + dfn[8]);
  return p;
}

}  // namespace sinscal

namespace sinscal {

std::vector<std::pair<std::string, double>> named(const PaperClosedForms& p) {
  return {{"gyro.bias.x", p.w0x},
          {"gyro.scale.x", p.dkgx},
          {"gyro.misalignment.xy", p.nu_xy},
          {"gyro.misalignment.xz", p.nu_xz},
          {"gyro.bias.z", p.w0z},
          {"gyro.scale.z", p.dkgz},
          {"gyro.misalignment.zx", p.nu_zx},
          {"gyro.misalignment.zy", p.nu_zy},
          {"accel.bias.x", p.f0x},
          {"accel.misalignment.xy", p.mu_xy},
          {"accel.misalignment.xz", p.mu_xz},
          {"accel.bias.z", p.f0z},
          {"accel.misalignment.zx", p.mu_zx},
          {"accel.misalignment.zy", p.mu_zy}};
}

namespace {
// The paper's 8-orientation plan (paper convention: heading, pitch, roll in deg).
bool is_paper_plan(const Session& session, const std::vector<EquivalentInputs>& stage1) {
  const auto& o = session.plan.orientations;
  static const double kPaper[8][3] = {{0, 0, 45},  {90, 45, 0},   {180, 0, 315}, {270, 315, 0},
                                      {0, 0, 225}, {90, 45, 180}, {180, 0, 135}, {90, 225, 0}};
  if (session.plan.type != Plan::Type::Orientations || o.size() != 8 || stage1.size() != 8)
    return false;
  for (std::size_t i = 0; i < 8; ++i) {
    const Eigen::Matrix3d C = C_b_n_from_euler(
        AngleConvention::Paper,
        {kPaper[i][0] * units::deg, kPaper[i][1] * units::deg, kPaper[i][2] * units::deg});
    if ((C - stage1[i].dwell.C_b_n_known).cwiseAbs().maxCoeff() >= 1e-9) return false;
  }
  return true;
}
}  // namespace

namespace {
// The samples turned by a rotation, both triads: the alignment's mounting taken out.
// The samples compensated with a model (rates at the static dwells: no angular acceleration).
class CompensatedSource : public SampleSource {
 public:
  CompensatedSource(SampleSource& in, const ImuErrorModel& model, double time_offset)
      : in_(in), model_(model), time_offset_(time_offset) {}
  bool next(ImuSample& s) override {
    if (!in_.next(s)) return false;
    if (!(s.dt > 0.0)) return true;  // stage 1 refuses it with the reason
    Eigen::Vector3d omega, f;
    model_.compensate(s.dtheta_b / s.dt, s.dv_b / s.dt, Eigen::Vector3d::Zero(), omega, f,
                      s.t - time_offset_);
    s.dtheta_b = omega * s.dt;
    s.dv_b = f * s.dt;
    return true;
  }

 private:
  SampleSource& in_;
  const ImuErrorModel& model_;
  double time_offset_;
};

class TurnedSource : public SampleSource {
 public:
  TurnedSource(SampleSource& in, const Eigen::Matrix3d& C) : in_(in), C_(C) {}
  bool next(ImuSample& s) override {
    if (!in_.next(s)) return false;
    s.dtheta_b = C_ * s.dtheta_b;
    s.dv_b = C_ * s.dv_b;
    return true;
  }

 private:
  SampleSource& in_;
  Eigen::Matrix3d C_;
};

// The model whose stage-2 coefficients are `theta` (SI, catalog indices `parameters`).
ImuErrorModel model_of(const std::vector<int>& parameters, const Eigen::VectorXd& theta) {
  ImuErrorModel m;
  auto refs = m.coefficient_refs();
  for (std::size_t i = 0; i < parameters.size(); ++i)
    *refs[static_cast<std::size_t>(parameters[i])].second = theta(static_cast<Eigen::Index>(i));
  return m;
}

// Stage 2's coefficients through an affine map of them (`map`: the coefficients' vector to the
// new one), applied to the estimate and its covariance. A coefficient the data did not determine
// spreads to those it enters.
template <class Map>
void map_coefficients(Stage2Result& r, const Map& map) {
  const auto n = static_cast<int>(r.theta.size());
  const Eigen::VectorXd offset = map(Eigen::VectorXd::Zero(n));
  Eigen::MatrixXd T(n, n);
  for (int j = 0; j < n; ++j) T.col(j) = map(Eigen::VectorXd::Unit(n, j)) - offset;
  std::vector<bool> observable = r.observable;
  Eigen::VectorXd theta = r.theta;
  Eigen::MatrixXd cov = r.cov;
  for (int j = 0; j < n; ++j)
    if (!r.observable[static_cast<std::size_t>(j)]) {
      theta(j) = 0.0;
      cov.row(j).setZero();
      cov.col(j).setZero();
      for (int i = 0; i < n; ++i)
        if (T(i, j) != 0.0) observable[static_cast<std::size_t>(i)] = false;
    }
  r.theta = T * theta + offset;
  r.cov = T * cov * T.transpose();
  r.observable = observable;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i)
    if (!observable[static_cast<std::size_t>(i)]) {
      r.theta(i) = nan;
      r.cov.row(i).setConstant(nan);
      r.cov.col(i).setConstant(nan);
    }
}

// Stage 2's coefficients of samples turned by C, relative to the platform again: A = C^T A',
// b = C^T b' (both triads), a linear map applied to the estimate and its covariance.
void turn_back(Stage2Result& r, const Eigen::Matrix3d& C) {
  map_coefficients(r, [&](const Eigen::VectorXd& theta) {
    const ImuErrorModel m = model_of(r.parameters, theta);
    ImuErrorModel out = m;
    for (auto [to, from] : {std::pair{&out.accel, &m.accel}, std::pair{&out.gyro, &m.gyro}}) {
      const Eigen::Matrix3d A = C.transpose() * from->linear();
      to->scale = A.diagonal() - Eigen::Vector3d::Ones();
      to->misalignment = A;
      to->misalignment.diagonal().setZero();
      to->bias = C.transpose() * from->bias;
    }
    return parameter_vector(out, r.parameters);
  });
}

// A triad's linear part and bias after samples compensated with `about` show `residual`: the
// outputs y = A_a x' + b_a of x' = A_r x + b_r, i.e. A = A_a A_r, b = b_a + A_a b_r.
void compose_triad(const TriadErrors& about, const TriadErrors& residual, TriadErrors& out) {
  const Eigen::Matrix3d A = about.linear() * residual.linear();
  out.scale = A.diagonal() - Eigen::Vector3d::Ones();
  out.misalignment = A;
  out.misalignment.diagonal().setZero();
  out.bias = about.bias + about.linear() * residual.bias;
}

// Stage 2's coefficients of samples compensated with `about` (the residual errors), as the
// totals: composed with it, estimate and covariance.
void compose_with(Stage2Result& r, const ImuErrorModel& about) {
  map_coefficients(r, [&](const Eigen::VectorXd& theta) {
    const ImuErrorModel m = model_of(r.parameters, theta);
    ImuErrorModel out = m;
    compose_triad(about.accel, m.accel, out.accel);
    compose_triad(about.gyro, m.gyro, out.gyro);
    return parameter_vector(out, r.parameters);
  });
}

// The alignment from the session's dwells; when significant, the dwells' attitudes turned by its
// base. Returns the turn of the samples (its mounting taken out), identity otherwise.
Eigen::Matrix3d apply_alignment(const Session& session, PlanTimeline& timeline, ClosedFormReport& r,
                                const ImuErrorModel* about) {
  std::vector<AlignmentDwell> means;
  try {
    // Bad samples left out of the means; stage 1 reports them.
    LogReader reader(session.log);
    reader.skip_bad_samples([](const BadSampleError&) {});
    if (about) {
      CompensatedSource compensated(reader, *about, session.time_offset);
      means = dwell_means(compensated, timeline, session.time_offset, kAlignmentEdge);
    } else {
      means = dwell_means(reader, timeline, session.time_offset, kAlignmentEdge);
    }
  } catch (const std::runtime_error&) {
    return Eigen::Matrix3d::Identity();  // a log stage 1 will refuse, with the reason
  }
  const Earth& earth = Earth::wgs84();
  InstallationResult& in = r.installation;
  in.alignment =
      align(means, session.site,
            kAlignmentLinearError * earth.gravity_n(session.site.lat_rad, session.site.h_m).norm(),
            kAlignmentLinearError * earth.rate());
  const Alignment& a = *in.alignment;
  if (!a.significant(kAlignmentThreshold)) return Eigen::Matrix3d::Identity();
  in.alignment_applied = true;
  const Eigen::Matrix3d C_base = dcm_from_rotvec(a.base_n);
  for (auto& d : timeline.dwells) d.C_b_n_known = C_base * d.C_b_n_known;
  in.base_n = a.base_n;
  return dcm_from_rotvec(a.mounting_b);
}

// The common rotation of the triads of the stage-2 coefficients (when the accelerometer
// misalignments are all determined).
void set_mounting(const Stage2Result& r, InstallationResult& in) {
  ImuErrorModel m;
  auto refs = m.coefficient_refs();
  for (std::size_t i = 0; i < r.parameters.size(); ++i) {
    const auto c = static_cast<std::size_t>(r.parameters[i]);
    if (refs[c].first.family == "accel.misalignment" && !r.observable[i]) return;
    if (r.observable[i]) *refs[c].second = r.theta(static_cast<Eigen::Index>(i));
  }
  in.mounting_estimated = true;
  in.mounting_b = mounting_of(m);
  in.mounting_sigma_b = mounting_sigma(r.parameters, r.cov);
}
}  // namespace

ClosedFormReport run_closed_form(const Session& session, const Stage1Options& stage1,
                                 const TableAttitudeError& table, bool align_first,
                                 const ImuErrorModel* about) {
  ClosedFormReport r;
  r.stage1_options = stage1;
  PlanTimeline timeline = PlanTimeline::of(session.plan, session.site);
  const Eigen::Matrix3d C_turn =
      align_first ? apply_alignment(session, timeline, r, about) : Eigen::Matrix3d::Identity();
  LogReader reader(session.log);
  std::optional<CompensatedSource> compensated;
  if (about) compensated.emplace(reader, *about, session.time_offset);
  TurnedSource turned(compensated ? static_cast<SampleSource&>(*compensated) : reader, C_turn);
  r.stage1 = run_stage1(turned, timeline.dwells, session.site, stage1, session.time_offset,
                        session.log.file);
  r.stage2_options.table = table;
  // The base needs every input (all four channels, the command line's default): with the
  // paper's two it mixes with the scale factors, and the paper's method takes the plan's base.
  const auto inputs = stage1.channels.inputs();
  r.stage2_options.base_attitude =
      align_first && std::all_of(inputs.begin(), inputs.end(), [](bool b) { return b; });
  r.stage2 = solve_stage2(r.stage1, session.site, r.stage2_options);
  InstallationResult& in = r.installation;
  if (in.alignment_applied) turn_back(r.stage2, C_turn);
  if (r.stage2.base_estimated && r.stage2.base_observable) {
    in.base_estimated = true;
    in.base_n = rotvec_from_dcm(dcm_from_rotvec(r.stage2.base_n) * dcm_from_rotvec(in.base_n));
    in.base_sigma_n = r.stage2.base_cov.diagonal().cwiseSqrt();
  }
  set_mounting(r.stage2, in);
  // The paper's literal closed forms, when the plan is its 8-orientation table.
  if (is_paper_plan(session, r.stage1)) {
    r.has_paper_forms = true;
    r.paper = paper_closed_forms(r.stage1, session.site);
  }
  return r;
}

DwellTurn closed_form_turn(const EquivalentInputs& e, const Site& site) {
  DwellTurn t;
  double rate2 = 0.0;
  for (int i = 3; i < 6; ++i)
    if (e.estimated[static_cast<std::size_t>(i)]) rate2 += e.u(i) * e.u(i);
  t.turn = std::sqrt(rate2) * e.duration;
  double sigma_f = HUGE_VAL;
  for (int i = 0; i < 2; ++i)
    if (e.estimated[static_cast<std::size_t>(i)] && e.cov(i, i) > 0.0)
      sigma_f = std::min(sigma_f, std::sqrt(e.cov(i, i)));
  const Earth& earth = Earth::wgs84();
  const double g = earth.gravity_n(site.lat_rad, site.h_m).norm();
  t.bound = std::isfinite(sigma_f) ? std::sqrt(2.0 * sigma_f / g) : HUGE_VAL;
  double force2 = 0.0;
  for (int i = 0; i < 3; ++i)
    if (e.estimated[static_cast<std::size_t>(i)]) force2 += e.u(i) * e.u(i);
  t.speed = std::sqrt(force2) * e.duration;
  t.speed_bound =
      std::isfinite(sigma_f) ? std::sqrt(sigma_f * earth.radius_meridian(site.lat_rad)) : HUGE_VAL;
  return t;
}

namespace {

// The dwell turned farthest against its bound, and the one whose velocity went farthest.
void set_largest_turn(ClosedFormReport& r, const Site& site) {
  double worst = -1.0, worst_speed = -1.0;
  for (const auto& e : r.stage1) {
    const DwellTurn t = closed_form_turn(e, site);
    if (t.turn / t.bound > worst) {
      worst = t.turn / t.bound;
      r.largest_turn = t.turn;
      r.linear_turn = t.bound;
      r.largest_turn_dwell = e.dwell.label;
    }
    if (t.speed / t.speed_bound > worst_speed) {
      worst_speed = t.speed / t.speed_bound;
      r.largest_speed = t.speed;
      r.linear_speed = t.speed_bound;
      r.largest_speed_dwell = e.dwell.label;
    }
  }
}

bool turned_beyond(const ClosedFormReport& r) { return r.largest_turn > r.linear_turn; }
bool beyond_range(const ClosedFormReport& r) {
  return turned_beyond(r) || r.largest_speed > r.linear_speed;
}

// The stage-2 gyro biases (rad/s), zero where unobservable.
Eigen::Vector3d gyro_biases(const Stage2Result& s2) {
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < s2.parameters.size(); ++i) {
    const auto& c = cat[static_cast<std::size_t>(s2.parameters[i])];
    if (c.family != "gyro.bias" || !s2.observable[i]) continue;
    b(c.name.back() - 'x') = s2.theta(static_cast<Eigen::Index>(i));
  }
  return b;
}

// Whether stage 2 determined every accelerometer bias, scale factor and misalignment.
bool accel_determined(const Stage2Result& s2) {
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < s2.parameters.size(); ++i)
    if (cat[static_cast<std::size_t>(s2.parameters[i])].family.rfind("accel.", 0) == 0 &&
        !s2.observable[i])
      return false;
  return true;
}

// The model to linearize about next: `about` composed with a pass's stage-2 gyro biases, and its
// accelerometer bias, scale and misalignment when `accel` (the rest of the gyro terms stay out:
// the Earth rate alone gives them, at sigmas far beyond their size).
ImuErrorModel next_about(const ImuErrorModel& about, const Stage2Result& s2, bool accel) {
  const Eigen::VectorXd theta =
      s2.theta.unaryExpr([](double v) { return std::isfinite(v) ? v : 0.0; });
  const ImuErrorModel m = model_of(s2.parameters, theta);
  ImuErrorModel out = about;
  out.gyro.bias += m.gyro.bias;
  if (accel) compose_triad(about.accel, m.accel, out.accel);
  return out;
}

// The paper's closed forms of a pass about `about`: its biases and misalignments added (to first
// order, as the forms are).
void add_about(PaperClosedForms& p, const ImuErrorModel& about) {
  p.w0x += about.gyro.bias.x();
  p.w0z += about.gyro.bias.z();
  p.f0x += about.accel.bias.x();
  p.f0z += about.accel.bias.z();
  p.mu_xy += about.accel.misalignment(0, 1);
  p.mu_xz += about.accel.misalignment(0, 2);
  p.mu_zx += about.accel.misalignment(2, 0);
  p.mu_zy += about.accel.misalignment(2, 1);
}

// The gyro biases from the dwells' mean outputs, the Earth rate at the plan's attitudes taken
// out (no integration: right to the scale factors times the Earth rate, whatever the biases);
// zero when the log cannot be read (stage 1 reports why).
Eigen::Vector3d dwell_mean_gyro_bias(const Session& session) {
  std::vector<AlignmentDwell> means;
  try {
    LogReader reader(session.log);
    reader.skip_bad_samples([](const BadSampleError&) {});
    means = dwell_means(reader, PlanTimeline::of(session.plan, session.site), session.time_offset,
                        kAlignmentEdge);
  } catch (const std::runtime_error&) {
    return Eigen::Vector3d::Zero();
  }
  const Eigen::Vector3d omega_ie_n = Earth::wgs84().omega_ie_n(session.site.lat_rad);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& d : means) sum += d.omega_b - d.C_b_n_known.transpose() * omega_ie_n;
  return means.empty() ? sum : Eigen::Vector3d(sum / static_cast<double>(means.size()));
}

}  // namespace

ClosedFormReport run_closed_form_relinearized(const Session& session, const Stage1Options& stage1,
                                              const TableAttitudeError& table,
                                              int max_linearizations) {
  ClosedFormReport r = run_closed_form(session, stage1, table);
  set_largest_turn(r, session.site);
  r.first_gyro_bias = gyro_biases(r.stage2);
  ImuErrorModel about;
  for (int k = 2; k <= max_linearizations && beyond_range(r); ++k) {
    // The first relinearization of a pass beyond the gyros' range about the dwells' mean rates
    // (a stage 1 far beyond its range gives biases shrunk and of either sign: seed8's 180 s
    // dwells at 1 deg/s turned -0.65 times the truth); otherwise by the pass's stage-2
    // corrections, the accelerometers' too when the pass was within the gyros' range.
    const bool turned = turned_beyond(r);
    const bool accel = !turned && accel_determined(r.stage2);
    ImuErrorModel step = about;
    if (k == 2 && turned)
      step.gyro.bias += dwell_mean_gyro_bias(session);
    else
      step = next_about(about, r.stage2, accel);
    if (!step.gyro.bias.allFinite()) break;
    ClosedFormReport next;
    try {
      next = run_closed_form(session, stage1, table, true, &step);
    } catch (const std::invalid_argument&) {
      break;  // a linearization that cannot run (no dwell left): the last one stands
    }
    about = step;
    next.linearizations = k;
    next.removed_gyro_bias = about.gyro.bias;
    next.removed_accel = r.removed_accel || accel;
    next.first_gyro_bias = r.first_gyro_bias;
    set_largest_turn(next, session.site);
    r = std::move(next);
  }
  if (r.linearizations > 1) {
    compose_with(r.stage2, about);
    set_mounting(r.stage2, r.installation);
    if (r.has_paper_forms) add_about(r.paper, about);
  }
  return r;
}

}  // namespace sinscal
