#include "filter/kalman_calibrator.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <memory>
#include <sstream>

#include "models/attitude.hpp"
#include "models/units.hpp"
#include "rig/log_io.hpp"
#include "rig/plan.hpp"

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
      layout_(StateLayout::make(effective_layout(options))),
      table_(options.table_geometry) {
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
  prior_sigma_.assign(cat.size(), 0.0);
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
      prior_sigma_[static_cast<std::size_t>(c)] = s0;
    }
  Phi_nn_ = Eigen::MatrixXd::Identity(n_nav_, n_nav_);
  Phi_nc_ = Eigen::MatrixXd::Zero(n_nav_, m);
  Q_nn_ = Eigen::MatrixXd::Zero(n_nav_, n_nav_);
  if (o_.initial_model) model_ = *o_.initial_model;
  if (o_.static_from == CalibratorOptions::StaticFrom::Data)
    detector_.emplace(o_.noise, o_.detector);
}

void Calibrator::push(const ImuSample& s) {
  // The filter integrates through the moves between dwells: a log with holes (one file per dwell)
  // has no data for them.
  if (!held_.empty() && s.t - s.dt > held_.back().t + 0.5 * s.dt) {
    char msg[320];
    std::snprintf(msg, sizeof msg,
                  "the data jump from t = %.6g s to %.6g s: the Kalman filter needs the samples "
                  "between dwells too (a log in one file per dwell: use --method closed-form)",
                  held_.back().t, s.t - s.dt);
    throw PlanDataMismatch(msg);
  }
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
  current_ = s;
  if (!started_) {
    nav_.reset(NavState::at_rest(s.has_table && o_.use_table_angles
                                     ? table_.C_b_n({s.table_outer, s.table_inner})
                                     : dwells_.front().C_b_n_known,
                                 site_));
    started_ = true;
  }
  const double dt = s.dt;
  if (detector_) {
    detector_->push(s);
    if (detector_->dwell() > static_cast<int>(dwells_.size())) {
      std::ostringstream m;
      m << "static interval " << detector_->dwell()
        << " found in the data at t = " << detector_->dwells().back().t_start
        << " s, but the plan has " << dwells_.size() << " dwells: the plan does not match the data";
      throw PlanDataMismatch(m.str());
    }
  }
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
  // Biases that wander (bias instability: a Gauss-Markov process of sigma b and correlation time
  // tau, driven by white noise of density 2 b^2 / tau; rate / acceleration random walk): random
  // walk on the bias states. Without the decay this is conservative over runs longer than tau.
  auto wander = [&](const Block& block, const TriadNoise& tn) {
    if (block.size == 0) return;
    const double q = (tn.correlation_time > 0.0
                          ? 2.0 * tn.bias_instability * tn.bias_instability / tn.correlation_time
                          : 0.0) +
                     tn.random_walk * tn.random_walk;
    for (int i = 0; i < block.size; ++i) Pn(block.index + i, block.index + i) += q * accumulated_;
  };
  wander(layout_.gyro_bias, o_.noise.gyro);
  wander(layout_.accel_bias, o_.noise.accel);
  P_ = 0.5 * (Pn + Pn.transpose());
  Phi_nn_.setIdentity();
  Phi_nc_.setZero();
  Q_nn_.setZero();
  accumulated_ = 0.0;
}

void Calibrator::update(double t_plan) {
  const Dwell* dwell = nullptr;
  if (detector_) {
    if (detector_->dwell() > 0) dwell = &dwells_[static_cast<std::size_t>(detector_->dwell() - 1)];
  } else {
    for (const auto& d : dwells_)
      if (t_plan >= d.t_start + o_.static_margin && t_plan <= d.t_end - o_.static_margin)
        dwell = &d;
  }
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
    Eigen::Vector3d phi = e.phi_n;
    if (current_.has_table && o_.use_table_angles) {
      // The attitude the table's angles give, checked against the plan's orientation.
      const Eigen::Matrix3d C_table = table_.C_b_n({current_.table_outer, current_.table_inner});
      const double apart = rotvec_from_dcm(C_table * dwell->C_b_n_known.transpose()).norm();
      if (apart > o_.table_plan_tolerance) {
        std::ostringstream m;
        m << "dwell " << dwell->index << " (" << dwell->label << ") at t = " << current_.t
          << " s: the table's angles (outer " << current_.table_outer / units::deg << " deg, inner "
          << current_.table_inner / units::deg << " deg) put the IMU " << apart / units::deg
          << " deg from the plan's orientation: the plan does not match the data";
        throw PlanDataMismatch(m.str());
      }
      phi = nav_error(x, C_table, Eigen::Vector3d::Zero(), site_).phi_n;
      ++table_updates_;
    }
    for (int i = 0; i < 3; ++i) {
      rows.emplace_back(layout_.attitude.index + i, phi(i));
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
  last_nis_ = z.dot(llt.solve(z));
  last_nis_dof_ = r;
  nis_sum_ += last_nis_;
  nis_dof_ += r;
  ++updates_;
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
    out[c].prior_sigma = prior_sigma_[c];
  }
  for (int c : layout_.fixed_by_convention())
    out[static_cast<std::size_t>(c)].status = CoefficientEstimate::Status::FixedByConvention;
  return out;
}

namespace {
ResultCoefficients coefficients_of(const std::vector<CoefficientEstimate>& est) {
  ResultCoefficients out;
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (est[i].status == CoefficientEstimate::Status::Off) continue;
    ResultCoefficient c;
    c.unit = cat[i].unit;
    c.fixed_by_convention = est[i].status == CoefficientEstimate::Status::FixedByConvention;
    if (!c.fixed_by_convention) {
      c.value = est[i].value / cat[i].si_per_unit;
      c.sigma = est[i].sigma / cat[i].si_per_unit;
      c.observable = est[i].observed();
    }
    out[cat[i].name] = c;
  }
  return out;
}

// Every estimated coefficient with a target for its family has sigma at or below it.
// Estimated coefficients whose sigma is above their family's target.
std::vector<std::string> above_target(const std::vector<CoefficientEstimate>& est,
                                      const std::map<std::string, double>& targets) {
  std::vector<std::string> out;
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (est[i].status != CoefficientEstimate::Status::Estimated) continue;
    const auto t = targets.find(coefficient_family(cat[i].name));
    if (t != targets.end() && est[i].sigma > t->second) out.push_back(cat[i].name);
  }
  return out;
}

bool converged(const std::vector<CoefficientEstimate>& est,
               const std::map<std::string, double>& targets) {
  return !targets.empty() && above_target(est, targets).empty();
}

// Upper quantile of chi-square(n) at z standard deviations (Wilson-Hilferty).
double chi2_upper(double n, double z) {
  const double a = 2.0 / (9.0 * n);
  return n * std::pow(1.0 - a + z * std::sqrt(a), 3);
}
}  // namespace

namespace {
KalmanReport run_kalman_pass(const Session& session, const CalibratorOptions& options,
                             SampleSource* source, const KalmanRunOptions& run) {
  const Motion motion = build_motion(session.plan, session.site);
  CalibratorOptions o = options;
  o.table_geometry = session.plan.table;  // the table whose angles a log may carry
  Calibrator kf(motion.dwells(), session.site, o);
  std::unique_ptr<LogReader> reader;
  if (!source) {
    reader = std::make_unique<LogReader>(session.log);
    source = reader.get();
  }
  KalmanReport r;
  if (run.skip_bad_samples) {
    auto* log = dynamic_cast<LogReader*>(source);
    if (!log) throw std::invalid_argument("skipping bad samples needs a log reader");
    log->skip_bad_samples([&r](const BadSampleError& e) {
      ++r.skipped;
      if (r.skipped_examples.size() < KalmanReport::kSkippedExamples)
        r.skipped_examples.push_back(e.what());
    });
  }
  ImuSample s;
  double t_first = 0.0, t_last = 0.0, next_monitor = run.monitor_interval;
  // NIS over a sliding window of updates (constant memory).
  std::deque<std::pair<double, int>> window;
  double window_nis = 0.0;
  int window_dof = 0, seen_updates = 0;
  auto record = [&](double t, const std::vector<CoefficientEstimate>& est) {
    nlohmann::ordered_json rec;
    rec["t"] = t;
    rec["nis_per_dof"] = kf.nis_dof() > 0 ? kf.nis_sum() / kf.nis_dof() : 0.0;
    rec["converged"] = r.converged_at.has_value();
    rec["body_frame"] = kf.layout().accel_triad_frame ? "accelerometer triad" : "table";
    nlohmann::ordered_json c = nlohmann::ordered_json::object();
    for (const auto& [name, e] : coefficients_of(est))
      if (!e.fixed_by_convention) c[name] = {e.value, *e.sigma};
    rec["coefficients"] = c;
    return rec;
  };
  auto stop_requested = [&] { return run.stop && run.stop->load(std::memory_order_relaxed); };
  try {
    while (!stop_requested() && source->next(s)) {
      if (r.samples == 0) {
        t_first = s.t - s.dt;
        next_monitor = t_first + run.monitor_interval;
      }
      t_last = s.t;
      kf.push(s);
      ++r.samples;
      if (kf.updates() != seen_updates) {
        seen_updates = kf.updates();
        window.emplace_back(kf.last_nis(), kf.last_nis_dof());
        window_nis += kf.last_nis();
        window_dof += kf.last_nis_dof();
        if (static_cast<int>(window.size()) > run.nis_window) {
          window_nis -= window.front().first;
          window_dof -= window.front().second;
          window.pop_front();
        }
        if (static_cast<int>(window.size()) == run.nis_window &&
            window_nis > chi2_upper(window_dof, run.nis_alarm_z)) {
          char msg[256];
          std::snprintf(msg, sizeof msg,
                        "filter diverging at t = %.3f s: NIS per dof %.3g over the last %d updates "
                        "(%d dof; a consistent filter stays below %.3g)",
                        s.t, window_nis / window_dof, run.nis_window, window_dof,
                        chi2_upper(window_dof, run.nis_alarm_z) / window_dof);
          r.diverged = msg;
          break;
        }
        if (!r.converged_at && !run.sigma_targets.empty() &&
            converged(kf.estimate(), run.sigma_targets))
          r.converged_at = s.t;
      }
      if (run.monitor && run.monitor_interval > 0.0 && s.t >= next_monitor - 1e-9) {
        run.monitor(record(s.t, kf.estimate()));
        next_monitor += run.monitor_interval;
      }
    }
  } catch (const LogError& e) {
    r.stopped = e.what();
  } catch (const PlanDataMismatch& e) {
    r.stopped = e.what();
  } catch (const std::runtime_error& e) {
    // The filter itself failed (estimates run away until the error model cannot be inverted,
    // an innovation covariance not positive definite): a diverged filter.
    r.diverged = "filter diverged at t = " + std::to_string(t_last) + " s: " + e.what();
  }
  if (stop_requested()) {
    // Stopped by the user (a signal; a read it interrupted may have failed): what was read is
    // the run.
    std::ostringstream m;
    m << "interrupted at t = " << t_last << " s";
    r.stopped = m.str();
    r.interrupted = true;
  }
  const StaticDetector* detector = kf.detector();
  const std::size_t plan_dwells = motion.dwells().size();
  if (detector && r.stopped.empty() && r.diverged.empty() &&
      detector->dwells().size() < plan_dwells) {
    std::ostringstream m;
    m << "the data have " << detector->dwells().size() << " static intervals, the plan "
      << plan_dwells << " dwells: the plan does not match the data";
    r.stopped = m.str();
  }
  // A log that ends before the plan does: the data do not match the plan. The estimates from the
  // data up to there are kept, and the run says so.
  if (!detector && r.stopped.empty() && r.diverged.empty() &&
      (r.samples == 0 || t_last - options.time_offset < motion.duration() - 1.5 * s.dt)) {
    std::ostringstream m;
    m << (source == reader.get() ? session.log.file : std::string("the input"))
      << ": the log ends at t = " << (r.samples ? t_last : 0.0) << " s but the plan runs until "
      << motion.duration() + options.time_offset << " s: the plan does not match the data";
    r.stopped = m.str();
  }
  if (r.diverged.empty()) try {
      kf.finish();
    } catch (const PlanDataMismatch& e) {
      if (r.stopped.empty()) r.stopped = e.what();
    } catch (const std::runtime_error& e) {
      r.diverged = "filter diverged at the last sample: " + std::string(e.what());
    }
  r.duration = t_last - t_first;
  r.states = kf.layout().size;
  r.nis_per_dof = kf.nis_dof() > 0 ? kf.nis_sum() / kf.nis_dof() : 0.0;
  const auto est = kf.estimate();
  r.coefficients = coefficients_of(est);
  for (std::size_t i = 0; i < est.size(); ++i)
    if (est[i].status == CoefficientEstimate::Status::Estimated && !est[i].observed())
      r.unobservable.push_back(coefficient_catalog()[i].name);
  r.above_target = above_target(est, run.sigma_targets);
  r.details["method"] = {
      {"name", "kf"},
      {"states", r.states},
      {"zero_velocity", options.zero_velocity},
      {"zero_velocity_in_motion", options.zero_velocity_in_motion},
      {"position", options.position},
      {"attitude", options.attitude == CalibratorOptions::AttitudeUpdates::Every   ? "every dwell"
                   : options.attitude == CalibratorOptions::AttitudeUpdates::First ? "first dwell"
                                                                                   : "none"},
      {"body_frame", kf.layout().accel_triad_frame ? "accelerometer triad" : "table"},
      {"static_from", detector ? "data" : "plan"},
      {"attitude_from", kf.table_attitude_updates() > 0 ? "table angles" : "plan"},
      {"update_interval_s", options.update_interval}};
  r.details["consistency"] = {{"nis_per_dof", r.nis_per_dof}, {"samples", r.samples}};
  nlohmann::ordered_json conv = {{"targets", !run.sigma_targets.empty()},
                                 {"converged", r.converged_at.has_value()}};
  if (r.converged_at) conv["converged_at_t"] = *r.converged_at;
  conv["above_target"] = r.above_target;
  conv["unobservable"] = r.unobservable;
  r.details["convergence"] = conv;
  if (detector) {
    // Where the data were static against where the plan says: the log's timing, measured.
    nlohmann::ordered_json d = nlohmann::ordered_json::array();
    for (const auto& f : detector->dwells()) {
      const Dwell& p = motion.dwells()[static_cast<std::size_t>(f.index - 1)];
      d.push_back({{"dwell", f.index},
                   {"label", p.label},
                   {"t_start", f.t_start},
                   {"t_end", f.t_end},
                   {"plan_t_start", p.t_start},
                   {"plan_t_end", p.t_end}});
    }
    r.details["static_from_data"] = {
        {"gyro_bound_deg_per_s", detector->gyro_bound() / units::deg_per_s},
        {"accel_bound_ug", detector->accel_bound() / units::ug},
        {"rate_threshold_deg_per_s", detector->rate_threshold() / units::deg_per_s},
        {"window_s", options.detector.window},
        {"dwells", d}};
  }
  if (r.skipped > 0)
    r.details["skipped_samples"] = {{"count", r.skipped}, {"first", r.skipped_examples}};
  if (!r.diverged.empty()) r.details["diverged"] = {{"reason", r.diverged}, {"t", t_last}};
  if (!r.stopped.empty())
    r.details["stopped"] = {
        {"reason", r.stopped}, {"last_good_t", t_last}, {"interrupted", r.interrupted}};
  r.model = kf.model();
  return r;
}
}  // namespace

KalmanReport run_kalman(const Session& session, const CalibratorOptions& options,
                        SampleSource* source, const KalmanRunOptions& run) {
  if (run.passes <= 1) return run_kalman_pass(session, options, source, run);
  if (source) throw std::invalid_argument("several passes need the session's log, not a stream");
  // Earlier passes: quiet, no alarm (their linearization is what the later passes improve).
  KalmanRunOptions quiet = run;
  quiet.monitor = nullptr;
  quiet.monitor_interval = 0.0;
  quiet.nis_alarm_z = std::numeric_limits<double>::infinity();
  CalibratorOptions o = options;
  nlohmann::ordered_json passes = nlohmann::ordered_json::array();
  KalmanReport previous;
  for (int pass = 1; pass <= run.passes; ++pass) {
    const bool last = pass == run.passes;
    KalmanReport r = run_kalman_pass(session, o, nullptr, last ? run : quiet);
    nlohmann::ordered_json p = {{"pass", pass}, {"nis_per_dof", r.nis_per_dof}};
    if (pass > 1) {
      // How far this pass moved the estimates, in this pass's sigmas.
      double moved = 0.0;
      for (const auto& [name, c] : r.coefficients) {
        const auto prev = previous.coefficients.find(name);
        if (prev == previous.coefficients.end() || !c.sigma || !(*c.sigma > 0.0)) continue;
        if (!c.observable || !prev->second.observable || c.fixed_by_convention) continue;
        moved = std::max(moved, std::abs(c.value - prev->second.value) / *c.sigma);
      }
      p["largest_change_over_sigma"] = moved;
    }
    passes.push_back(p);
    if (last || !r.stopped.empty() || !r.diverged.empty()) {  // bad input, an interruption
      r.details["method"]["passes"] = run.passes;
      r.details["passes"] = passes;
      return r;
    }
    o.initial_model = r.model;
    previous = std::move(r);
  }
  return previous;  // not reached
}

}  // namespace sinscal
