// Static poses of a hand-held multi-position session, found in the raw data: a sample is at rest
// when its windowed gyro and accelerometer variances are at the level of the record's own static
// noise (found from the record in two passes; no absolute rate compared, so unknown offsets do no
// harm). The number of poses is found, not given; O(N). The test and its thresholds:
// docs/methods/table-free.md "Static poses, found in the data".
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
