#pragma once

#include <Eigen/Core>
#include <vector>

namespace sinscal {

/// One IMU output: incremental angle and velocity over the interval (t - dt, t], body axes.
struct ImuSample {
  double t = 0.0;                                      // s, end of the interval
  double dt = 0.0;                                     // s, length of the interval
  Eigen::Vector3d dtheta_b = Eigen::Vector3d::Zero();  // rad
  Eigen::Vector3d dv_b = Eigen::Vector3d::Zero();      // m/s
  /// Table axis angles read at t, when the log has them (rig/table.hpp: outer, inner).
  bool has_table = false;
  double table_outer = 0.0;  // rad
  double table_inner = 0.0;  // rad
  /// The sensors' temperatures at t, when the log has them (deg C, docs/conventions.md "Units"):
  /// one per triad, or one per unit (both equal).
  bool has_temperature = false;
  double accel_temperature_c = 0.0;  // deg C
  double gyro_temperature_c = 0.0;   // deg C
  /// The sample's label (a text column of the log, e.g. a part of a six-face session): an index
  /// into LogReader::labels(); -1 when the log has no label column.
  int label = -1;
};

/// Anything that yields IMU samples in time order (simulator, log reader).
class SampleSource {
 public:
  virtual ~SampleSource() = default;
  /// Next sample; false at the end.
  virtual bool next(ImuSample& sample) = 0;
};

/// Samples held in memory (tests, batch use); the vector must outlive the source.
class VectorSource : public SampleSource {
 public:
  explicit VectorSource(const std::vector<ImuSample>& samples) : samples_(samples) {}
  bool next(ImuSample& sample) override {
    if (next_ >= samples_.size()) return false;
    sample = samples_[next_++];
    return true;
  }

 private:
  const std::vector<ImuSample>& samples_;
  std::size_t next_ = 0;
};

}  // namespace sinscal
