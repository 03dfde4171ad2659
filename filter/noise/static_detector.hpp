// Static intervals detected from the IMU data, for logs whose timing does not follow the plan
// (an unknown start offset, pauses, a table driven by hand). Causal, constant memory and O(1)
// per sample: a sample is static when, over the trailing window up to it, the rates' RMS
// deviation from their mean is within half a noise-derived bound and the newest rate within the
// bound, the specific forces likewise, and the mean rate is below a threshold (a turn at
// constant rate about the vertical leaves the accelerometers unchanged). The k-th static
// interval that lasts `min_duration` is the plan's k-th dwell.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "models/noise_model.hpp"
#include "rig/imu_sample.hpp"

namespace sinscal {

struct StaticDetectorOptions {
  double window = 1.0;           // s, trailing window
  double min_duration = 3.0;     // s from the window's start: shorter stops are not dwells
  double rate_threshold = 0.0;   // rad/s: mean rate above it is motion (0: 3 deg/s)
  double gyro_deviation = 0.0;   // rad/s: |rate - window mean| bound at rest (0: from noise)
  double accel_deviation = 0.0;  // m/s^2: the same for the specific force (0: from noise)
  double sigmas = 6.0;           // noise-derived bounds: this many per-sample sigmas
};

/// One static interval found (times of the log).
struct DetectedDwell {
  int index = 0;         // 1-based: the plan's dwell it is taken for
  double t_start = 0.0;  // s: start of the trailing window when the interval began
  double t_end = 0.0;    // s: last static sample so far
};

class StaticDetector {
 public:
  StaticDetector(const NoiseModel& noise, const StaticDetectorOptions& options = {});
  /// Feeds one sample; true if the trailing window up to it is static.
  bool push(const ImuSample& s);
  bool is_static() const { return static_; }
  /// The dwell the data are in now (1-based): static for at least min_duration; 0 otherwise.
  int dwell() const { return static_ && counted_ ? static_cast<int>(found_.size()) : 0; }
  /// Dwells found so far, in order (the last may still be going on).
  const std::vector<DetectedDwell>& dwells() const { return found_; }
  /// The bounds in use (rad/s, m/s^2), for reports.
  double gyro_bound() const { return gyro_bound_; }
  double accel_bound() const { return accel_bound_; }
  double rate_threshold() const { return rate_threshold_; }

 private:
  NoiseModel noise_;
  StaticDetectorOptions o_;
  std::vector<Eigen::Vector3d> rate_, force_;  // ring buffer of the window
  std::vector<double> t_;
  std::size_t next_ = 0, filled_ = 0, since_recount_ = 0;
  Eigen::Vector3d ref_rate_ = Eigen::Vector3d::Zero(), ref_force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_rate_ = Eigen::Vector3d::Zero(), sum_force_ = Eigen::Vector3d::Zero();
  double sq_rate_ = 0.0, sq_force_ = 0.0;
  double gyro_bound_ = 0.0, accel_bound_ = 0.0, rate_threshold_ = 0.0;
  bool static_ = false, counted_ = false;
  double static_since_ = 0.0;
  std::vector<DetectedDwell> found_;
};

}  // namespace sinscal
