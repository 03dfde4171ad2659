// Error-state Kalman filter calibrator (first version: batch and streaming push/estimate).
//
// Each IMU sample is compensated with the current coefficient estimate (models/imu_error_model),
// integrated by the strapdown navigator, and its error dynamics accumulated into the transition
// of the state of filter/kalman/state_layout.hpp:
//   phi'  = -omega_ie x phi + d_omega_in(dv, dp) - C_b_n J_g dtheta
//   dv'   = f_n x phi - 2 omega_ie x dv + (2g/R) dp_d e_d + C_b_n J_a dtheta
//   dp'   = dv
// with J the error model's Jacobian (residual coefficient errors dtheta = true - estimate). The
// transition is accumulated per sample exploiting its structure [[A, B], [0, I]]; the covariance is
// propagated and updated every `update_interval`. Measurements during the plan's static dwells:
// zero velocity, known position, and the table-known attitude (at every update of a dwell, the
// table's orientation error of the dwell a state: the same at every update, drawn anew at each
// dwell; or once per dwell, that error the measurement's noise). Joseph-form updates, symmetrized;
// the normalized innovation squared (NIS) is kept. After every update the estimate is fed back
// (navigator state and coefficients) and the error state reset.
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "filter/kalman/error_propagation.hpp"
#include "filter/kalman/innovation_check.hpp"
#include "filter/kalman/measurements.hpp"
#include "filter/kalman/misalignment_frame.hpp"
#include "filter/kalman/state_layout.hpp"
#include "filter/noise/static_detector.hpp"
#include "filter/strapdown/ins_error_model.hpp"
#include "filter/strapdown/strapdown.hpp"
#include "models/imu_error_model.hpp"
#include "models/noise_model.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "rig/imu_sample.hpp"
#include "rig/motion.hpp"
#include "rig/table.hpp"
#include "rig/thermal.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

/// The prior 1-sigma of a coefficient is this many times the largest magnitude of its family's
/// range in the sensor profile (the range the simulator draws from): wide enough for any value
/// the profile admits, narrow enough to keep the first pass linear.
constexpr double kDefaultPriorScale = 1.5;
/// Table attitude accuracy per orientation (2-3 arcsec for a precision two-axis table).
constexpr double kDefaultTableAttitudeSigma = 2.5 * units::arcsec;
/// A precision table's stillness within a dwell (servo jitter, encoder noise), per update.
constexpr double kDefaultTableHoldSigma = 0.1 * units::arcsec;
/// Start of the navigation: attitude about the plan's start orientation (the body frame may
/// differ from the table's by the mounting), velocity and position at rest on the site.
constexpr double kDefaultStartAttitudeSigma = 0.5 * units::deg;
/// Prior 1-sigma of the table base attitude (docs/conventions.md "Table base and mounting"):
/// level (about North and East) and heading (about Down) of a table set up on its site.
constexpr double kBaseLevelPriorSigma = 1.0 * units::deg;
constexpr double kBaseHeadingPriorSigma = 5.0 * units::deg;
/// The base heading is estimated when the gyro bias prior is below this fraction of the Earth
/// rate (the gyros then find North); otherwise it is the plan's, to the table's accuracy.
constexpr double kNorthSeekingBiasRatio = 0.1;
constexpr double kStartVelocitySigma = 1e-3;  // m/s
constexpr double kStartPositionSigma = 1e-2;  // m

struct CalibratorOptions {
  StateLayoutOptions layout;
  double update_interval = 1.0;  // s
  bool zero_velocity = true;
  bool position = true;
  /// Table-attitude updates: at every dwell (orientation plans: the table sets each
  /// orientation independently), at the first dwell only (rotation plans: errors of the turns
  /// accumulate, so later dwells are not independent), or none (zero velocity only).
  enum class AttitudeUpdates { Every, First, None };
  AttitudeUpdates attitude = AttitudeUpdates::Every;
  double velocity_sigma = 1e-5;  // m/s, zero-velocity measurement (table at rest)
  double position_sigma = 1e-3;  // m
  /// Zero velocity also while the table turns (the IMU reference point on the table's axes).
  /// (The plan's IMU reference point is at the intersection of the table axes, so it stays put.)
  bool zero_velocity_in_motion = true;
  double motion_velocity_sigma = 1e-4;                 // m/s
  double attitude_sigma = kDefaultTableAttitudeSigma;  // rad, table attitude
  /// The attitude updates repeated through each dwell, the dwell's orientation error (of
  /// attitude_sigma) a state of the layout: the table holds its orientation, so the navigator's
  /// drift at rest is measured against it (a MEMS unit's vertical gyro bias, unobserved by
  /// gravity, otherwise turns the heading by degrees over the first dwell, and the first turn
  /// about a horizontal axis then meets a heading error the linear error model does not hold).
  /// Off: one update per dwell, its table error the measurement noise.
  bool attitude_hold = true;
  /// 1-sigma per update of the table's orientation about the dwell's own (its stillness: servo
  /// jitter, encoder noise), rad.
  double hold_sigma = kDefaultTableHoldSigma;
  /// The bias instability's Gauss-Markov wander as six states when the noise model has one (a
  /// bias_instability with a correlation_time): the bias families are then the constant bias.
  /// Off: the bias families wander as a random walk of density 2 b^2 / tau, which over runs
  /// much longer than tau grows far beyond the wander's b (a MEMS chamber ramp: 10.8 b).
  bool bias_wander_states = true;
  /// The table base attitude estimated (states of the layout; only with attitude updates): the
  /// attitude updates then measure the attitude relative to the base.
  bool base_attitude = true;
  /// The base attitude to start from (rotation vector, rad, NED: C_b_n_true = R(base) C_b_n of
  /// the table), e.g. from an alignment (filter/installation/installation.hpp); the prior is
  /// centred on it.
  Eigen::Vector3d initial_base_n = Eigen::Vector3d::Zero();
  /// Without attitude updates (body frame = accelerometer triad): the start attitude is the
  /// plan's turned by this mounting (rotation vector of C_b_p, rad), e.g. the alignment's.
  Eigen::Vector3d start_mounting_b = Eigen::Vector3d::Zero();
  double static_margin = 0.5;  // s: updates only this far inside a dwell
  /// 1-sigma of the start attitude about the plan's start orientation; zero: 0.5 deg. Not the
  /// table's attitude_sigma: the first attitude update measures the same table error again, and
  /// without attitude updates the body frame is the accelerometer triad's, which differs from
  /// the table's by the mounting.
  double initial_attitude_sigma = 0.0;  // rad
  NoiseModel noise;                     // white-noise densities drive the process noise
  /// Initial 1-sigma of every coefficient (SI, catalog order); zero: the family's default prior
  /// (models/coefficient_families.hpp). calibrator_options_from_profile() fills it with
  /// prior_scale times the largest magnitude of the family's range in the profile.
  std::vector<double> initial_sigma;
  double prior_scale = kDefaultPriorScale;  // the scale initial_sigma was made with (reported)
  double time_offset = 0.0;                 // s: log time at which the plan starts
  /// Coefficients to start from (the linearization point; the prior sigmas stay those above).
  /// Multi-pass runs start each pass from the previous pass's estimate.
  std::optional<ImuErrorModel> initial_model;
  /// T0 of the thermal coefficients (deg C): the sensor profile's [thermal] reference_temperature.
  double reference_temperature_c = 25.0;
  /// Where the static dwells are: the plan's timing (shifted by time_offset), or detected in the
  /// data (StaticDetector; the k-th static interval is the plan's k-th dwell, whose orientation
  /// the attitude updates use; time_offset is then not needed).
  enum class StaticFrom { Plan, Data };
  StaticFrom static_from = StaticFrom::Plan;
  StaticDetectorOptions detector;
  /// Samples carrying the table's axis angles (a table-angle column in the log): the attitude
  /// updates use the attitude the angles give through the timeline's table geometry instead of
  /// the plan's orientation; a dwell where the two differ by more than `table_plan_tolerance` is
  /// a plan mismatch.
  bool use_table_angles = true;
  double table_plan_tolerance = 1.0 * units::deg;  // rad
  /// The table's known motion in plan time (the plan's motion of a perfect table, rig/plan.hpp
  /// build_motion), when the IMU follows it: the error dynamics are then evaluated along it (the
  /// Jacobian's rates and specific force, and the attitude that turns the coefficient errors into
  /// navigation axes, with `initial_base_n`), not along the navigator's compensated outputs.
  /// Those carry the sensor noise and the current estimate: for a MEMS unit, whose estimates
  /// wander along the combinations the first turns leave undetermined, the Jacobian followed
  /// them and the filter gained information the data do not hold (docs/accuracy.md "Several passes
  /// (MEMS)"). Null: the navigator's outputs and attitude (every estimator but run_kalman's
  /// passes).
  std::shared_ptr<const Motion> reference_motion;
  /// Along the reference motion, the time delay's Jacobian column from the motion's specific
  /// force rate (-omega_nb_b x f_ib_b) instead of the measured difference (off: the measured).
  bool delay_from_reference = true;
  /// The plan's dwells where the data are still (filter/kalman/motion_from_data.hpp: turns that
  /// reach into the plan's dwells shorten them); null: the plan's.
  std::shared_ptr<const PlanTimeline> data_timeline;
  /// Held-out intervals of plan time (s, start and end): no measurement update inside them, and
  /// the first update after each is recorded as a prediction (HoldoutPrediction). The
  /// diagnosis leaves turns out this way to measure how well a model predicts them.
  std::vector<std::pair<double, double>> holdout;
  /// The frame run_kalman reports the coefficients in (filter/kalman/misalignment_frame.hpp):
  /// the filter's own (ByMode), or the triad frame after an estimation relative to the table.
  /// The filter itself always estimates in its own frame.
  MisalignmentFrame misalignment_frame = MisalignmentFrame::ByMode;
};

/// The first update after a held-out interval: how well the filter, which saw no measurement
/// over the interval, predicted the navigation error accumulated in it.
struct HoldoutPrediction {
  double t_plan = 0.0;  // s, plan time of the update
  double nis = 0.0;     // normalized innovation squared of the update
  int dof = 0;          // its rows
  /// The zero-velocity rows' innovation (m/s, NED; zero when the update has none).
  Eigen::Vector3d velocity_innovation = Eigen::Vector3d::Zero();
};

/// The data do not match the plan (a log shorter than the plan, more or fewer static intervals
/// than the plan's dwells).
class PlanDataMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Options from a sensor profile: noise, the extended families the profile declares present,
/// initial sigmas of prior_scale times its coefficient ranges.
CalibratorOptions calibrator_options_from_profile(const SensorProfile& profile,
                                                  double prior_scale = kDefaultPriorScale);

/// The state layout the options imply: without table-attitude updates the body frame is the
/// accelerometer triad's (docs/conventions.md), whatever `layout.accel_triad_frame` says.
StateLayoutOptions effective_layout(const CalibratorOptions& options);
/// Whether the gyros find North: every gyro-bias prior below kNorthSeekingBiasRatio of the Earth
/// rate (otherwise the base heading's prior is the table's attitude sigma: the plan's heading).
bool gyros_find_north(const CalibratorOptions& options);
/// Whether the IMU follows the plan's motion as the options describe the session (dwells where
/// the plan puts them, table-attitude updates, the reference point on the table's axes): the
/// error dynamics are then evaluated along the plan's motion (CalibratorOptions::reference_motion;
/// run_kalman and the plan search give it).
bool follows_plan_motion(const CalibratorOptions& options);
/// Whether the motion the data show may be the error dynamics' linearization point (run_kalman,
/// motion_from_data): as follows_plan_motion, the dwells also when the data give them
/// (--static-from data: the navigator's outputs, noisy and off by a MEMS unit's errors, made the
/// filter diverge at the first turn).
bool motion_from_data_applies(const CalibratorOptions& options);
/// The start-attitude sigma the options imply.
double initial_attitude_sigma(const CalibratorOptions& options);

struct CoefficientEstimate {
  double value = 0.0;  // SI
  double sigma = 0.0;  // SI
  /// Off: its block is not in the state; FixedByConvention: zero by the body-frame convention.
  enum class Status { Off, Estimated, FixedByConvention };
  Status status = Status::Off;
  double prior_sigma = 0.0;  // SI, the sigma before any data
  /// Part of a combination of coefficients the data did not determine (kalman_run.hpp).
  bool in_unobservable_direction = false;
  /// Observed: the data alone determine it better than the prior did (sigma below prior /
  /// sqrt(2)), alone and in every combination with others; otherwise the plan cannot observe it
  /// and the value is the prior's.
  bool observed() const {
    return status == Status::Estimated && !in_unobservable_direction &&
           sigma * sigma < 0.5 * prior_sigma * prior_sigma;
  }
};

class Calibrator {
 public:
  /// The plan's timeline (rig/timeline.hpp: dwells, known attitudes, table geometry), the site.
  Calibrator(PlanTimeline timeline, const Site& site, const CalibratorOptions& options);
  /// One IMU sample (streaming: call in time order). A sample is processed when the next one
  /// arrives (one sample of latency: the rates of change of angular rate and specific force over
  /// an interval are central differences of its neighbours).
  void push(const ImuSample& sample);
  /// Processes the last sample held back (end of the log).
  void finish();
  /// Current estimate of every coefficient of the catalog (coefficients whose block is off are
  /// reported as zero with sigma zero).
  std::vector<CoefficientEstimate> estimate() const;
  const StateLayout& layout() const { return layout_; }
  const Eigen::MatrixXd& covariance() const { return P_; }
  const ImuErrorModel& model() const { return model_; }
  /// NIS of the updates so far (sum and count of the measurement dimensions).
  double nis_sum() const { return nis_sum_; }
  int nis_dof() const { return nis_dof_; }
  /// Innovation log-likelihood of the updates so far: the sum of log N(z; 0, S) over them, the
  /// constant log(2 pi) terms dropped (the likelihood of the data under the filter's model).
  double log_likelihood() const { return log_likelihood_; }
  /// Number of measurement updates so far, and the NIS and dimension of the last one.
  int updates() const { return updates_; }
  double last_nis() const { return last_nis_; }
  int last_nis_dof() const { return last_nis_dof_; }
  /// The normalized innovations of the updates so far, by channel (innovation_check.hpp).
  const InnovationRecord& innovations() const { return innovations_; }
  /// Attitude updates that took the attitude from the table's angles.
  int table_attitude_updates() const { return table_updates_; }
  /// The first update after each held-out interval (CalibratorOptions::holdout).
  const std::vector<HoldoutPrediction>& holdout_predictions() const { return holdout_; }
  /// With static intervals from the data: the detector (its dwells found so far); else null.
  const StaticDetector* detector() const { return detector_ ? &*detector_ : nullptr; }
  /// The navigator's state (the filter's reference trajectory).
  const NavState& navigation() const { return nav_.state(); }
  /// The table base attitude's estimate (identity when not estimated nor given).
  const Eigen::Matrix3d& base() const { return C_base_; }
  /// The error dynamics accumulated since the last covariance propagation.
  const ErrorPropagator& propagator() const { return propagator_; }
  /// Adds a known error `dx` (layout's states, the error-state convention of
  /// filter/kalman/measurements.hpp) to the navigator and the coefficients: at once, or when the
  /// navigation starts if it has not yet. For tests of the error dynamics and Monte Carlo runs.
  void inject_error(const Eigen::VectorXd& dx);
  /// Plan design's search (filter/design/search.hpp): the run goes on over a longer plan, whose
  /// dwells begin with those given so far (the same plan with further turns). Throws
  /// std::invalid_argument when they do not.
  void extend_timeline(const PlanTimeline& longer);
  /// The reference motion from here on (CalibratorOptions::reference_motion), e.g. a longer
  /// plan's whose beginning is the motion so far.
  void set_reference_motion(std::shared_ptr<const Motion> motion) {
    o_.reference_motion = std::move(motion);
  }

 private:
  void process(const ImuSample& s, const Eigen::Vector3d& omega_dot, const Eigen::Vector3d& f_dot,
               const Eigen::Vector3d& f_ddot);
  void update(double t_plan);
  /// The error dynamics of one sample along the reference motion (CalibratorOptions).
  void step_along_reference(const KinematicSample& k, const Eigen::Vector3d& f_dot, double dt);
  /// Takes the bias wander's estimate off the compensated inputs, and decays it over dt.
  void remove_wander(KinematicSample& k, double dt);
  /// The known attitude of a dwell: the table's angles when the log has them, else the plan's.
  Eigen::Matrix3d dwell_attitude(const PlanDwell& dwell);
  void apply(const Measurement& m);
  /// Records the update's normalized innovations z_i / sqrt(S_ii) by channel.
  void record_innovations(const Measurement& m, const Eigen::VectorXd& z, const Eigen::MatrixXd& S);
  void initialize_covariance();

  std::vector<PlanDwell> dwells_;
  Site site_;
  InsSiteTerms site_terms_;  // Earth terms at the site (the table does not move), once
  CalibratorOptions o_;
  StateLayout layout_;
  ImuErrorModel model_;
  ImuErrorModel::LinearInverses inverses_;  // model_'s, refreshed with each change of it
  Eigen::MatrixXd work_KHP_, work_KSK_;     // apply(): n x n products, kept between updates
  Eigen::Matrix3d C_base_ = Eigen::Matrix3d::Identity();  // the base attitude's estimate
  // The estimate of the table's orientation error in the current dwell (identity without it).
  Eigen::Matrix3d C_dwell_ = Eigen::Matrix3d::Identity();
  // The bias wander's estimate (gyro, accelerometer; compensated inputs' axes), decaying with
  // the correlation time between updates; zero without its states.
  Eigen::Matrix<double, 6, 1> wander_ = Eigen::Matrix<double, 6, 1>::Zero();
  // Its decay over one sample interval, for the interval `wander_dt_` (s).
  Eigen::Matrix<double, 6, 1> wander_decay_ = Eigen::Matrix<double, 6, 1>::Ones();
  double wander_dt_ = -1.0;
  // The base the reference motion is turned by (the start's, fixed: not the wandering estimate).
  Eigen::Matrix3d C_reference_base_ = Eigen::Matrix3d::Identity();
  // The IMU's mounting on the table at the start (the navigator's start: C_base C_table C_m).
  Eigen::Matrix3d C_reference_mounting_ = Eigen::Matrix3d::Identity();
  Strapdown nav_;
  ErrorPropagator propagator_;
  bool started_ = false;
  Eigen::VectorXd pending_error_;  // injected before the navigation started
  Eigen::MatrixXd P_;
  // The last two samples pushed (held back for the central differences).
  std::vector<ImuSample> held_;
  int attitude_dwell_done_ = 0;
  std::optional<StaticDetector> detector_;
  Table table_;
  TemperatureRate temperature_rate_;  // the gyros' dT/dt from the log's temperatures
  bool thermal_ = false;              // the layout has thermal coefficient states
  ImuSample current_;                 // the sample being processed (its table angles)
  int table_updates_ = 0;
  double nis_sum_ = 0.0;
  int nis_dof_ = 0;
  double log_likelihood_ = 0.0;
  int updates_ = 0;
  double last_nis_ = 0.0;
  int last_nis_dof_ = 0;
  std::vector<double> prior_sigma_;  // catalog order, SI
  bool after_holdout_ = false;       // the next update is the first after a held-out interval
  std::vector<HoldoutPrediction> holdout_;
  InnovationRecord innovations_;
  bool in_dwell_ = false;  // the update being applied is a dwell's (else a turn's)
};

}  // namespace sinscal
