// The physics plausibility gate: before any estimate, the log is read once and each static dwell
// of the plan is compared with what the Earth and the plan say a table at rest must show. A wrong
// unit, a flipped or swapped axis, the wrong plan or clipped data fail here, named, instead of
// becoming coefficients with small sigmas.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/earth.hpp"
#include "rig/io/log_io.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

struct SensorProfile;
struct Session;
struct EquivalentInputs;
struct ClosedFormReport;
struct RateTableResult;
struct PassLinearization;

/// What a static dwell may show and still be plausible. SI units.
struct PlausibilityLimits {
  double specific_force = 0.05 * 9.80665;  // m/s^2: tolerated | |f_b| - g | of a dwell's mean
  bool check_rate = false;                 // without a profile the gyro biases are unknown
  double rate = 0.0;                       // rad/s: tolerated | |omega_ib_b| - Earth rate |
  double direction = 0.0;                  // rad: tolerated angle, gravity measured vs planned
  double accel_range = 0.0;                // m/s^2: saturation (0: none)
  double gyro_range = 0.0;                 // rad/s
  double accel_white = 0.0;                // m/s/sqrt(s): for the noise of a dwell's mean
  double gyro_white = 0.0;                 // rad/sqrt(s)
  double max_stage1_chi2_per_dof = 10.0;   // closed form: a dwell's fit far above 1
  double stage2_fit_z = 4.0;  // closed form: stage 2's chi2 above its quantile at this normal tail
  /// The integrating methods (Kalman filter, closed form): the tolerated spread of the log's
  /// sample intervals, (99th - 1st percentile) / median; 0: not checked (the means-only methods).
  double max_interval_spread = 0.0;
  /// > 0: the log has no time column and the reader takes its times from this rate (Hz): the
  /// intervals cannot show a spread and the rate is an assumption the check names.
  double assumed_rate_hz = 0.0;
  /// The spread the integrating methods set (docs/usage/plausibility.md, "sample intervals"): a
  /// timing error of this fraction of the interval during a 90 deg turn at 10 deg/s sampled at
  /// 100 Hz walks the integrated angle by about 1 arcmin, the attitude budget of a table session.
  static constexpr double kIntegratingIntervalSpread = 0.02;

  /// The profile's thermal terms, 3 times their largest as the base terms': at a dwell's mean
  /// temperature T the specific-force and rate tolerances grow by sum over the degree d of
  /// `*_thermal[d - 1] |T - T0|^d`, the rate's also by `rate_per_temperature_rate |dT/dt|` (the
  /// gyro bias in dT/dt). Zero without thermal terms; not used on a log without temperatures.
  double reference_temperature_c = 25.0;           // T0, deg C
  std::array<double, 3> specific_force_thermal{};  // m/s^2 per C^d
  std::array<double, 3> rate_thermal{};            // rad/s per C^d
  double rate_per_temperature_rate = 0.0;          // rad/s per C/s
  /// The thermal part of a tolerance (`specific_force_thermal` or `rate_thermal`) at |T - T0|.
  static double thermal_part(const std::array<double, 3>& per_degree, double dT);

  /// Bounds from the sensor profile's error ranges (3 times the largest error they allow, plus
  /// 5 noise sigmas of a dwell's mean; the thermal terms at each dwell's temperature), or generic
  /// bounds without a profile (nullptr).
  static PlausibilityLimits from_profile(const SensorProfile* profile);
};

/// One check of the gate.
struct PlausibilityCheck {
  std::string name;  // "saturation", "gravity magnitude", "Earth rate", "gravity direction", ...
  bool passed = true;
  std::string detail;  // what was measured against what was expected, and the likely cause
};

struct PlausibilityReport {
  std::vector<PlausibilityCheck> checks;
  bool passed() const;
  /// The failed checks, one per line.
  std::string failures() const;
};

/// A failed gate: the message names the log, the dwell and the likely cause (unit, axis, plan,
/// profile). apps/ exit 2; --force runs anyway and records the report.
class PlausibilityError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The mean specific force and rate of one static dwell of the plan.
struct DwellMean {
  PlanDwell dwell;
  Eigen::Vector3d f_b = Eigen::Vector3d::Zero();         // m/s^2
  Eigen::Vector3d omega_ib_b = Eigen::Vector3d::Zero();  // rad/s
  double seconds = 0.0;                                  // averaged time
  std::size_t samples = 0;
  /// The log's temperatures over the averaged samples (when it has them): the means, and the
  /// gyros' rate of change from the first to the last sample (deg C, deg C/s).
  bool has_temperature = false;
  double accel_temperature_c = 0.0, gyro_temperature_c = 0.0;
  double gyro_temperature_rate = 0.0;
};

/// Reads the log once: the means over the middle of each static dwell (the plan's timing shifted
/// by `time_offset`; `dwell_checks` false skips them, e.g. when the dwells come from the data) and
/// saturation at the limits' ranges. Then compares each dwell with the Earth at the site and the
/// plan's attitude. A read error ends the pass (the estimators report it): the gate judges what it
/// read.
PlausibilityReport check_plausibility(LogReader& reader, const std::string& input,
                                      const PlanTimeline& timeline, const Site& site,
                                      double time_offset, const PlausibilityLimits& limits,
                                      bool dwell_checks = true);

/// The gate on a session's own log, plan, site and time offset.
PlausibilityReport check_plausibility(const Session& session, const PlausibilityLimits& limits,
                                      bool dwell_checks = true);

/// A unit mistaken for another: the ratio it puts between a measured magnitude and the true one,
/// and the cause to name. With a sample interval `dt` > 0 also rates taken as increments and
/// back (or a wrong rate).
struct UnitFactor {
  double value;
  std::string cause;
};
std::vector<UnitFactor> unit_factors(bool gyro, double dt);

/// The failures of one check over several dwells or rests: the check shows the first three and
/// the count of the others (`items`: "dwells", "rests").
struct PlausibilityFindings {
  std::vector<std::string> lines;
  std::string items = "dwells";
  void add(const std::string& s) { lines.push_back(s); }
  PlausibilityCheck check(const std::string& name) const;
};

/// A figure in a gate's message: `precision` significant digits.
std::string plausibility_number(double v, int precision = 4);

/// Throws PlausibilityError listing the failed checks unless the report passed or `force`.
void enforce(const PlausibilityReport& report, bool force);

/// The limits of the integrating methods (Kalman filter, closed form) on `log`: `limits` with
/// the sample intervals checked (and the rate assumed when the log has no time column).
PlausibilityLimits integrating_limits(PlausibilityLimits limits, const LogFormat& log);

/// The spread of a log's sample intervals.
struct IntervalSpread {
  std::size_t intervals = 0;
  double low = 0.0, median = 0.0, high = 0.0;  // s: 1st percentile, median, 99th percentile
  /// s: the timestamps' resolution when the intervals sit on a grid (separate values, e.g. 9, 10
  /// and 11 ms stamped in whole ms at 100 Hz), else 0. Rounding a steady clock's times moves
  /// each interval by up to one resolution, and the integrated errors telescope: not counted.
  double resolution = 0.0;
  double spread() const { return median > 0.0 ? (high - low) / median : 0.0; }
  /// The spread beyond the timestamps' rounding: what the check compares with its limit.
  double jitter() const {
    return median > 0.0 ? std::max(0.0, high - low - 2.0 * resolution) / median : 0.0;
  }
};
/// The spread of sample intervals held in memory (s, each positive; others are skipped), with the
/// timestamps' grid found as the log pass finds it.
IntervalSpread interval_spread(const std::vector<double>& intervals);
/// The table methods' remedy for irregular intervals.
inline const char* const kIntervalRemedyTable =
    "use --method rate-table (means only) or a log with a clean time column";
/// The "sample intervals" check: refuses a spread above `limits.max_interval_spread`, naming
/// `remedy` (the caller's: what its method's user can do; a pass without a time column names the
/// assumed rate in its detail).
PlausibilityCheck check_interval_spread(const IntervalSpread& s, const PlausibilityLimits& limits,
                                        const std::string& input,
                                        const std::string& remedy = kIntervalRemedyTable);

/// The closed form's stage-1 fits: a dwell whose residual chi2 per dof is far above 1 does not
/// fit the model (the data or the plan are not what the session says).
PlausibilityCheck check_stage1_fit(const std::vector<EquivalentInputs>& stage1,
                                   const PlausibilityLimits& limits, const std::string& input);
/// The closed form's linear range: after its relinearizations about its own gyro biases
/// (run_closed_form_relinearized) no dwell's gyro inputs may turn the attitude beyond what stage
/// 1's linear model tolerates (closed_form_turn); the cause named is the gyro biases. Nor may
/// its accelerometer inputs drive the velocity beyond the range (after the relinearization about
/// the accelerometers' bias, scale and misalignment, an accelerometer error the model lacks).
PlausibilityCheck check_linear_range(const ClosedFormReport& r, const std::string& input);
/// The Kalman filter's linear range: its last pass (of `passes`; 0: automatic) may not leave the
/// second-order term of its linearization beyond a whole sigma (the automatic passes stop below
/// kLinearizationShare, a tenth)
/// (filter/kalman/pass_linearization.hpp); the cause named is the coefficients the pass moved
/// far from the model it linearized about, and the remedy more passes (`streamed`: the log came
/// on standard input, read once, so the remedy is to give it as a file).
PlausibilityCheck check_kf_linearization(const PassLinearization& last, int passes, int passes_run,
                                         const std::string& input, bool streamed = false);
/// The closed form's stage 2: its residual chi2 (dof = inputs - rank) against the chi-square
/// quantile at the normal tail of `limits.stage2_fit_z`: above it the dwells do not fit one set
/// of the model's coefficients.
PlausibilityCheck check_stage2_fit(const ClosedFormReport& r, const PlausibilityLimits& limits,
                                   const std::string& input);

/// The triads ("gyro", "accel") whose rate-table fit is beyond its quantile (check_rate_table_fit's
/// rule).
std::vector<std::string> failed_rate_table_triads(const RateTableResult& r,
                                                  const PlausibilityLimits& limits);

/// The rate table's fit, triad by triad: each triad's chi2 against its chi-square quantile at
/// the normal tail of `limits.stage2_fit_z` (the same tail as the closed form's stage 2); above
/// it the segments' means do not fit the model (a segment not at its commanded rate, a gyro
/// offset while turning the model lacks, noise densities too small).
PlausibilityCheck check_rate_table_fit(const RateTableResult& r, const PlausibilityLimits& limits,
                                       const std::string& input);

}  // namespace sinscal
