#include "filter/kalman/kalman_run.hpp"

#include <Eigen/Eigenvalues>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <memory>
#include <sstream>
#include <tuple>

#include "filter/installation/stream_alignment.hpp"
#include "models/attitude.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "rig/plan.hpp"

namespace sinscal {

std::string UnobservableDirection::text() const {
  std::string out;
  for (const auto& [name, w] : components) {
    char buf[128];
    std::snprintf(buf, sizeof buf, "%s%+.3f %s", out.empty() ? "" : " ", w, name.c_str());
    out += buf;
  }
  return out;
}

std::vector<std::string> above_target(const std::vector<CoefficientEstimate>& est,
                                      const std::map<std::string, double>& targets) {
  std::vector<std::string> out;
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (est[i].status != CoefficientEstimate::Status::Estimated) continue;
    const auto t = targets.find(cat[i].family);
    if (t != targets.end() && est[i].sigma > t->second) out.push_back(cat[i].name);
  }
  return out;
}

namespace {

bool converged(const std::vector<CoefficientEstimate>& est,
               const std::map<std::string, double>& targets) {
  return !targets.empty() && above_target(est, targets).empty();
}

/// The divergence alarm: the NIS summed over a sliding window of updates against the upper
/// chi-square quantile at the normal tail probability of `z` standard deviations (constant
/// memory).
class NisWatch {
 public:
  NisWatch(int window, double z)
      : window_(window),
        tail_(std::isfinite(z) ? boost::math::cdf(boost::math::complement(
                                     boost::math::normal_distribution<double>(), z))
                               : 0.0) {}
  /// Adds one update; true when the window is full and its NIS beyond the quantile, or at once
  /// when the NIS is not a number (estimates run away to infinities: a NaN compares false with
  /// any bound, and a later pass of a diverged log exited 0 with NIS per dof -nan; APOPHIS,
  /// issue 34), even with the alarm off.
  bool add(double nis, int dof) {
    if (!std::isfinite(nis)) {
      not_finite_ = true;
      return true;
    }
    updates_.emplace_back(nis, dof);
    sum_ += nis;
    dof_ += dof;
    if (static_cast<int>(updates_.size()) > window_) {
      sum_ -= updates_.front().first;
      dof_ -= updates_.front().second;
      updates_.pop_front();
    }
    return static_cast<int>(updates_.size()) == window_ && tail_ > 0.0 && sum_ > limit();
  }
  double limit() const {
    return boost::math::quantile(
        boost::math::complement(boost::math::chi_squared_distribution<double>(dof_), tail_));
  }
  std::string message(double t) const {
    char msg[256];
    if (not_finite_) {
      std::snprintf(msg, sizeof msg,
                    "filter diverged at t = %.3f s: its NIS is not a number (the estimates ran "
                    "away)",
                    t);
      return msg;
    }
    std::snprintf(msg, sizeof msg,
                  "filter diverging at t = %.3f s: NIS per dof %.3g over the last %d updates "
                  "(%d dof; a consistent filter stays below %.3g)",
                  t, sum_ / dof_, window_, dof_, limit() / dof_);
    return msg;
  }

 private:
  int window_;
  double tail_;
  std::deque<std::pair<double, int>> updates_;
  double sum_ = 0.0;
  int dof_ = 0;
  bool not_finite_ = false;
};

// The filter estimates relative to the table and the run reports in the triad frame.
bool converts_to_triad(const CalibratorOptions& o) {
  return reported_frame(o) == MisalignmentFrame::Triad && !effective_layout(o).accel_triad_frame;
}

// The covariance of the coefficient states and their catalog indices, by the layout's blocks.
std::pair<Eigen::MatrixXd, std::vector<int>> coefficient_covariance(const Calibrator& kf) {
  std::vector<int> states, catalog;
  for (const auto& cb : kf.layout().coefficients)
    for (int k = 0; k < cb.block.size; ++k) {
      states.push_back(cb.block.index + k);
      catalog.push_back(cb.catalog[static_cast<std::size_t>(k)]);
    }
  const auto n = static_cast<Eigen::Index>(states.size());
  Eigen::MatrixXd P(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      P(i, j) =
          kf.covariance()(states[static_cast<std::size_t>(i)], states[static_cast<std::size_t>(j)]);
  return {P, catalog};
}

// Estimates and their covariance (rows: `catalog`) turned into the triad frame: values, sigmas,
// the three coefficients the convention fixes.
void estimates_to_triad_frame(std::vector<CoefficientEstimate>& est, Eigen::MatrixXd& P,
                              std::vector<int>& catalog) {
  Eigen::VectorXd values(static_cast<Eigen::Index>(est.size()));
  for (std::size_t c = 0; c < est.size(); ++c) values(static_cast<Eigen::Index>(c)) = est[c].value;
  TriadFrameEstimate t = to_accel_triad_frame(values, P, catalog);
  for (std::size_t c = 0; c < est.size(); ++c)
    est[c].value = t.values(static_cast<Eigen::Index>(c));
  for (std::size_t i = 0; i < t.catalog.size(); ++i)
    est[static_cast<std::size_t>(t.catalog[i])].sigma = std::sqrt(
        std::max(0.0, t.covariance(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(i))));
  for (int c : triad_fixed_coefficients()) {
    auto& e = est[static_cast<std::size_t>(c)];
    if (e.status == CoefficientEstimate::Status::Off) continue;
    e.status = CoefficientEstimate::Status::FixedByConvention;
    e.value = e.sigma = 0.0;
  }
  P = std::move(t.covariance);
  catalog = std::move(t.catalog);
}

// The filter's estimates in the frame the run reports.
std::vector<CoefficientEstimate> reported_estimates(const Calibrator& kf,
                                                    const CalibratorOptions& o) {
  std::vector<CoefficientEstimate> est = kf.estimate();
  if (!converts_to_triad(o)) return est;
  auto [P, catalog] = coefficient_covariance(kf);
  estimates_to_triad_frame(est, P, catalog);
  return est;
}

MonitorRecord monitor_record(const Calibrator& kf, const CalibratorOptions& o, double t,
                             bool converged_now) {
  return {t, kf.nis_dof() > 0 ? kf.nis_sum() / kf.nis_dof() : 0.0, converged_now,
          kf.layout().accel_triad_frame || converts_to_triad(o), reported_estimates(kf, o)};
}

// The samples through the filter, with the supervision of each update: divergence alarm,
// convergence, monitor records, interruption. Fills what the loop learns into `r`.
void read_samples(Calibrator& kf, SampleSource& source, const KalmanRunOptions& run, KalmanRun& r,
                  const CalibratorOptions& o) {
  NisWatch watch(run.nis_window, run.nis_alarm_z);
  ImuSample s;
  double t_first = 0.0, next_monitor = run.monitor_interval;
  int seen_updates = 0;
  auto stop_requested = [&] { return run.stop && run.stop->load(std::memory_order_relaxed); };
  // Samples a stream held for its alignment were read: the filter takes them even after a stop.
  const auto* held = dynamic_cast<const HeldStream*>(&source);
  try {
    while ((!stop_requested() || (held && held->replaying())) && source.next(s)) {
      if (r.samples == 0) {
        t_first = s.t - s.dt;
        next_monitor = t_first + run.monitor_interval;
      }
      r.t_last = s.t;
      kf.push(s);
      ++r.samples;
      if (kf.updates() != seen_updates) {
        seen_updates = kf.updates();
        if (watch.add(kf.last_nis(), kf.last_nis_dof())) {
          r.diverged = watch.message(s.t);
          break;
        }
        if (!r.converged_at && !run.sigma_targets.empty() &&
            converged(reported_estimates(kf, o), run.sigma_targets))
          r.converged_at = s.t;
      }
      if (run.monitor && run.monitor_interval > 0.0 && s.t >= next_monitor - 1e-9) {
        run.monitor(monitor_record(kf, o, s.t, r.converged_at.has_value()));
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
    r.diverged = "filter diverged at t = " + std::to_string(r.t_last) + " s: " + e.what();
  }
  if (stop_requested()) {
    // Stopped by the user (a signal; a read it interrupted may have failed): what was read is
    // the run.
    std::ostringstream m;
    m << "interrupted at t = " << r.t_last << " s";
    r.stopped = m.str();
    r.interrupted = true;
  }
  r.duration = r.t_last - t_first;
}

// The data against the plan once the input ended: as many static intervals as dwells, a log as
// long as the plan.
void check_against_plan(const Calibrator& kf, const PlanTimeline& timeline,
                        const std::string& input, double time_offset, double last_dt,
                        KalmanRun& r) {
  if (!r.stopped.empty() || !r.diverged.empty()) return;
  std::ostringstream m;
  if (const StaticDetector* detector = kf.detector()) {
    if (detector->dwells().size() < timeline.dwells.size()) {
      // The detector's bounds come from the sensor profile's noise: outputs at rest noisier than
      // that (a real BMI160 table log whose gyro toggles between two levels 1 deg/s apart: no
      // rest in any pass, while the message blamed the plan alone; APOPHIS, issue 34) are never
      // still.
      m.precision(3);
      m << input << ": the data have " << detector->dwells().size()
        << " static intervals, the plan " << timeline.dwells.size()
        << " dwells: the plan does not match the data, or the outputs at rest scatter beyond "
           "the detector's bounds from the sensor profile's noise (rates within "
        << detector->gyro_bound() / units::deg_per_s << " deg/s and specific forces within "
        << detector->accel_bound() / units::ug << " ug of their mean, a mean rate below "
        << detector->rate_threshold() / units::deg_per_s << " deg/s)";
      r.stopped = m.str();
    }
    return;
  }
  // A log that ends before the plan does: the estimates from the data up to there are kept.
  if (r.samples == 0 || r.t_last - time_offset < timeline.duration - 1.5 * last_dt) {
    m << input << ": the log ends at t = " << (r.samples ? r.t_last : 0.0)
      << " s but the plan runs until " << timeline.duration + time_offset
      << " s: the plan does not match the data";
    r.stopped = m.str();
  }
}

// Combinations of coefficient states whose variance the data did not bring below half the
// prior's: eigen-decomposition of the coefficient covariance normalized by the prior sigmas.
// `P`: the covariance of the coefficient states, `catalog` the catalog index of each row (the
// filter's own frame, or the triad frame after the conversion: the names are the frame's).
std::vector<UnobservableDirection> unobservable_directions(const Eigen::MatrixXd& P,
                                                           const std::vector<int>& catalog,
                                                           std::vector<CoefficientEstimate>& est) {
  const auto m = static_cast<int>(catalog.size());
  Eigen::VectorXd d(m);
  for (int k = 0; k < m; ++k)
    d(k) = 1.0 / est[static_cast<std::size_t>(catalog[static_cast<std::size_t>(k)])].prior_sigma;
  const Eigen::MatrixXd M = d.asDiagonal() * P * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(M);
  std::vector<UnobservableDirection> out;
  const auto& cat = coefficient_catalog();
  for (int k = m - 1; k >= 0 && es.eigenvalues()(k) > kUnobservedVarianceRatio; --k) {
    Eigen::VectorXd v = es.eigenvectors().col(k);
    Eigen::Index lead = 0;
    v.cwiseAbs().maxCoeff(&lead);
    if (v(lead) < 0.0) v = -v;
    UnobservableDirection u;
    u.remaining = es.eigenvalues()(k);
    for (int i = 0; i < m; ++i) {
      if (v(i) * v(i) < kUnobservedWeight) continue;
      const auto c = static_cast<std::size_t>(catalog[static_cast<std::size_t>(i)]);
      u.components.emplace_back(cat[c].name, v(i));
      est[c].in_unobservable_direction = true;
    }
    out.push_back(u);
  }
  return out;
}

// The run's result from the filter at its end.
void summarize(const Calibrator& kf, const PlanTimeline& timeline, const KalmanRunOptions& run,
               KalmanRun& r) {
  r.states = kf.layout().size;
  r.accel_triad_frame = kf.layout().accel_triad_frame;
  r.nis_per_dof = kf.nis_dof() > 0 ? kf.nis_sum() / kf.nis_dof() : 0.0;
  r.log_likelihood = kf.log_likelihood();
  r.innovations = innovation_check(kf.innovations());
  std::tie(r.coefficient_covariance, r.covariance_catalog) = coefficient_covariance(kf);
  r.estimates = kf.estimate();
  r.unobservable_directions =
      unobservable_directions(r.coefficient_covariance, r.covariance_catalog, r.estimates);
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < r.estimates.size(); ++i)
    if (r.estimates[i].status == CoefficientEstimate::Status::Estimated &&
        !r.estimates[i].observed())
      r.unobservable.push_back(cat[i].name);
  r.has_targets = !run.sigma_targets.empty();
  r.above_target = above_target(r.estimates, run.sigma_targets);
  r.table_attitude_updates = kf.table_attitude_updates();
  r.holdout = kf.holdout_predictions();
  InstallationResult& in = r.installation;
  in.base_estimated = StateLayout::on(kf.layout().base);
  in.base_known = !r.options.base_attitude;
  in.base_n = rotvec_from_dcm(kf.base());
  if (in.base_estimated)
    in.base_sigma_n = kf.covariance().diagonal().segment<3>(kf.layout().base.index).cwiseSqrt();
  in.mounting_estimated = !kf.layout().accel_triad_frame;
  if (in.mounting_estimated) {
    in.mounting_b = mounting_of(kf.model());
    in.mounting_sigma_b = mounting_sigma(kf.layout(), kf.covariance());
  }
  r.dwells = static_cast<int>(timeline.dwells.size());
  r.model = kf.model();
  if (const StaticDetector* detector = kf.detector()) {
    KalmanRun::Detected d{
        detector->gyro_bound(), detector->accel_bound(), detector->rate_threshold(), {}};
    for (const auto& f : detector->dwells()) {
      // A static interval beyond the plan's last dwell stopped the run (PlanDataMismatch, named
      // in `stopped`): it has no dwell of the plan to be reported against. Reading the plan's
      // dwell past the end crashed `--passes 2` on a real log (APOPHIS, issue 34): a quiet pass,
      // without the divergence alarm, read on until the data had more static intervals than the
      // plan.
      if (f.index < 1 || f.index > static_cast<int>(timeline.dwells.size())) continue;
      const PlanDwell& p = timeline.dwells[static_cast<std::size_t>(f.index - 1)];
      d.intervals.push_back({f.index, p.label, f.t_start, f.t_end, p.t_start, p.t_end});
    }
    r.detected = d;
  }
}

// Without attitude updates nothing observes the heading, and the common part of the gyro
// g-sensitivity's diagonal (a rate along the specific force: about the vertical at every dwell)
// moves with the heading drift. On MEMS (mems profile, rot19, plain) the filter put all three
// diagonal terms near -2300 deg/h/g (the profile's range: up to 360), 160 of their own sigmas off
// the truth, NIS per dof 0.76, every check passed. A diagonal term beyond the profile's range (its
// prior sigma over the prior scale) by more than kAttitudeFreeSigmas of its own sigmas is refused,
// with the cause.
constexpr double kAttitudeFreeSigmas = 4.0;

void refuse_attitude_free_g_sensitivity(const CalibratorOptions& o, KalmanRun& r) {
  if (o.attitude != CalibratorOptions::AttitudeUpdates::None || !r.diverged.empty()) return;
  const auto& cat = coefficient_catalog();
  std::ostringstream m;
  int beyond = 0;
  for (std::size_t c = 0; c < cat.size(); ++c) {
    const CoefficientEstimate& e = r.estimates[c];
    const std::string& n = cat[c].name;
    if (cat[c].family != "gyro.g_sensitivity" || n[n.size() - 1] != n[n.size() - 2] ||
        e.status != CoefficientEstimate::Status::Estimated || !(e.prior_sigma > 0.0) ||
        !(o.prior_scale > 0.0))
      continue;
    const double range = e.prior_sigma / o.prior_scale;
    if (!(std::abs(e.value) - range > kAttitudeFreeSigmas * e.sigma)) continue;
    m << (beyond++ ? ", " : "") << n << " " << e.value / cat[c].si_per_unit << " +- "
      << e.sigma / cat[c].si_per_unit << " " << cat[c].unit;
    if (beyond == 1) m << " (the profile's range up to " << range / cat[c].si_per_unit << ")";
  }
  if (beyond == 0) return;
  r.diverged =
      "without attitude updates (--attitude none) the gyro g-sensitivity's diagonal moves with "
      "the heading drift, which nothing observes: " +
      m.str() + " beyond the sensor profile's range by more than " +
      std::to_string(static_cast<int>(kAttitudeFreeSigmas)) +
      " sigmas; calibrate with table-attitude updates (--attitude every or first)";
}

// The plan's timeline, or the dwells where the data are still.
PlanTimeline timeline_of(const Session& session, const CalibratorOptions& o) {
  return o.data_timeline ? *o.data_timeline : PlanTimeline::of(session.plan, session.site);
}

KalmanRun run_pass(const Session& session, const CalibratorOptions& options, SampleSource* source,
                   const KalmanRunOptions& run) {
  const PlanTimeline timeline = timeline_of(session, options);
  CalibratorOptions o = options;
  // The error dynamics along the plan's motion when the IMU follows it.
  if (!o.reference_motion && follows_plan_motion(o))
    o.reference_motion = std::make_shared<const Motion>(build_motion(session.plan, session.site));
  Calibrator kf(timeline, session.site, o);
  std::unique_ptr<LogReader> reader;
  if (!source) {
    reader = std::make_unique<LogReader>(session.log);
    source = reader.get();
  }
  KalmanRun r;
  r.options = options;
  if (run.skip_bad_samples) {
    auto on_skip = [&r](const BadSampleError& e) {
      ++r.skipped;
      if (r.skipped_examples.size() < KalmanRun::kSkippedExamples)
        r.skipped_examples.push_back(e.what());
    };
    auto* log = dynamic_cast<LogReader*>(source);
    if (auto* held = dynamic_cast<HeldStream*>(source))
      held->skip_bad_samples(on_skip);
    else if (log)
      log->skip_bad_samples(on_skip);
    else
      throw std::invalid_argument("skipping bad samples needs a log reader");
  }
  read_samples(kf, *source, run, r, options);
  const double last_dt =
      r.samples > 0 && r.duration > 0.0 ? r.duration / static_cast<double>(r.samples) : 0.0;
  check_against_plan(kf, timeline, reader ? session.log.file : std::string("the input"),
                     options.time_offset, last_dt, r);
  if (r.diverged.empty()) try {
      kf.finish();
    } catch (const PlanDataMismatch& e) {
      if (r.stopped.empty()) r.stopped = e.what();
    } catch (const std::runtime_error& e) {
      r.diverged = "filter diverged at the last sample: " + std::string(e.what());
    }
  summarize(kf, timeline, run, r);
  refuse_attitude_free_g_sensitivity(options, r);
  return r;
}

// The prior 1-sigma of a coefficient under the options (SI).
double prior_of(const CalibratorOptions& o, const std::string& name) {
  const auto& cat = coefficient_catalog();
  for (std::size_t c = 0; c < cat.size(); ++c)
    if (cat[c].name == name)
      return o.initial_sigma.size() > c && o.initial_sigma[c] > 0.0
                 ? o.initial_sigma[c]
                 : coefficient_family_info(cat[c].family).default_prior;
  return 0.0;
}

double largest_prior(const CalibratorOptions& o, const std::string& family) {
  double out = 0.0;
  for (const auto& c : coefficient_catalog())
    if (c.family == family) out = std::max(out, prior_of(o, c.name));
  return out;
}

// The mean outputs of the plan's dwells in the session's log (empty when the log cannot be read:
// the filter's pass refuses it, with the reason).
std::vector<AlignmentDwell> log_dwell_means(const Session& session, const CalibratorOptions& o) {
  const PlanTimeline timeline = timeline_of(session, o);
  try {
    // Bad samples left out of the means; the filter's pass reports them (stop or skip).
    LogReader reader(session.log);
    reader.skip_bad_samples([](const BadSampleError&) {});
    return dwell_means(reader, timeline, o.time_offset, o.static_margin);
  } catch (const std::runtime_error&) {
    return {};
  }
}

// The alignment from the dwells' means, the fit's unmodelled errors from the priors.
Alignment alignment_of(const Session& session, const CalibratorOptions& options,
                       const std::vector<AlignmentDwell>& means) {
  const double linear_a =
      std::max(largest_prior(options, "accel.scale"), largest_prior(options, "accel.misalignment"));
  const double linear_g =
      std::max(largest_prior(options, "gyro.scale"), largest_prior(options, "gyro.misalignment"));
  const Earth& earth = Earth::wgs84();
  return align(means, session.site, linear_a * earth.gravity_n(session.site.lat_rad, 0.0).norm(),
               linear_g * earth.omega_ie_n(session.site.lat_rad).norm());
}

// A stream's: the samples held dwell by dwell of the plan until the dwells so far determine the
// alignment (stream_alignment.hpp: valid, sigmas below kStreamAlignmentSigma). Empty when they
// do not fit in the buffer or the stream ends or fails before.
std::vector<AlignmentDwell> held_dwell_means(HeldStream& held, const Session& session,
                                             const CalibratorOptions& o,
                                             const KalmanRunOptions& run) {
  const PlanTimeline timeline = PlanTimeline::of(session.plan, session.site);
  PlanTimeline first = timeline;
  for (std::size_t k = kStreamAlignmentMinDwells; k <= timeline.dwells.size(); ++k) {
    first.dwells.assign(timeline.dwells.begin(),
                        timeline.dwells.begin() + static_cast<std::ptrdiff_t>(k));
    if (!held.hold(first, k, o.time_offset, o.static_margin, run.stop)) return {};
    VectorSource samples(held.held());
    auto means = dwell_means(samples, first, o.time_offset, o.static_margin);
    if (stream_alignment_settled(alignment_of(session, o, means))) return means;
  }
  return {};
}

// Whether an alignment is a starting point the filter admits: a mounting up to kAdmittedMounting,
// a base within 3 of its prior sigmas. MEMS gyros at -40 C (mems-thermal, a chamber soak) gave a
// 14 deg mounting and a 50 deg heading, "significant" by their own sigmas (the gyros' g-sensitivity
// and thermal bias, unmodelled, are 100 times the Earth rate the heading comes from): the filter
// started there diverged at the first turn (t = 80 s).
bool admissible(const Alignment& a) {
  return a.mounting_b.norm() <= kAdmittedMounting &&
         a.base_n.head<2>().norm() <= 3.0 * kBaseLevelPriorSigma &&
         std::abs(a.base_n.z()) <= 3.0 * kBaseHeadingPriorSigma;
}

// The alignment from the dwells' means; the options start from it when it is significant and
// admissible. With the base known (CalibratorOptions::base_attitude off) only its mounting is
// taken: the base stays the plan's. A stream's alignment from its first dwells is judged with its
// sigmas times sqrt(dwells) (stream_alignment_judged).
CalibratorOptions aligned(const Session& session, const CalibratorOptions& options,
                          const std::vector<AlignmentDwell>& means, bool streamed,
                          InstallationResult& in) {
  const Alignment a = alignment_of(session, options, means);
  in.alignment = a;
  const double threshold = std::max(
      kAlignmentThreshold, kAlignmentPriorMultiple * largest_prior(options, "accel.misalignment"));
  CalibratorOptions o = options;
  const Alignment judged = streamed ? stream_alignment_judged(a) : a;
  if (!judged.significant(threshold, options.base_attitude) || !admissible(a)) return o;
  in.alignment_applied = true;
  if (options.base_attitude) o.initial_base_n = a.base_n;
  if (o.attitude == CalibratorOptions::AttitudeUpdates::None) {
    // The body frame is the accelerometer triad's: the mounting turns the start attitude.
    o.start_mounting_b = a.mounting_b;
  } else {
    // Relative to the platform the triads carry the mounting: the coefficients start there.
    o.initial_model =
        in_platform_frame(o.initial_model.value_or(ImuErrorModel{}), dcm_from_rotvec(a.mounting_b));
  }
  return o;
}

// How far the estimates moved from one pass to the next, in the later pass's sigmas, over the
// coefficients both passes observe.
double largest_change(const KalmanRun& now, const KalmanRun& before) {
  double moved = 0.0;
  const InstallationResult &later = now.installation, &earlier = before.installation;
  if (later.base_estimated && earlier.base_estimated)  // the base too, in the later pass's sigmas
    for (int i = 0; i < 3; ++i)
      if (later.base_sigma_n(i) > 0.0)
        moved =
            std::max(moved, std::abs(later.base_n(i) - earlier.base_n(i)) / later.base_sigma_n(i));
  for (std::size_t c = 0; c < now.estimates.size(); ++c) {
    const CoefficientEstimate &a = now.estimates[c], &b = before.estimates[c];
    if (!a.observed() || !b.observed() || !(a.sigma > 0.0)) continue;
    moved = std::max(moved, std::abs(a.value - b.value) / a.sigma);
  }
  return moved;
}

// The run's result in the frame the options ask for (the passes ran in the filter's own).
void report_in_frame(KalmanRun& r, const KalmanRunOptions& run) {
  r.misalignment_frame = reported_frame(r.options);
  if (!converts_to_triad(r.options)) return;
  estimates_to_triad_frame(r.estimates, r.coefficient_covariance, r.covariance_catalog);
  r.model = in_accel_triad_frame(r.model);
  r.accel_triad_frame = r.converted_to_triad_frame = true;
  // The combinations the data do not observe, of the converted coefficients (the table frame's
  // common rotation has dropped out of them).
  for (auto& e : r.estimates) e.in_unobservable_direction = false;
  r.unobservable_directions =
      unobservable_directions(r.coefficient_covariance, r.covariance_catalog, r.estimates);
  const auto& cat = coefficient_catalog();
  r.unobservable.clear();
  for (std::size_t i = 0; i < r.estimates.size(); ++i)
    if (r.estimates[i].status == CoefficientEstimate::Status::Estimated &&
        !r.estimates[i].observed())
      r.unobservable.push_back(cat[i].name);
  r.above_target = above_target(r.estimates, run.sigma_targets);
}

// How far a pass ran from the model it started from (pass_linearization.hpp).
PassLinearization linearization_of(const KalmanRun& r, const CalibratorOptions& started) {
  return pass_linearization(r.estimates, r.model.vector(),
                            started.initial_model.value_or(ImuErrorModel{}).vector());
}

// The options of one pass of several: earlier passes of a fixed count run quiet, without the
// alarm (their linearization is what the later passes improve); automatic passes, any of which
// may be the last, with the alarm, their monitor records held for the end.
KalmanRunOptions pass_options(const KalmanRunOptions& run, bool last,
                              std::vector<MonitorRecord>& held) {
  KalmanRunOptions o = run;
  if (run.passes == 0) {
    if (run.monitor) o.monitor = [&held](const MonitorRecord& m) { held.push_back(m); };
    return o;
  }
  if (last) return o;
  o.monitor = nullptr;
  o.monitor_interval = 0.0;
  o.nis_alarm_z = std::numeric_limits<double>::infinity();
  return o;
}

// Several passes over the session's log, each from the previous pass's coefficients: a fixed
// count, or automatic (KalmanRunOptions::passes 0).
KalmanRun run_passes(const Session& session, const CalibratorOptions& options,
                     const KalmanRunOptions& run) {
  const bool automatic = run.passes == 0;
  const int most = automatic ? kMaxAutomaticPasses : run.passes;
  CalibratorOptions o = options;
  std::vector<KalmanRun::Pass> passes;
  std::vector<MonitorRecord> held;
  KalmanRun previous;
  for (int pass = 1; pass <= most; ++pass) {
    held.clear();
    bool last = pass == most;
    KalmanRun r = run_pass(session, o, nullptr, pass_options(run, last, held));
    r.linearization = linearization_of(r, o);
    KalmanRun::Pass p{pass, r.nis_per_dof, std::nullopt, r.linearization.share};
    if (pass > 1) p.largest_change_over_sigma = largest_change(r, previous);
    passes.push_back(p);
    last = last || (automatic && r.linearization.within());
    if (last || !r.stopped.empty() || !r.diverged.empty()) {  // bad input, an interruption
      // An earlier pass of a fixed count runs without the alarm: its stop is said to be its own.
      const std::string which = "pass " + std::to_string(pass) + " of " + std::to_string(most) +
                                " (without the divergence alarm): ";
      if (!last && !automatic && !r.stopped.empty() && !r.interrupted)
        r.stopped = which + r.stopped;
      if (!last && !automatic && !r.diverged.empty()) r.diverged = which + r.diverged;
      if (automatic && run.monitor)
        for (const MonitorRecord& m : held) run.monitor(m);
      r.passes = passes;
      r.passes_requested = run.passes;
      return r;
    }
    // The coefficients carry over; the base starts again where the first pass did (a pass
    // far off, MEMS, leaves it anywhere, and its prior is wide enough). Carrying the base over
    // too was measured worse: MEMS rot19, seeds 1-6, the third pass moved 0.15-0.29 sigma with
    // it, 0.009-0.029 without (docs/accuracy.md "Several passes (MEMS)").
    o.initial_model = r.model;
    previous = std::move(r);
  }
  return previous;  // not reached
}

}  // namespace

std::vector<CoefficientEstimate> estimates_in_reported_frame(const Calibrator& kf,
                                                             const CalibratorOptions& options) {
  return reported_estimates(kf, options);
}

MisalignmentFrame reported_frame(const CalibratorOptions& o) {
  const bool own_triad = effective_layout(o).accel_triad_frame;
  if (own_triad && o.misalignment_frame == MisalignmentFrame::Table &&
      o.attitude != CalibratorOptions::AttitudeUpdates::None)
    throw std::invalid_argument(
        "the table frame needs a filter that estimates relative to the "
        "table (the layout fixes the accelerometer-triad frame)");
  return resolve_misalignment_frame(own_triad && o.misalignment_frame == MisalignmentFrame::ByMode
                                        ? MisalignmentFrame::Triad
                                        : o.misalignment_frame,
                                    o.attitude != CalibratorOptions::AttitudeUpdates::None);
}

KalmanRun run_kalman(const Session& session, const CalibratorOptions& given, SampleSource* source,
                     const KalmanRunOptions& run) {
  reported_frame(given);  // refuses a frame the mode cannot give, before any data are read
  InstallationResult installation;
  // The alignment averages the plan's dwells: the log's, read once more before the filter, or a
  // stream's first ones, held and given again (not for dwells found in the data: the plan's
  // timing may not hold).
  const bool align_first = run.align && given.static_from == CalibratorOptions::StaticFrom::Plan;
  std::optional<HeldStream> held;
  CalibratorOptions options = given;
  // The motion from the data (a batch run along the plan's motion): the start-time offset, the
  // turns' realized profiles, the dwells where the data are still.
  std::optional<DataMotion> motion;
  if (run.motion) {
    motion = *run.motion;
  } else if (!source && run.motion_from_data && motion_from_data_applies(given) &&
             !given.reference_motion) {
    try {
      motion = motion_from_data(session, given);
    } catch (const std::runtime_error&) {
      motion.reset();  // the filter's pass reads the log again and reports what is wrong
    }
  }
  if (motion) {
    options.time_offset = motion->time_offset;
    options.reference_motion = motion->reference;
    options.data_timeline = motion->timeline;
  }
  if (align_first && !source) {
    options = aligned(session, options, log_dwell_means(session, options), false, installation);
  } else if (align_first) {
    held.emplace(*source, run.stream_alignment_capacity, run.skip_bad_samples);
    options =
        aligned(session, given, held_dwell_means(*held, session, given, run), true, installation);
    installation.alignment_streamed = true;
    source = &*held;
  }
  auto with_installation = [&](KalmanRun r) {
    r.installation.alignment = installation.alignment;
    r.installation.alignment_applied = installation.alignment_applied;
    r.installation.alignment_streamed = installation.alignment_streamed;
    r.options = given;
    r.motion = motion;
    report_in_frame(r, run);
    return r;
  };
  if (run.passes == 1 || (run.passes == 0 && source)) {
    KalmanRun r = run_pass(session, options, source, run);
    r.linearization = linearization_of(r, options);
    return with_installation(std::move(r));
  }
  if (source) throw std::invalid_argument("several passes need the session's log, not a stream");
  return with_installation(run_passes(session, options, run));
}

}  // namespace sinscal
