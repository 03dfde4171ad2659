// The sample intervals of a log without a time column, measured from gravity's cycles (issue 34,
// item 4: the APOPHIS BMI160 logs, readings at an irregular 12-18 Hz without time). While the
// unit turns about an axis across gravity, gravity's direction in the plane across the axis
// advances by the turn's rate times each reading's true interval: its step between two readings
// over the gyros' rate about the axis is that interval. The accelerometers' and gyros' noise
// spread the steps too; their share, from the noise the turn's rests show, is taken out. The
// accelerometers' bias moves gravity's track off the origin and their scale factors and
// misalignments make it an ellipse: each run about one axis has its ellipse fitted and mapped onto
// a circle, and the steps are measured about its centre (about the origin, a regular 15 Hz log
// with 30-50 mg biases showed a 3.3 % spread that is not there).
// NOT YET A GATE CHECK: on the APOPHIS logs (accelerometer noise 6-18 mg per reading at steps of
// 1.7 deg) the steps' spread comes out 100-180 % against a noise share of 25-60 %: the noise while
// turning is not the rests' (docs/measured/apophis/README.md, "Not done").
#pragma once

#include <string>
#include <vector>

#include "filter/plausibility/plausibility.hpp"
#include "filter/plausibility/turn_timing.hpp"
#include "rig/io/log_io.hpp"

namespace sinscal {

struct GravityCycleIntervals {
  int turns = 0;              // runs about one axis across gravity that gave intervals
  std::size_t intervals = 0;  // intervals measured
  double mean = 0.0;          // s: their mean (the log's true mean interval)
  double nominal = 0.0;       // s: the interval the log's rate assumes
  double jitter = 0.0;        // the intervals' spread (std / mean), the noise's share out
  double jitter_sigma = 0.0;  // its sigma
  double noise = 0.0;         // the spread the noise alone gives (std / mean)
  double mean_sigma = 0.0;    // s: the mean's sigma from the noise and the jitter
  /// The spread beyond what the integrating methods tolerate (a jitter whose 1st-99th
  /// percentile spread, 4.65 standard deviations of a normal spread, exceeds
  /// PlausibilityLimits::kIntegratingIntervalSpread), by more than 4 of its sigmas.
  bool irregular() const;
};

/// The intervals of the turns (turn_timings) whose axis lies across gravity: the readings where
/// the rate about the axis is above half the turn's largest and gravity across the axis above
/// half its magnitude. One streaming read of the log.
GravityCycleIntervals gravity_cycle_intervals(const LogFormat& log,
                                              const std::vector<TurnTiming>& turns);

/// The gate's check "sample intervals from gravity" (a log without a time column): fails when
/// the measured intervals are irregular, or their mean is off the nominal by more than 4 of its
/// sigmas and the profile's gyro scale range (`relative`); passes, saying so, when no turn
/// crosses gravity.
PlausibilityCheck check_gravity_cycle_intervals(const GravityCycleIntervals& g,
                                                const LogFormat& log, double relative);

}  // namespace sinscal
