// Static poses of a hand-held multi-position session, found in the raw data. The sensors' offsets
// are unknown (a MEMS gyro may read several deg/s at rest), so nothing is compared with an
// absolute rate: a sample is at rest when the variance of the gyro and of the accelerometer
// readings over a centred window about it is at the level of the record's own static noise.
//
// The noise level is found from the record itself, in two passes. Pass 1 takes, per channel, a
// low quantile of the windowed variances over the whole record (a hand-held session rests most of
// the time, so the low quantiles are static windows). Pass 2 re-estimates it as the median of
// the windowed variances of the windows pass 1 called static, corrected for the median of the
// chi-square distribution. With it, a window is static when the sum over the three axes of
// variance / noise variance, which is chi-square with 3 (w - 1) degrees of freedom over (w - 1)
// for white noise, stays below its (1 - false_alarm) quantile times `margin` (real sensors'
// noise is not white; hand-held motion exceeds the noise by orders of magnitude, so the margin
// costs nothing at the edges). A pose is a run of static window centres, extended towards the
// edges of their windows reading by reading while every channel stays within `edge_sigmas` noise
// sigmas of the run's mean (so its edges are where the motion stops and starts, not half a window
// inside, and a hand settling slowly at the start is left out); at least `min_duration` long.
// The number of poses is found, not given. O(N) time and memory (cumulative sums).
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <stdexcept>
#include <vector>

#include "rig/handheld.hpp"

namespace sinscal {

/// Input the detector cannot work with (too short, times not increasing, no static part).
class PoseDetectorError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct PoseDetectorOptions {
  double window = 1.0;              // s: centred window of the variances
  double min_duration = 2.0;        // s: shorter static stretches are not poses
  double reference_quantile = 0.1;  // pass 1 noise level: this quantile of windowed variances
  double false_alarm = 1e-3;        // white noise: chance that a static window is called moving
  double margin = 3.0;              // factor on the chi-square threshold (non-white noise)
  double edge_sigmas = 5.0;         // readings at a pose's edges: within this many noise sigmas
  /// false: the accelerometers alone decide (imu_tk's detector), for sessions where a hand holds
  /// the unit during the poses: the gyros then see its tremor and slow drift, which a gyro test
  /// at the noise level calls motion.
  bool use_gyro = true;
};

/// One static pose found. Means and standard deviations in the readings' units (counts or SI).
struct Pose {
  int index = 0;          // 1-based, in time order
  std::size_t first = 0;  // index of the first reading of the pose
  std::size_t last = 0;   // index of the last reading (inclusive)
  double t_start = 0.0;   // s: time of the first reading
  double t_end = 0.0;     // s: time of the last reading
  std::size_t count = 0;  // readings in the pose
  Eigen::Vector3d accel_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_std = Eigen::Vector3d::Zero();  // per-reading standard deviation
  Eigen::Vector3d gyro_std = Eigen::Vector3d::Zero();
  double duration() const { return t_end - t_start; }
};

struct PoseDetection {
  std::vector<Pose> poses;
  std::size_t window_samples = 0;  // odd
  double sample_interval = 0.0;    // s: median interval of the readings
  /// Per-reading noise variance at rest per axis (pass 2), readings' units squared.
  Eigen::Vector3d accel_noise_variance = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_noise_variance = Eigen::Vector3d::Zero();
  /// Threshold on sum(windowed variance / noise variance) over the three axes.
  double threshold = 0.0;
};

/// Finds the static poses of a record. Throws PoseDetectorError when the record is shorter than
/// three windows, its times do not increase, or no window is quiet enough to be static.
PoseDetection detect_poses(const std::vector<ImuReading>& readings,
                           const PoseDetectorOptions& options = {});

/// Mean and per-reading standard deviation of readings [first, last] (inclusive).
void reading_statistics(const std::vector<ImuReading>& readings, std::size_t first,
                        std::size_t last, Eigen::Vector3d& accel_mean, Eigen::Vector3d& gyro_mean,
                        Eigen::Vector3d& accel_std, Eigen::Vector3d& gyro_std);

}  // namespace sinscal
