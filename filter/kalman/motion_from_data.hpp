// The table's motion as the data show it, aligned to the plan: the Kalman filter's linearization
// point for logs whose turns do not follow the plan's commanded trapezoids (another tool's
// smoothed profile, servo lag and overshoot, settling and rate ripple, slower turns, a start-time
// offset). docs/methods/kalman-filter.md "The motion from the data".
//
// Two reads of the log, before the filter:
//  1. the log's time against the plan's: the gyros' rate magnitude (0.1 s bins) cross-correlated
//     with the plan's over +-kOffsetSearch; a shift beyond kOffsetResolution is the start-time
//     offset the session did not state;
//  2. each move of the plan, in a window from the middle of the dwell before it to the middle of
//     the dwell after it: the gyros' rates less the bias (the adjacent dwells' means less the
//     Earth rate) and the Earth rate, resolved on the move's axes (the outer axis fixed in the
//     navigation frame, the inner one in the body), smoothed (a zero-phase Gaussian), integrated
//     and scaled to the plan's angle (the gyros' scale errors drop out: the dwells' attitudes
//     are the plan's). Where this profile departs from the plan's by more than the tolerance,
//     the filter linearizes along it and the dwell's updates start where the data are still.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "filter/kalman/kalman_calibrator.hpp"
#include "rig/motion.hpp"
#include "rig/session.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

/// A move whose realized angle stays within this of the plan's at every time follows the plan.
constexpr double kFollowTolerance = 0.01 * units::deg;
/// The start-time offset searched for, and the smallest reported (below it, each move's own
/// profile takes the shift).
constexpr double kOffsetSearch = 60.0;      // s
constexpr double kOffsetResolution = 0.05;  // s
/// Where turns have their own timing, the log's start is located to their detection only.
constexpr double kTimingResolution = 0.1;  // s
/// Zero-phase Gaussian smoothing of the measured rates (sigma, s), sized by the gyros' noise:
/// the smoothed rate's noise and its derivative's (the angular acceleration) within
/// kSmoothingNoise of the move's peak rate and acceleration, at least a sample interval and at
/// most these (a lighter smoothing keeps a table's ripple: 0.1 s wiped out a 10 Hz structural
/// mode whose angular acceleration drives the lever arms' column).
constexpr double kSmoothingNoise = 0.01;
constexpr double kRateSmoothing = 0.05;
constexpr double kAccelSmoothing = 0.1;

/// The smoothing (sigma, s) of a rate of white noise density `density` (rad/s/sqrt(Hz)) sampled
/// every dt whose own noise stays within kSmoothingNoise of `peak`: for the rate (derivative 0)
/// sigma >= N^2 / (2 sqrt(pi) (e R)^2); for its derivative sigma >= (N / (2 pi^(1/4) e A))^(2/3)
/// (the variance of white noise through a Gaussian and its derivative).
double noise_smoothing(double density, double dt, double peak, int derivative);

/// How one move of the data departs from the plan's.
struct MoveDeparture {
  int move = 0;              // 1-based, the plan's moves in order
  std::string label;         // "before dwell 3 (after 2 (+y))"
  double t_plan = 0.0;       // s, plan time the plan's move starts
  double start_shift = 0.0;  // s: when the data reach 50 % of the turn, less the plan's time
  double largest = 0.0;      // rad: the largest |data angle - plan angle| in the move's window
  double overshoot = 0.0;    // rad: beyond the turn's end angle
  double begins = 0.0, ends = 0.0;  // s, plan time: the data's motion (rate above its noise)
  double end_shift = 0.0;           // s: ends less the plan's end
  /// The time shift that lays the plan's profile best over the data's (least squares), and the
  /// largest angle left between them after it (rad): small for a pure shift of the log.
  double fitted_shift = 0.0, shift_residual = 0.0;
  double plan_begins = 0.0, plan_ends = 0.0;
  double turned = 0.0, plan_turned = 0.0;  // rad: the gyros' turn (before scaling), the plan's
  bool follows = true;                     // within kFollowTolerance: the plan's profile is used
};

struct DataMotion {
  double session_offset = 0.0;  // s: the session's time_offset
  double time_offset = 0.0;     // s: the log time at which the plan starts, as found
  double correlation = 0.0;     // of the rate magnitudes at the offset found (0..1)
  std::vector<MoveDeparture> moves;
  /// The motion to linearize along (the plan's where the data follow it), in plan time.
  std::shared_ptr<const Motion> reference;
  /// The plan's dwells, shortened to where the data are still.
  std::shared_ptr<const PlanTimeline> timeline;
  int departing() const {
    int n = 0;
    for (const auto& m : moves) n += m.follows ? 0 : 1;
    return n;
  }
  bool offset_found() const { return std::abs(time_offset - session_offset) > kOffsetResolution; }
  /// One line: "the data follow the plan" or what departs, by how much.
  std::string summary() const;
};

/// The motion of a session's log aligned to its plan (the log read twice). Throws LogError as
/// the log reader does.
DataMotion motion_from_data(const Session& session, const CalibratorOptions& options);

}  // namespace sinscal
