// The plausibility gate of the sessions without a table (hand-held `calibrate --method
// table-free`, `--method six-face`, `allan`): the same checks, report and error as the table's
// gate (plausibility.hpp), on the rests the data show (the detector's poses, the labelled faces,
// a static record) instead of the plan's dwells. Nothing knows their attitude, so what a rest must
// show is its magnitudes: |f_b| near local gravity, |omega_ib_b| within the gyro biases plus the
// Earth rate, a noise density a sensor of that kind can have. Two triads that are one signal and
// a fit thousands of times off its noise model are refused too. Each failure names the rest, the
// figures and the likely cause (a unit, the columns, the file).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "filter/plausibility/plausibility.hpp"
#include "filter/six_face/six_face.hpp"
#include "filter/table_free/pose_detector.hpp"
#include "filter/table_free/table_free.hpp"
#include "rig/handheld.hpp"

namespace sinscal {

struct SensorProfile;

/// What a rest may show. SI units.
struct RestLimits {
  std::string source;           // "sensor profile 'mems'" or "generic MEMS bounds"
  double gyro_bias = 0.0;       // rad/s: tolerated |omega_ib_b| at rest beyond the Earth rate
  double specific_force = 0.0;  // m/s^2: tolerated | |f_b| - g |
  // White-noise densities a unit of this kind can have: rad/sqrt(s), m/s/sqrt(s).
  double gyro_noise_lo = 0.0, gyro_noise_hi = 0.0;
  double accel_noise_lo = 0.0, accel_noise_hi = 0.0;
  /// A fit whose chi2 per dof is beyond this is not the data's model (a wrong file, column or
  /// unit): a failure (six-face; the hand-held fit has bounds of its own, check_handheld_fit).
  double max_fit_chi2_per_dof = 1000.0;
  /// |correlation| of a gyro and an accelerometer column at or above this: one signal.
  double same_signal = 0.999;
  /// How far each triad's bias wanders between the poses of a hand-held session (the fit takes
  /// one constant bias): the profile's bias instability (Gauss-Markov: 1-sigma, correlation
  /// time) and random walk; without a profile, a consumer MEMS unit's thermal drift over a
  /// session (the data sheets' offset drift over 2 K: 2 mg and 0.1 deg/s, one value), also for
  /// a profile that states no bias instability or random walk for the triad.
  struct Wander {
    double instability = 0.0;       // rad/s | m/s^2, 1-sigma
    double correlation_time = 0.0;  // s (0: one value over the session, no decorrelation)
    double random_walk = 0.0;       // rad/s/sqrt(s) | m/s^2/sqrt(s)
  };
  Wander accel_wander, gyro_wander;
  std::string wander_source;  // where the wander comes from when not `source` alone

  /// From the profile's error ranges and noise (3 times the largest error they allow; noise
  /// within 1/2 and 10 times its density), or the generic MEMS bounds (nullptr).
  static RestLimits from_profile(const SensorProfile* profile);
};

/// One rest: mean outputs and the white-noise density of each axis.
struct RestStatistics {
  std::string where;  // "pose 3 (t = 12.10 to 20.30 s)", "face 'x_p'", "the record"
  Eigen::Vector3d f_b = Eigen::Vector3d::Zero();         // m/s^2, mean
  Eigen::Vector3d omega_ib_b = Eigen::Vector3d::Zero();  // rad/s, mean
  /// Per-axis white-noise density: m/s/sqrt(s) and rad/sqrt(s).
  Eigen::Vector3d accel_density = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_density = Eigen::Vector3d::Zero();
  double seconds = 0.0;  // s, length
  double dt = 0.0;       // s, sample interval
  std::size_t count = 0;
};

/// Statistics of readings [first, last] (inclusive; rates, SI). The noise comes from the
/// differences of consecutive readings (var(y_k - y_k-1) / 2 per reading, times dt): a slow
/// drift or a hand's slow sway does not enter it. Needs at least three readings.
RestStatistics rest_statistics(const std::vector<ImuReading>& readings, std::size_t first,
                               std::size_t last, const std::string& where);

/// The rests against gravity `g` (m/s^2), the Earth rate and the limits: checks "gravity
/// magnitude", "rate at rest", "noise" (its detail, passed or not, states the densities found and
/// the band, and the sample interval they assume). `input` names the log.
PlausibilityReport check_rests(const std::vector<RestStatistics>& rests, double g,
                               const RestLimits& limits, const std::string& input);

/// "same signal": a gyro and an accelerometer column with |correlation| at or above the limit
/// (the same file given for both triads, or accelerometer columns named as gyro columns).
PlausibilityCheck check_same_signal(const std::vector<ImuReading>& readings,
                                    const RestLimits& limits, const std::string& input);

/// "same signal" for a log split over two files: the same file given as accel_file and gyro_file.
PlausibilityCheck check_same_files(const LogFormat& log);

/// The hand-held fit gate's bounds, per stage of the fit (docs/methods/table-free.md, "Sigmas
/// and the fit gate"): each part's chi2 against what a correct session gives under the noise
/// model. Static poses (accelerometers; gyros): the chi-square quantile of their dof (white
/// noise) plus the expected chi2 of the bias wander (RestLimits::Wander over the session's span)
/// times the quantile of its effective number of independent values over that number. Turns:
/// their quantile times the mean over the turns of the variance they are expected to have (noise,
/// a timing error of one sample interval at the turn's peak rate, kTurnDynamics of its angle)
/// over the noise the fit gives them.
struct HandheldFitBounds {
  static constexpr double kFalseAlarm = 1e-3;    // of each part's quantiles
  static constexpr double kTurnDynamics = 5e-3;  // unmodelled share of a turn's angle
  struct Part {
    double chi2 = 0.0, dof = 0.0, bound = 0.0;
    double expected = 0.0;  // the chi2 a correct session gives on average (noise and wander)
    double wander = 0.0;    // 1-sigma bias wander over the session assumed (SI), static parts
  };
  Part accel, gyro, turns;
  double turn_excess = 1.0;   // mean expected variance over the fit's, over the turns
  std::string wander_source;  // "sensor profile 'x'" or "generic MEMS bounds"
};
HandheldFitBounds handheld_fit_bounds(const TableFreeResult& result, const RestLimits& limits);

/// "fit" of a hand-held session: each part within its bound (handheld_fit_bounds); a fit whose
/// estimate has not converged (TableFreeResult::converged) fails too.
PlausibilityCheck check_handheld_fit(const TableFreeResult& result, const RestLimits& limits,
                                     const std::string& input);

/// "fit": a solution's chi2 per dof against the limit; `what` names the fit.
PlausibilityCheck check_fit(double chi2_per_dof, const RestLimits& limits, const std::string& input,
                            const std::string& what);

/// The "sample intervals" check of a record in memory (the table-free fit integrates its turns):
/// the readings' intervals against the integrating methods' tolerated spread
/// (PlausibilityLimits::kIntegratingIntervalSpread); without a time column it passes, naming the
/// assumed rate (the turns' timing is checked against gravity: turn_timing.hpp).
PlausibilityCheck check_reading_intervals(const LogFormat& log,
                                          const std::vector<ImuReading>& readings,
                                          const std::string& input);

/// The whole gate of a hand-held record before its fit (table-free): its poses as rests (`poses`
/// index `readings`, rates SI), its two triads one signal or not, the same file twice, its sample
/// intervals (check_reading_intervals).
PlausibilityReport check_handheld(const LogFormat& log, const std::vector<ImuReading>& readings,
                                  const std::vector<Pose>& poses, double g,
                                  const RestLimits& limits, const std::string& input);

/// The whole gate of a six-face session before its fit: the declared faces as rests, the turns'
/// readings for one signal, the same file twice.
PlausibilityReport check_six_face(const LogFormat& log, const std::vector<PartStatistics>& parts,
                                  const FerrarisDeclaration& declared, double g,
                                  const RestLimits& limits, const std::string& input);

/// The cause of a filter's divergence the data show, when they do: the white-noise density of the
/// log's outputs over [t0, t1] (log time, s; a rest before the divergence, rest_statistics)
/// against the densities the filter assumes (the profile's: rad/sqrt(s), m/s/sqrt(s)). Empty
/// when every axis is within kNoiseExcess times them (or the interval has fewer than 3 readings).
inline constexpr double kNoiseExcess = 3.0;
std::string rest_noise_cause(const LogFormat& log, double t0, double t1, double gyro_white,
                             double accel_white);

/// The line a session's noise statement starts with: the record's length at the declared rate,
/// and whether the times come from the log or from the rate alone.
std::string record_statement(const LogFormat& log, std::size_t samples, double seconds);

}  // namespace sinscal
