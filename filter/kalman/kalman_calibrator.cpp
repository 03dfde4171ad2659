#include "filter/kalman/kalman_calibrator.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <memory>
#include <sstream>

#include "models/attitude.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "rig/io/log_io.hpp"
#include "rig/plan.hpp"

namespace sinscal {

CalibratorOptions calibrator_options_from_profile(const SensorProfile& profile,
                                                  double prior_scale) {
  if (!(prior_scale > 0.0)) throw std::invalid_argument("the prior scale must be positive");
  CalibratorOptions o;
  o.noise = profile.noise;
  o.prior_scale = prior_scale;
  o.reference_temperature_c = profile.reference_temperature_c;
  for (const auto& f : coefficient_families())
    if (!f.base && profile.has(f.name)) o.layout.extended.insert(f.name);
  const auto& cat = coefficient_catalog();
  o.initial_sigma.assign(cat.size(), 0.0);
  for (std::size_t i = 0; i < cat.size(); ++i) {
    const auto it = profile.ranges.find(cat[i].family);
    if (it != profile.ranges.end() && it->second.present())
      o.initial_sigma[i] = prior_scale * std::max(std::abs(it->second.lo), std::abs(it->second.hi));
  }
  return o;
}

bool gyros_find_north(const CalibratorOptions& o) {
  const auto& cat = coefficient_catalog();
  for (std::size_t c = 0; c < cat.size(); ++c) {
    if (cat[c].family != "gyro.bias") continue;
    double sigma = o.initial_sigma.size() > c ? o.initial_sigma[c] : 0.0;
    if (!(sigma > 0.0)) sigma = coefficient_family_info(cat[c].family).default_prior;
    if (!(sigma < kNorthSeekingBiasRatio * Earth::wgs84().rate())) return false;
  }
  return true;
}

bool follows_plan_motion(const CalibratorOptions& o) {
  return o.static_from == CalibratorOptions::StaticFrom::Plan &&
         o.attitude != CalibratorOptions::AttitudeUpdates::None && o.zero_velocity_in_motion;
}

bool motion_from_data_applies(const CalibratorOptions& o) {
  return o.attitude != CalibratorOptions::AttitudeUpdates::None && o.zero_velocity_in_motion;
}

double initial_attitude_sigma(const CalibratorOptions& o) {
  if (o.initial_attitude_sigma > 0.0) return o.initial_attitude_sigma;
  return kDefaultStartAttitudeSigma;
}

StateLayoutOptions effective_layout(const CalibratorOptions& o) {
  StateLayoutOptions l = o.layout;
  if (o.attitude == CalibratorOptions::AttitudeUpdates::None) l.accel_triad_frame = true;
  // Only an attitude update relates the navigation to the base.
  l.base_attitude = o.base_attitude && o.attitude != CalibratorOptions::AttitudeUpdates::None;
  l.dwell_orientation = o.attitude_hold && o.attitude != CalibratorOptions::AttitudeUpdates::None;
  auto gauss_markov = [](const TriadNoise& tn) {
    return tn.bias_instability > 0.0 && tn.correlation_time > 0.0;
  };
  l.bias_wander =
      o.bias_wander_states && (gauss_markov(o.noise.gyro) || gauss_markov(o.noise.accel));
  return l;
}

Calibrator::Calibrator(PlanTimeline timeline, const Site& site, const CalibratorOptions& options)
    : dwells_(std::move(timeline.dwells)),
      site_(site),
      site_terms_(InsSiteTerms::at(site)),
      o_(options),
      layout_(StateLayout::make(effective_layout(options))),
      propagator_(layout_, site_terms_, options.noise),
      table_(timeline.table) {
  if (dwells_.empty()) throw std::invalid_argument("the Kalman calibrator needs the plan's dwells");
  initialize_covariance();
  if (o_.initial_model) model_ = *o_.initial_model;
  inverses_ = model_.linear_inverses();
  model_.reference_temperature_c = o_.reference_temperature_c;
  for (const auto& f : coefficient_families())
    if (f.thermal() && layout_.block(f.name)) thermal_ = true;
  C_base_ = dcm_from_rotvec(o_.initial_base_n);
  C_reference_base_ = C_base_;
  C_reference_mounting_ = dcm_from_rotvec(o_.start_mounting_b);
  if (o_.static_from == CalibratorOptions::StaticFrom::Data)
    detector_.emplace(o_.noise, o_.detector);
}

void Calibrator::initialize_covariance() {
  const int n = layout_.size;
  const auto& cat = coefficient_catalog();
  prior_sigma_.assign(cat.size(), 0.0);
  P_ = Eigen::MatrixXd::Zero(n, n);
  auto diagonal = [&](const Block& b, double sigma) {
    P_.diagonal().segment(b.index, b.size).setConstant(sigma * sigma);
  };
  diagonal(layout_.attitude, initial_attitude_sigma(o_));
  diagonal(layout_.velocity, kStartVelocitySigma);
  diagonal(layout_.position, kStartPositionSigma);
  if (StateLayout::on(layout_.base)) {
    // The navigation starts from the base's estimate: its error is the start attitude's too
    // (phi_n = -d_base + the table's own start error).
    // Gyros that cannot find North (MEMS) leave the base heading to the plan, to the table's
    // accuracy: estimated from 5 deg, it wandered by degrees and passes did not settle.
    const Eigen::Vector3d sigma(kBaseLevelPriorSigma, kBaseLevelPriorSigma,
                                gyros_find_north(o_) ? kBaseHeadingPriorSigma : o_.attitude_sigma);
    const Eigen::Matrix3d P_base = sigma.array().square().matrix().asDiagonal();
    const int a = layout_.attitude.index, b = layout_.base.index;
    P_.block<3, 3>(b, b) = P_base;
    P_.block<3, 3>(a, a) += P_base;
    P_.block<3, 3>(a, b) = -P_base;
    P_.block<3, 3>(b, a) = -P_base;
  }
  if (StateLayout::on(layout_.wander))
    for (int i = 0; i < 6; ++i) {
      const TriadNoise& tn = i < 3 ? o_.noise.gyro : o_.noise.accel;
      if (tn.correlation_time > 0.0)  // stationary
        P_(layout_.wander.index + i, layout_.wander.index + i) =
            tn.bias_instability * tn.bias_instability;
    }
  for (const auto& cb : layout_.coefficients)
    for (int k = 0; k < cb.block.size; ++k) {
      const auto c = static_cast<std::size_t>(cb.catalog[static_cast<std::size_t>(k)]);
      double s0 = o_.initial_sigma.size() > c ? o_.initial_sigma[c] : 0.0;
      if (!(s0 > 0.0)) s0 = coefficient_family_info(cb.family).default_prior;
      P_(cb.block.index + k, cb.block.index + k) = s0 * s0;
      prior_sigma_[c] = s0;
    }
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
  propagator_.flush();
}

void Calibrator::process(const ImuSample& s, const Eigen::Vector3d& omega_dot_raw,
                         const Eigen::Vector3d& f_dot_raw, const Eigen::Vector3d& f_ddot_raw) {
  current_ = s;
  if (!started_ && thermal_ && !s.has_temperature)
    throw std::invalid_argument(
        "thermal coefficients are estimated (the sensor profile or --terms) but the log has no "
        "temperature column (docs/formats.md \"Temperature columns\")");
  if (!started_) {
    nav_.reset(NavState::at_rest(
        C_base_ *
            (s.has_table && o_.use_table_angles ? table_.C_b_n({s.table_outer, s.table_inner})
                                                : dwells_.front().C_b_n_known) *
            dcm_from_rotvec(o_.start_mounting_b),
        site_));
    started_ = true;
    if (pending_error_.size() > 0) inject_error(pending_error_);
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
  // The rates of change are differences of the outputs: the inputs' are the model's linear part
  // inverted (without it, the delay correction below would carry tau (A - I) f_dot).
  const Eigen::Vector3d omega_dot = inverses_.gyro * omega_dot_raw;
  const Eigen::Vector3d f_dot = inverses_.accel * f_dot_raw;
  const Eigen::Vector3d f_ddot = inverses_.accel * f_ddot_raw;
  // Compensate with the current estimate (mean rates over the interval, at its middle).
  KinematicSample k;
  k.omega_dot_ib_b = omega_dot;
  k.t = s.t - 0.5 * dt - o_.time_offset;
  if (s.has_temperature) {
    k.accel_dtemp = s.accel_temperature_c - model_.reference_temperature_c;
    k.gyro_dtemp = s.gyro_temperature_c - model_.reference_temperature_c;
    k.gyro_dtemp_rate = temperature_rate_.add(s.t, s.gyro_temperature_c);
  }
  model_.compensate(s.dtheta_b / dt, s.dv_b / dt, omega_dot, k.omega_ib_b, k.f_ib_b, k.t, &k,
                    &inverses_);
  remove_wander(k, dt);
  // Accelerometers late by tau: f(t) = f_meas(t + tau), to second order.
  const double tau = model_.time_delay;
  k.f_ib_b += tau * f_dot + 0.5 * tau * tau * f_ddot;
  const Eigen::Quaterniond q_before = nav_.state().q_b_n;
  nav_.step(k.omega_ib_b * dt, k.f_ib_b * dt, dt);
  // The interval's mean rates act at its middle: the error dynamics take the attitude there (the
  // end attitude would rotate the specific force by half the interval's turn, a spurious
  // heading-velocity coupling of g omega dt / 2 while the table turns).
  const Eigen::Quaterniond q_mid = q_before.slerp(0.5, nav_.state().q_b_n);
  const Eigen::Matrix3d C_mid = q_mid.toRotationMatrix();
  if (o_.reference_motion)
    step_along_reference(k, f_dot, dt);
  else
    propagator_.step(C_mid, k, f_dot, model_, inverses_, dt);
  if (propagator_.accumulated() >= o_.update_interval - 1e-9) {
    propagator_.propagate(P_);
    update(s.t - o_.time_offset);
  }
}

void Calibrator::step_along_reference(const KinematicSample& k, const Eigen::Vector3d& f_dot,
                                      double dt) {
  // The output error J(x) dtheta is exact at the true input x, and the coefficient errors act
  // through the true attitude. The table's motion gives both without the sensor noise and
  // without the current estimate (a fixed linearization point), in the IMU's axes (the start's
  // mounting and base). So does the specific force of the f_n x phi term, in navigation axes
  // (gravity and the motion's own, whatever the base and mounting): the navigator's carries
  // the accelerometers' noise, and noise times the heading error (unobserved at rest, degrees
  // for a MEMS unit) gave the filter information on the vertical gyro's bias that the data do
  // not hold (its estimate left the truth by 6 of its sigmas within the first dwell).
  const KinematicState ref = o_.reference_motion->at(k.t);
  KinematicSample k_ref = k;
  k_ref.omega_ib_b = C_reference_mounting_.transpose() * ref.imu.omega_ib_b;
  k_ref.omega_dot_ib_b = C_reference_mounting_.transpose() * ref.imu.omega_dot_ib_b;
  k_ref.f_ib_b = C_reference_mounting_.transpose() * ref.imu.f_ib_b;
  const Eigen::Matrix3d C_ref = C_reference_base_ * ref.C_b_n * C_reference_mounting_;
  // The time delay's column is the specific force's rate of change: along the motion, gravity
  // turning in the IMU's axes, -omega_nb_b x f_ib_b, without the accelerometers' noise that
  // the measured difference of two samples carries (docs/methods/kalman-filter.md).
  const Eigen::Vector3d f_dot_ref =
      o_.delay_from_reference
          ? Eigen::Vector3d(
                -(C_reference_mounting_.transpose() * ref.omega_nb_b).cross(k_ref.f_ib_b))
          : f_dot;
  propagator_.step(C_ref, k_ref, f_dot_ref, model_, inverses_, dt, ref.C_b_n * ref.imu.f_ib_b);
}

void Calibrator::remove_wander(KinematicSample& k, double dt) {
  if (!StateLayout::on(layout_.wander)) return;
  // The bias wander's estimate, decaying towards zero as the Gauss-Markov process does.
  k.omega_ib_b -= wander_.head<3>();
  k.f_ib_b -= wander_.tail<3>();
  if (dt != wander_dt_) {  // the sample interval changes rarely: the decay once per change
    wander_dt_ = dt;
    for (int i = 0; i < 6; ++i) {
      const TriadNoise& tn = i < 3 ? o_.noise.gyro : o_.noise.accel;
      wander_decay_(i) = tn.correlation_time > 0.0 ? std::exp(-dt / tn.correlation_time) : 1.0;
    }
  }
  wander_ = wander_.cwiseProduct(wander_decay_);
}

void Calibrator::inject_error(const Eigen::VectorXd& dx) {
  if (dx.size() != layout_.size)
    throw std::invalid_argument("inject_error: the error has " + std::to_string(dx.size()) +
                                " states, the layout " + std::to_string(layout_.size));
  if (!started_) {
    pending_error_ = dx;
    return;
  }
  NavState x = nav_.state();
  sinscal::inject_error(layout_, site_terms_, dx, x, model_);
  inverses_ = model_.linear_inverses();
  inject_base_error(layout_, dx, C_base_);
  inject_dwell_orientation_error(layout_, dx, C_dwell_);
  if (StateLayout::on(layout_.wander)) wander_ -= dx.segment<6>(layout_.wander.index);
  nav_.correct(x);
  pending_error_.resize(0);
}

Eigen::Matrix3d Calibrator::dwell_attitude(const PlanDwell& dwell) {
  if (!current_.has_table || !o_.use_table_angles) return dwell.C_b_n_known;
  // The attitude the table's angles give, checked against the plan's orientation.
  Eigen::Matrix3d C_table = table_.C_b_n({current_.table_outer, current_.table_inner});
  const double apart = rotvec_from_dcm(C_table * dwell.C_b_n_known.transpose()).norm();
  if (apart > o_.table_plan_tolerance) {
    std::ostringstream m;
    m << "dwell " << dwell.index << " (" << dwell.label << ") at t = " << current_.t
      << " s: the table's angles (outer " << current_.table_outer / units::deg << " deg, inner "
      << current_.table_inner / units::deg << " deg) put the IMU " << apart / units::deg
      << " deg from the plan's orientation: the plan does not match the data";
    throw PlanDataMismatch(m.str());
  }
  ++table_updates_;
  return C_table;
}

void Calibrator::update(double t_plan) {
  for (const auto& [t0, t1] : o_.holdout)
    if (t_plan >= t0 && t_plan <= t1) {
      after_holdout_ = true;
      return;
    }
  if (after_holdout_) {
    after_holdout_ = false;
    holdout_.push_back({t_plan, 0.0, 0, Eigen::Vector3d::Zero()});
  }
  const PlanDwell* dwell = nullptr;
  if (detector_) {
    if (detector_->dwell() > 0) dwell = &dwells_[static_cast<std::size_t>(detector_->dwell() - 1)];
  } else {
    for (const auto& d : dwells_)
      if (t_plan >= d.t_start + o_.static_margin && t_plan <= d.t_end - o_.static_margin)
        dwell = &d;
  }
  const NavState& x = nav_.state();
  in_dwell_ = dwell != nullptr;
  if (!dwell) {
    // Turning about the IMU reference point: zero velocity holds, the attitude is not known.
    if (o_.zero_velocity_in_motion) apply(zero_velocity(layout_, x, o_.motion_velocity_sigma));
    return;
  }
  Measurement m;
  if (o_.zero_velocity) m.append(zero_velocity(layout_, x, o_.velocity_sigma));
  if (o_.position) m.append(known_position(layout_, x, site_, o_.position_sigma));
  const bool attitude_wanted =
      o_.attitude == CalibratorOptions::AttitudeUpdates::Every ||
      (o_.attitude == CalibratorOptions::AttitudeUpdates::First && dwell->index == 1);
  if (attitude_wanted && StateLayout::on(layout_.dwell_orientation)) {
    if (dwell->index > attitude_dwell_done_) {
      // A new dwell: the table's orientation error drawn anew (the last dwell's marginalized).
      const int d = layout_.dwell_orientation.index;
      P_.middleRows(d, 3).setZero();
      P_.middleCols(d, 3).setZero();
      P_.block<3, 3>(d, d).diagonal().setConstant(o_.attitude_sigma * o_.attitude_sigma);
      C_dwell_.setIdentity();
      attitude_dwell_done_ = dwell->index;
    }
    m.append(known_attitude(layout_, x, dwell_attitude(*dwell), o_.hold_sigma, C_base_, C_dwell_));
  } else if (attitude_wanted && dwell->index > attitude_dwell_done_) {
    m.append(known_attitude(layout_, x, dwell_attitude(*dwell), o_.attitude_sigma, C_base_));
    attitude_dwell_done_ = dwell->index;
  }
  apply(m);
}

void Calibrator::extend_timeline(const PlanTimeline& longer) {
  bool prefix = longer.dwells.size() >= dwells_.size();
  for (std::size_t i = 0; prefix && i < dwells_.size(); ++i)
    prefix = std::abs(longer.dwells[i].t_start - dwells_[i].t_start) < 1e-9 &&
             std::abs(longer.dwells[i].t_end - dwells_[i].t_end) < 1e-9;
  if (!prefix)
    throw std::invalid_argument(
        "extend_timeline: the longer plan's dwells do not begin with the "
        "plan's so far");
  dwells_ = longer.dwells;
}

void Calibrator::apply(const Measurement& m) {
  if (m.empty()) return;
  const int r = m.rows(), n = layout_.size;
  const Eigen::Map<const Eigen::VectorXd> z(m.z.data(), r);
  const Eigen::VectorXd R = Eigen::Map<const Eigen::VectorXd>(m.sigma.data(), r).array().square();
  // H's rows are a state or a difference of two: H P is (differences of) rows of P, X H^T
  // (differences of) columns of X (no products with H).
  auto rows_of = [&](const Eigen::MatrixXd& X, Eigen::MatrixXd& out) {
    for (int i = 0; i < r; ++i) {
      const auto k = static_cast<std::size_t>(i);
      out.row(i) = X.row(m.states[k]);
      if (m.minus_states[k] >= 0) out.row(i) -= X.row(m.minus_states[k]);
      if (m.minus_states_2[k] >= 0) out.row(i) -= X.row(m.minus_states_2[k]);
    }
  };
  auto columns_of = [&](const Eigen::MatrixXd& X, Eigen::MatrixXd& out) {
    for (int j = 0; j < r; ++j) {
      const auto k = static_cast<std::size_t>(j);
      out.col(j) = X.col(m.states[k]);
      if (m.minus_states[k] >= 0) out.col(j) -= X.col(m.minus_states[k]);
      if (m.minus_states_2[k] >= 0) out.col(j) -= X.col(m.minus_states_2[k]);
    }
  };
  Eigen::MatrixXd HP(r, n);
  rows_of(P_, HP);
  Eigen::MatrixXd S(r, r);
  columns_of(HP, S);
  S.diagonal() += R;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success)
    throw std::runtime_error("Kalman update: innovation covariance not positive definite");
  const Eigen::MatrixXd K = llt.solve(HP).transpose();
  last_nis_ = z.dot(llt.solve(z));
  last_nis_dof_ = r;
  record_innovations(m, z, S);
  if (!holdout_.empty() && holdout_.back().dof == 0) {
    HoldoutPrediction& h = holdout_.back();
    h.nis = last_nis_;
    h.dof = r;
    for (int i = 0; i < r; ++i) {
      const int v = m.states[static_cast<std::size_t>(i)] - layout_.velocity.index;
      if (m.minus_states[static_cast<std::size_t>(i)] < 0 && v >= 0 && v < 3)
        h.velocity_innovation(v) = z(i);
    }
  }
  nis_sum_ += last_nis_;
  nis_dof_ += r;
  // Prediction-error decomposition: log N(z; 0, S) summed over the updates (log 2 pi dropped).
  log_likelihood_ -= 0.5 * (last_nis_ + 2.0 * llt.matrixLLT().diagonal().array().log().sum());
  ++updates_;
  // Joseph form (I - K H) P (I - K H)^T + K R K^T = P - K (H P) - (K (H P))^T + K S K^T (P
  // symmetric), symmetrized: two products of n x r by r x n.
  work_KHP_.noalias() = K * HP;
  work_KSK_.noalias() = (K * S) * K.transpose();
  work_KSK_ -= work_KHP_;
  work_KSK_ -= work_KHP_.transpose();
  P_ += 0.5 * (work_KSK_ + work_KSK_.transpose());
  NavState x = nav_.state();
  const Eigen::VectorXd dx = K * z;
  feed_back(layout_, site_terms_, dx, x, model_);
  inverses_ = model_.linear_inverses();
  feed_back_base(layout_, dx, C_base_);
  feed_back_dwell_orientation(layout_, dx, C_dwell_);
  if (StateLayout::on(layout_.wander)) wander_ += dx.segment<6>(layout_.wander.index);
  // Keep the coning/sculling memory: the correction is tiny and the increments unchanged.
  nav_.correct(x);
}

void Calibrator::record_innovations(const Measurement& m, const Eigen::VectorXd& z,
                                    const Eigen::MatrixXd& S) {
  for (int i = 0; i < m.rows(); ++i) {
    const int state = m.states[static_cast<std::size_t>(i)];
    InnovationKind kind = InnovationKind::Attitude;
    int axis = state - layout_.attitude.index;
    if (state >= layout_.velocity.index && state < layout_.velocity.index + layout_.velocity.size) {
      kind = in_dwell_ ? InnovationKind::VelocityDwells : InnovationKind::VelocityTurns;
      axis = state - layout_.velocity.index;
    } else if (state >= layout_.position.index &&
               state < layout_.position.index + layout_.position.size) {
      kind = InnovationKind::Position;
      axis = state - layout_.position.index;
    }
    innovations_.add(kind, axis, z(i) / std::sqrt(S(i, i)));
  }
}

std::vector<CoefficientEstimate> Calibrator::estimate() const {
  ImuErrorModel copy = model_;
  const auto refs = copy.coefficient_refs();
  std::vector<CoefficientEstimate> out(refs.size());
  for (std::size_t c = 0; c < refs.size(); ++c) {
    out[c].value = *refs[c].second;
    const int xs = layout_.state_of[c];
    out[c].sigma = xs >= 0 ? std::sqrt(P_(xs, xs)) : 0.0;
    out[c].status =
        xs >= 0 ? CoefficientEstimate::Status::Estimated : CoefficientEstimate::Status::Off;
    out[c].prior_sigma = prior_sigma_[c];
  }
  for (int c : layout_.fixed_by_convention())
    out[static_cast<std::size_t>(c)].status = CoefficientEstimate::Status::FixedByConvention;
  return out;
}

}  // namespace sinscal
