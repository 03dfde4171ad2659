// The Kalman-filter calibrator over a session's samples, batch from the log or streaming from
// any source, with its supervision: bad samples (stop or skip), the NIS divergence alarm, the
// convergence verdict against sigma targets, a log that does not match the plan, interruption,
// several passes. Returns typed results; report/ writes them.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "filter/installation/installation.hpp"
#include "filter/installation/stream_alignment.hpp"
#include "filter/kalman/kalman_calibrator.hpp"
#include "filter/kalman/motion_from_data.hpp"
#include "filter/kalman/pass_linearization.hpp"
#include "rig/io/log_io.hpp"
#include "rig/session.hpp"

namespace sinscal {

/// One record of the convergence monitor: the state of the estimate at a time of the log.
struct MonitorRecord {
  double t = 0.0;  // s, log time
  double nis_per_dof = 0.0;
  bool converged = false;
  bool accel_triad_frame = false;
  std::vector<CoefficientEstimate> estimates;  // catalog order, SI
};

struct KalmanRunOptions {
  double monitor_interval = 0.0;  // s of data between monitor records (0: none)
  std::function<void(const MonitorRecord&)> monitor;
  /// Sigma targets by family (SI), from the sensor profile: the "converged" verdict.
  std::map<std::string, double> sigma_targets;
  /// Bad samples (NaN, saturated, time backwards): skip them (reported) or stop the run.
  bool skip_bad_samples = false;
  /// Divergence alarm: the NIS summed over the last `nis_window` updates beyond the chi-square
  /// quantile `nis_alarm_z` standard deviations up stops the run (estimates kept).
  int nis_window = 30;
  double nis_alarm_z = 6.0;
  /// Passes over the log (batch only): each starts from the previous pass's coefficients, with
  /// the profile's prior sigmas, so the last is linearized about a close estimate (large errors:
  /// MEMS). The monitor, the divergence alarm and the verdicts are those of the last pass.
  /// 0: automatic: one pass, and another while the last left its linearization's second-order
  /// term beyond kLinearizationShare of a sigma (pass_linearization.hpp), at most
  /// kMaxAutomaticPasses; every pass with the divergence alarm, the monitor's records given for
  /// the last only (at its end). With a stream: one pass.
  int passes = 1;
  /// Align from the plan's dwells before the first pass (filter/installation/installation.hpp;
  /// not for dwells found in the data, whose timing is not the plan's): from the log, all its
  /// dwells; from a stream, read once, as many of its first dwells as settle the alignment, whose
  /// samples are held (at most `stream_alignment_capacity`) and given to the filter again
  /// (filter/installation/stream_alignment.hpp). The alignment's mounting and base become the
  /// filter's starting point when either is beyond kAlignmentThreshold and 3 times the
  /// accelerometer misalignments' largest prior, and both within what the filter admits (a
  /// mounting up to kAdmittedMounting, a base within 3 of its prior sigmas).
  bool align = true;
  /// Batch runs along the plan's motion (follows_plan_motion): take the motion from the data
  /// first (filter/kalman/motion_from_data.hpp): a start-time offset the session does not state,
  /// turns that depart from the plan's profile. Off: the plan's commanded motion.
  bool motion_from_data = true;
  /// The motion from the data found already (e.g. for the plausibility gate); not owned.
  const DataMotion* motion = nullptr;
  std::size_t stream_alignment_capacity = kStreamAlignmentCapacity;  // samples
  /// Set (e.g. from a signal handler) to stop reading: the run ends as if the log ended there,
  /// with `interrupted` and the estimates so far.
  const std::atomic<bool>* stop = nullptr;
};

/// A combination of prior-normalized coefficient states is not observed when the data leave more
/// than this ratio of its prior variance (the single-coefficient rule of
/// CoefficientEstimate::observed()); a coefficient with at least kUnobservedWeight of such a
/// direction's (unit) weight is reported as not observable.
constexpr double kUnobservedVarianceRatio = 0.5;
constexpr double kUnobservedWeight = 0.05;

/// A combination of coefficients the data did not shrink below its prior (the filter's form of
/// the closed form's null directions), on prior-normalized coefficients.
struct UnobservableDirection {
  std::vector<std::pair<std::string, double>> components;  // coefficient, weight (unit norm)
  double remaining = 0.0;    // variance along it over the prior's (1: not shrunk at all)
  std::string text() const;  // "+0.577 accel.lever_arm.x.x +0.577 ..."
};

/// Everything one run of the filter produced.
struct KalmanRun {
  /// The frame of `estimates`, `model` and `coefficient_covariance` (reported_frame()): an
  /// estimate relative to the table converted to the triad frame has `accel_triad_frame` and
  /// `converted_to_triad_frame` set.
  MisalignmentFrame misalignment_frame = MisalignmentFrame::Table;
  bool converted_to_triad_frame = false;
  CalibratorOptions options;                   // as run
  std::vector<CoefficientEstimate> estimates;  // catalog order, SI
  ImuErrorModel model;                         // the final estimate as a model (SI)
  int states = 0;
  bool accel_triad_frame = false;
  std::size_t samples = 0;
  double duration = 0.0;  // s of data
  double t_last = 0.0;    // s, log time of the last sample read
  double nis_per_dof = 0.0;
  double log_likelihood = 0.0;  // innovation log-likelihood (Calibrator::log_likelihood)
  /// The innovations' NIS and whiteness per channel, and their verdict (innovation_check.hpp).
  InnovationCheck innovations;
  /// Covariance of the coefficient states at the end (SI), rows and columns in the order of
  /// `covariance_catalog` (their coefficient_catalog() indices).
  Eigen::MatrixXd coefficient_covariance;
  std::vector<int> covariance_catalog;
  std::string stopped;       // empty, or why the input stopped early (bad sample); estimates kept
  bool interrupted = false;  // stopped on request (KalmanRunOptions::stop)
  std::string diverged;      // empty, or the NIS alarm that stopped the run; estimates kept
  bool has_targets = false;
  std::optional<double> converged_at;     // s: first update with every sigma below its target
  std::vector<std::string> unobservable;  // estimated, but the plan's data do not observe them
  std::vector<UnobservableDirection> unobservable_directions;
  std::vector<std::string> above_target;  // at the end, sigma above the profile's target
  std::size_t skipped = 0;                // bad samples skipped
  static constexpr std::size_t kSkippedExamples = 20;
  std::vector<std::string> skipped_examples;  // the first few, "FILE:LINE: cause"
  int table_attitude_updates = 0;
  /// The first update after each held-out interval (CalibratorOptions::holdout).
  std::vector<HoldoutPrediction> holdout;
  int dwells = 0;  // the plan's
  /// With static intervals from the data: the detector's bounds and the intervals it took.
  struct Detected {
    double gyro_bound = 0.0, accel_bound = 0.0, rate_threshold = 0.0;  // rad/s, m/s^2, rad/s
    struct Interval {
      int dwell = 0;
      std::string label;
      double t_start = 0.0, t_end = 0.0, plan_t_start = 0.0, plan_t_end = 0.0;
    };
    std::vector<Interval> intervals;
  };
  std::optional<Detected> detected;
  struct Pass {
    int pass = 0;
    double nis_per_dof = 0.0;
    std::optional<double> largest_change_over_sigma;  // from the second pass on
    double linearization_share = 0.0;                 // PassLinearization::share
  };
  std::vector<Pass> passes;  // several passes only
  int passes_requested = 1;  // 0: automatic
  /// The last pass's distance from the model it linearized about (every run).
  PassLinearization linearization;
  InstallationResult installation;
  /// The motion found in the data (batch runs along the plan's motion).
  std::optional<DataMotion> motion;
};

/// The frame the run's coefficients are reported in (CalibratorOptions::misalignment_frame
/// resolved by its attitude updates); throws std::invalid_argument for the table frame without
/// attitude updates.
MisalignmentFrame reported_frame(const CalibratorOptions& options);
/// The filter's estimates (sigmas from its covariance) in the frame `options` reports: converted
/// to the triad frame when the filter estimates relative to the table (design's search scores
/// these, as the calibration reports them).
std::vector<CoefficientEstimate> estimates_in_reported_frame(const Calibrator& kf,
                                                             const CalibratorOptions& options);

/// Runs the filter over `source` (the session's log when null; several passes need the log).
/// A bad sample (LogError) stops the run: the result keeps the estimates so far and says where
/// and why in `stopped`.
KalmanRun run_kalman(const Session& session, const CalibratorOptions& options,
                     SampleSource* source = nullptr, const KalmanRunOptions& run = {});

/// Estimated coefficients whose sigma is above their family's target (SI targets by family).
std::vector<std::string> above_target(const std::vector<CoefficientEstimate>& estimates,
                                      const std::map<std::string, double>& targets);

}  // namespace sinscal
