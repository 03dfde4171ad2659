// The log's time against its turns, for logs without a time column (issue 34: readings at an
// irregular 12-18 Hz logged without time, taken at a nominal 15 Hz). The integrating methods
// (Kalman filter, closed form) need each reading's interval; without a time column nothing shows
// it but the data: between two rests the gyros' turn, integrated at the nominal rate, must carry
// the first rest's gravity direction onto the second's. Where it does not, beyond the rests'
// noise and the gyros' scale and misalignment errors the sensor profile allows, the log's time is
// not the nominal rate. docs/usage/plausibility.md, "turn timing".
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "filter/plausibility/plausibility.hpp"
#include "rig/io/log_io.hpp"

namespace sinscal {

struct SensorProfile;

struct TurnTimingOptions {
  double rate_threshold = 3.0 * M_PI / 180.0;  // rad/s: a smoothed rate below it is rest
  double smoothing = 0.5;                      // s: centred moving average (nominal readings)
  double min_rest = 3.0;                       // s: shorter rests are not used
  double min_turn = 10.0 * M_PI / 180.0;       // rad: smaller turns are not judged
  /// The gyros' errors the profile allows, as a fraction of a turn's path: its scale range plus
  /// its misalignment range (0.1 without a profile: consumer MEMS).
  double relative = 0.1;
  /// Each rest's gravity direction error the profile allows (rad): its accelerometer bias range
  /// over g plus its scale and misalignment ranges (0.15 without a profile: consumer MEMS).
  double accel_direction = 0.15;
  double sigmas = 4.0;  // noise sigmas of the disagreement tolerated
};

/// One turn between two rests.
struct TurnTiming {
  int turn = 0;                     // 1-based, in the log's order
  std::size_t first = 0, last = 0;  // readings of the turn [first, last)
  double integrated = 0.0;          // rad: the rotation the gyros integrate to (nominal time)
  double path = 0.0;                // rad: the integrated |rate| (the turn's path)
  double gravity_angle = 0.0;       // rad between the two rests' mean specific forces
  double disagreement = 0.0;        // rad: the second rest's gravity against the integrated one
  double tolerance = 0.0;           // rad: noise and the profile's sensor errors
  /// rad: how far the integrated turn would leave gravity from where it leaves it now, were the
  /// log's true rate kTimingProbe off the nominal one (a turn about gravity: none).
  double probe_shift = 0.0;
  /// rad/s: the two rests' mean rate (the gyros' bias and the Earth rate), taken from the turn's.
  Eigen::Vector3d rest_omega = Eigen::Vector3d::Zero();
  /// The rests' per-reading noise variance per axis: specific force ((m/s^2)^2), rate ((rad/s)^2).
  double rest_var_f = 0.0, rest_var_omega = 0.0;
  bool agrees() const { return disagreement <= tolerance; }
  /// Whether the turn would show a time error of kTimingProbe beyond its tolerance.
  bool judges() const { return probe_shift > tolerance; }
};

/// The relative error of the nominal rate a turn must be able to show to judge the log's time
/// (the APOPHIS logs' 12-18 Hz about a nominal 15 Hz: up to 25 %).
constexpr double kTimingProbe = 0.25;

/// Every turn between two rests of the log (its readings at the reader's intervals: the nominal
/// rate without a time column), in three streaming reads (memory independent of the log's
/// length); throws LogError as the reader does.
std::vector<TurnTiming> turn_timings(const LogFormat& log, const TurnTimingOptions& options);

/// The gate's check "turn timing": fails on the first turn that disagrees, naming it; and when
/// no turn judges the time (turns about the vertical move no gravity; long turns' tolerances are
/// wider than what a time error moves), since the log's time then cannot be trusted.
PlausibilityCheck check_turn_timing(const std::vector<TurnTiming>& turns, const LogFormat& log);

/// The options with the gyro and accelerometer errors `profile` allows (its scale and
/// misalignment ranges; null: the consumer-MEMS defaults).
TurnTimingOptions turn_timing_options(const SensorProfile* profile);

/// The rule for every integrating method (Kalman filter, closed form, table-free): a log without a
/// time column has its nominal rate checked by its turns between rests (check_turn_timing with
/// the profile's errors); a log with time needs no such check (none returned).
std::optional<PlausibilityCheck> no_time_turn_timing(const LogFormat& log,
                                                     const SensorProfile* profile);

}  // namespace sinscal
