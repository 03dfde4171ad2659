#include "filter/kalman_calibrator.hpp"

#include <Eigen/Cholesky>
#include <cmath>

#include "models/attitude.hpp"
#include "models/units.hpp"

namespace sinscal {

CalibratorOptions calibrator_options_from_profile(const SensorProfile& profile) {
  CalibratorOptions o;
  o.noise = profile.noise;
  o.layout.accel_k2 = profile.has("accel.k2");
  o.layout.lever_arm = profile.has("accel.lever_arm");
  o.layout.time_delay = profile.has("time_delay");
  o.layout.g_sensitivity = profile.has("gyro.g_sensitivity");
  o.layout.scale_asym = profile.has("gyro.scale_asym") || profile.has("accel.scale_asym");
  const auto& cat = coefficient_catalog();
  o.initial_sigma.assign(cat.size(), 0.0);
  for (std::size_t i = 0; i < cat.size(); ++i) {
    const auto it = profile.ranges.find(coefficient_family(cat[i].name));
    if (it != profile.ranges.end() && it->second.present())
      o.initial_sigma[i] = 1.5 * std::max(std::abs(it->second.lo), std::abs(it->second.hi));
  }
  return o;
}

namespace {
// Family defaults for blocks switched on without a profile range (SI).
double default_sigma(const std::string& family) {
  using namespace units;
  if (family == "gyro.bias") return 1.0 * deg_per_h;
  if (family == "accel.bias") return 1000 * ug;
  if (family == "gyro.g_sensitivity") return 0.1 * deg_per_h_per_g;
  if (family == "accel.k2") return 100 * ug_per_g2;
  if (family == "accel.lever_arm") return 0.1;
  if (family == "time_delay") return 0.01;
  if (family.find("misalignment") != std::string::npos) return 300 * arcsec;
  return 300 * ppm;  // scale factors, asymmetry
}
}  // namespace

double initial_attitude_sigma(const CalibratorOptions& o) {
  if (o.initial_attitude_sigma > 0.0) return o.initial_attitude_sigma;
  return 0.5 * units::deg;
}

StateLayoutOptions effective_layout(const CalibratorOptions& o) {
  StateLayoutOptions l = o.layout;
  if (o.attitude == CalibratorOptions::AttitudeUpdates::None) l.accel_triad_frame = true;
  return l;
}

Calibrator::Calibrator(std::vector<Dwell> dwells, const Site& site,
                       const CalibratorOptions& options)
    : dwells_(std::move(dwells)),
      site_(site),
      o_(options),
      layout_(StateLayout::make(effective_layout(options))) {
  if (dwells_.empty()) throw std::invalid_argument("the Kalman calibrator needs the plan's dwells");
  site_terms_ = InsSiteTerms::at(site);
  n_nav_ = layout_.position.index + layout_.position.size;
  for (int i = 0; i < 3; ++i) ins_index_.push_back(ins_state::kAttitude.index + i);
  for (int i = 0; i < layout_.velocity.size; ++i)
    ins_index_.push_back(ins_state::kVelocity.index + i);
  for (int i = 0; i < 3; ++i) ins_index_.push_back(ins_state::kPosition.index + i);
  const int n = layout_.size, m = n - n_nav_;
  const auto& cat = coefficient_catalog();
  state_of_coefficient_.assign(cat.size(), -1);
  P_ = Eigen::MatrixXd::Zero(n, n);
  P_.block(layout_.attitude.index, layout_.attitude.index, 3, 3)
      .diagonal()
      .setConstant(std::pow(initial_attitude_sigma(o_), 2));
  P_.block(layout_.velocity.index, layout_.velocity.index, layout_.velocity.size,
           layout_.velocity.size)
      .diagonal()
      .setConstant(1e-6);
  P_.block(layout_.position.index, layout_.position.index, 3, 3).diagonal().setConstant(1e-4);
  for (const auto& cb : layout_.coefficient_blocks())
    for (int k = 0; k < cb.block.size; ++k) {
      const int c = cb.catalog[static_cast<std::size_t>(k)], x = cb.block.index + k;
      state_of_coefficient_[static_cast<std::size_t>(c)] = x;
      double s0 = o_.initial_sigma.size() > static_cast<std::size_t>(c)
                      ? o_.initial_sigma[static_cast<std::size_t>(c)]
                      : 0.0;
      if (!(s0 > 0.0)) s0 = default_sigma(cb.family);
      P_(x, x) = s0 * s0;
    }
  Phi_nn_ = Eigen::MatrixXd::Identity(n_nav_, n_nav_);
  Phi_nc_ = Eigen::MatrixXd::Zero(n_nav_, m);
  Q_nn_ = Eigen::MatrixXd::Zero(n_nav_, n_nav_);
}

void Calibrator::push(const ImuSample& s) {
  held_.push_back(s);
  if (held_.size() < 2) return;
  if (held_.size() > 3) held_.erase(held_.begin());
  // Process the middle sample: derivatives from its neighbours' mean rates.
  const ImuSample& next = held_.back();
  const ImuSample& cur = held_[held_.size() - 2];
  const ImuSample& prev = held_.size() == 3 ? held_.front() : cur;
  const double span = held_.size() == 3 ? next.t - prev.t : next.t - cur.t;
  const Eigen::Vector3d f_ddot =
      held_.size() == 3
          ? Eigen::Vector3d((next.dv_b / next.dt - 2.0 * cur.dv_b / cur.dt + prev.dv_b / prev.dt) /
                            (0.25 * span * span))
          : Eigen::Vector3d::Zero();
  process(cur, (next.dtheta_b / next.dt - prev.dtheta_b / prev.dt) / span,
          (next.dv_b / next.dt - prev.dv_b / prev.dt) / span, f_ddot);
}

void Calibrator::finish() {
  if (held_.empty()) return;
  const ImuSample& cur = held_.back();
  const ImuSample& prev = held_.size() > 1 ? held_[held_.size() - 2] : cur;
  const double span = cur.t - prev.t;
  const Eigen::Vector3d wd =
      span > 0 ? Eigen::Vector3d((cur.dtheta_b / cur.dt - prev.dtheta_b / prev.dt) / span)
               : Eigen::Vector3d::Zero();
  const Eigen::Vector3d fd = span > 0
                                 ? Eigen::Vector3d((cur.dv_b / cur.dt - prev.dv_b / prev.dt) / span)
                                 : Eigen::Vector3d::Zero();
  process(cur, wd, fd, Eigen::Vector3d::Zero());
  held_.clear();
}

void Calibrator::process(const ImuSample& s, const Eigen::Vector3d& omega_dot,
                         const Eigen::Vector3d& f_dot, const Eigen::Vector3d& f_ddot) {
  if (!started_) {
    nav_.reset(NavState::at_rest(dwells_.front().C_b_n_known, site_));
    started_ = true;
  }
  const double dt = s.dt;
  // Compensate with the current estimate (mean rates over the interval).
  const Eigen::Vector3d y_g = s.dtheta_b / dt, y_a = s.dv_b / dt;
  Eigen::Vector3d omega, f;
  model_.compensate(y_g, y_a, omega_dot, omega, f);
  // Accelerometers late by tau: f(t) = f_meas(t + tau), to second order.
  const double tau = model_.time_delay;
  f += tau * f_dot + 0.5 * tau * tau * f_ddot;
  nav_.step(omega * dt, f * dt, dt);

  // Error dynamics of this interval.
  const NavState& x = nav_.state();
  const Eigen::Matrix3d C = x.C_b_n();
  const Eigen::Vector3d f_n = C * f;
  const int a = layout_.attitude.index, v = layout_.velocity.index;
  const int nv = layout_.velocity.size;
  const InsF F = ins_error_matrix(site_terms_, f_n, ErrorModelKind::Coupled);
  Eigen::MatrixXd A(n_nav_, n_nav_);
  for (int i = 0; i < n_nav_; ++i)
    for (int j = 0; j < n_nav_; ++j) A(i, j) = F(ins_index_[i], ins_index_[j]);

  KinematicSample k;
  k.omega_ib_b = omega;
  k.omega_dot_ib_b = omega_dot;
  k.f_ib_b = f;
  const auto J = model_.jacobian(k, f_dot);
  Eigen::MatrixXd B = Eigen::MatrixXd::Zero(n_nav_, layout_.size - n_nav_);
  for (std::size_t c = 0; c < state_of_coefficient_.size(); ++c) {
    const int xs = state_of_coefficient_[c];
    if (xs < 0) continue;
    const int col = xs - n_nav_;
    const auto jc = J.col(static_cast<Eigen::Index>(c));
    B.block<3, 1>(a, col) = -(C * jc.head<3>());
    B.block(v, col, nv, 1) = (C * jc.tail<3>()).head(nv);
  }
  const Eigen::MatrixXd step = Eigen::MatrixXd::Identity(n_nav_, n_nav_) + A * dt;
  Phi_nn_ = step * Phi_nn_;
  Phi_nc_ = step * Phi_nc_ + B * dt;
  // Noise entered earlier in the interval is carried by the later steps (into position, and from
  // attitude into velocity): Q <- step Q step^T + q dt.
  Q_nn_ = step * Q_nn_ * step.transpose();
  Q_nn_.diagonal().segment<3>(a).array() += o_.noise.gyro.white * o_.noise.gyro.white * dt;
  Q_nn_.diagonal().segment(v, nv).array() += o_.noise.accel.white * o_.noise.accel.white * dt;
  accumulated_ += dt;
  if (accumulated_ >= o_.update_interval - 1e-9) {
    propagate_covariance();
    update(s.t - o_.time_offset);
  }
}

void Calibrator::propagate_covariance() {
  const int n = n_nav_, m = layout_.size - n_nav_;
  // P <- Phi P Phi^T + Q with Phi = [[Phi_nn, Phi_nc], [0, I]].
  Eigen::MatrixXd T = P_;
  T.topRows(n) = Phi_nn_ * P_.topRows(n) + Phi_nc_ * P_.bottomRows(m);
  Eigen::MatrixXd Pn = T;
  Pn.leftCols(n) = T.leftCols(n) * Phi_nn_.transpose() + T.rightCols(m) * Phi_nc_.transpose();
  Pn.topLeftCorner(n, n) += Q_nn_;
  P_ = 0.5 * (Pn + Pn.transpose());
  Phi_nn_.setIdentity();
  Phi_nc_.setZero();
  Q_nn_.setZero();
  accumulated_ = 0.0;
}

void Calibrator::update(double t_plan) {
  const Dwell* dwell = nullptr;
  for (const auto& d : dwells_)
    if (t_plan >= d.t_start + o_.static_margin && t_plan <= d.t_end - o_.static_margin) dwell = &d;
  if (!dwell && !o_.zero_velocity_in_motion) return;
  const NavState& x = nav_.state();
  const NavError e =
      nav_error(x, dwell ? dwell->C_b_n_known : x.C_b_n(), Eigen::Vector3d::Zero(), site_);
  if (!dwell) {
    // Turning about the IMU reference point: zero velocity holds, the attitude is not known.
    std::vector<std::pair<int, double>> rows;
    for (int i = 0; i < layout_.velocity.size; ++i)
      rows.emplace_back(layout_.velocity.index + i, e.dv_n(i));
    apply_update(rows, std::vector<double>(rows.size(), o_.motion_velocity_sigma));
    return;
  }
  std::vector<std::pair<int, double>> rows;  // state index, measured value; with sigma
  std::vector<double> sig;
  if (o_.zero_velocity)
    for (int i = 0; i < layout_.velocity.size; ++i) {
      rows.emplace_back(layout_.velocity.index + i, e.dv_n(i));
      sig.push_back(o_.velocity_sigma);
    }
  if (o_.position)
    for (int i = 0; i < 3; ++i) {
      rows.emplace_back(layout_.position.index + i, e.dp_n(i));
      sig.push_back(o_.position_sigma);
    }
  const bool attitude_wanted =
      o_.attitude == CalibratorOptions::AttitudeUpdates::Every ||
      (o_.attitude == CalibratorOptions::AttitudeUpdates::First && dwell->index == 1);
  if (attitude_wanted && dwell->index > attitude_dwell_done_) {
    for (int i = 0; i < 3; ++i) {
      rows.emplace_back(layout_.attitude.index + i, e.phi_n(i));
      sig.push_back(o_.attitude_sigma);
    }
    attitude_dwell_done_ = dwell->index;
  }
  apply_update(rows, sig);
}

void Calibrator::apply_update(const std::vector<std::pair<int, double>>& rows,
                              const std::vector<double>& sig) {
  if (rows.empty()) return;
  const int r = static_cast<int>(rows.size()), n = layout_.size;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(r, n);
  Eigen::VectorXd z(r);
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(r, r);
  for (int i = 0; i < r; ++i) {
    H(i, rows[static_cast<std::size_t>(i)].first) = 1.0;
    z(i) = rows[static_cast<std::size_t>(i)].second;
    R(i, i) = sig[static_cast<std::size_t>(i)] * sig[static_cast<std::size_t>(i)];
  }
  const Eigen::MatrixXd PHt = P_ * H.transpose();
  const Eigen::MatrixXd S = H * PHt + R;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success)
    throw std::runtime_error("Kalman update: innovation covariance not positive definite");
  const Eigen::MatrixXd K = llt.solve(PHt.transpose()).transpose();
  nis_sum_ += z.dot(llt.solve(z));
  nis_dof_ += r;
  const Eigen::MatrixXd IKH = Eigen::MatrixXd::Identity(n, n) - K * H;
  P_ = IKH * P_ * IKH.transpose() + K * R * K.transpose();
  P_ = 0.5 * (P_ + P_.transpose());
  feed_back(K * z);
}

void Calibrator::feed_back(const Eigen::VectorXd& dx) {
  NavState x = nav_.state();
  const Eigen::Vector3d phi = dx.segment<3>(layout_.attitude.index);
  x.q_b_n = (quat_from_rotvec(phi) * x.q_b_n).normalized();
  for (int i = 0; i < layout_.velocity.size; ++i) x.v_n(i) -= dx(layout_.velocity.index + i);
  const Eigen::Vector3d dp = dx.segment<3>(layout_.position.index);
  x.lat_rad -= dp.x() / site_terms_.R_N;
  x.lon_rad -= dp.y() / (site_terms_.R_E * std::cos(site_.lat_rad));
  x.h_m += dp.z();
  // Keep the coning/sculling memory: the correction is tiny and the increments unchanged.
  nav_.correct(x);
  auto refs = model_.coefficient_refs();
  for (std::size_t c = 0; c < state_of_coefficient_.size(); ++c)
    if (state_of_coefficient_[c] >= 0) *refs[c].second += dx(state_of_coefficient_[c]);
}

std::vector<CoefficientEstimate> Calibrator::estimate() const {
  ImuErrorModel copy = model_;
  const auto refs = copy.coefficient_refs();
  std::vector<CoefficientEstimate> out(refs.size());
  for (std::size_t c = 0; c < refs.size(); ++c) {
    out[c].value = *refs[c].second;
    const int xs = state_of_coefficient_[c];
    out[c].sigma = xs >= 0 ? std::sqrt(P_(xs, xs)) : 0.0;
    out[c].status =
        xs >= 0 ? CoefficientEstimate::Status::Estimated : CoefficientEstimate::Status::Off;
  }
  for (int c : layout_.fixed_by_convention())
    out[static_cast<std::size_t>(c)].status = CoefficientEstimate::Status::FixedByConvention;
  return out;
}

}  // namespace sinscal

#include <memory>

#include "rig/log_io.hpp"
#include "rig/plan.hpp"

namespace sinscal {

namespace {
ResultCoefficients coefficients_of(const Calibrator& kf) {
  ResultCoefficients out;
  const auto est = kf.estimate();
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (est[i].sigma == 0.0) continue;  // block off
    ResultCoefficient c;
    c.value = est[i].value / cat[i].si_per_unit;
    c.sigma = est[i].sigma / cat[i].si_per_unit;
    c.unit = cat[i].unit;
    out[cat[i].name] = c;
  }
  return out;
}
}  // namespace

KalmanReport run_kalman(const Session& session, const CalibratorOptions& options,
                        SampleSource* source, const KalmanRunOptions& run) {
  const Motion motion = build_motion(session.plan, session.site);
  Calibrator kf(motion.dwells(), session.site, options);
  std::unique_ptr<LogReader> reader;
  if (!source) {
    reader = std::make_unique<LogReader>(session.log);
    source = reader.get();
  }
  KalmanReport r;
  ImuSample s;
  double t_first = 0.0, t_last = 0.0, next_monitor = run.monitor_interval;
  try {
    while (source->next(s)) {
      if (r.samples == 0) {
        t_first = s.t - s.dt;
        next_monitor = t_first + run.monitor_interval;
      }
      t_last = s.t;
      kf.push(s);
      ++r.samples;
      if (run.monitor && run.monitor_interval > 0.0 && s.t >= next_monitor - 1e-9) {
        nlohmann::ordered_json rec;
        rec["t"] = s.t;
        rec["nis_per_dof"] = kf.nis_dof() > 0 ? kf.nis_sum() / kf.nis_dof() : 0.0;
        nlohmann::ordered_json c = nlohmann::ordered_json::object();
        for (const auto& [name, e] : coefficients_of(kf)) c[name] = {e.value, *e.sigma};
        rec["coefficients"] = c;
        run.monitor(rec);
        next_monitor += run.monitor_interval;
      }
    }
  } catch (const LogError& e) {
    r.stopped = e.what();
  }
  kf.finish();
  r.duration = t_last - t_first;
  r.states = kf.layout().size;
  r.nis_per_dof = kf.nis_dof() > 0 ? kf.nis_sum() / kf.nis_dof() : 0.0;
  r.coefficients = coefficients_of(kf);
  r.details["method"] = {
      {"name", "kf"},
      {"states", r.states},
      {"zero_velocity", options.zero_velocity},
      {"position", options.position},
      {"attitude", options.attitude == CalibratorOptions::AttitudeUpdates::Every   ? "every dwell"
                   : options.attitude == CalibratorOptions::AttitudeUpdates::First ? "first dwell"
                                                                                   : "none"},
      {"update_interval_s", options.update_interval}};
  r.details["consistency"] = {{"nis_per_dof", r.nis_per_dof}, {"samples", r.samples}};
  if (!r.stopped.empty()) r.details["stopped"] = {{"reason", r.stopped}, {"last_good_t", t_last}};
  return r;
}

}  // namespace sinscal
