// IMU simulator: incremental angles and velocities at a fixed rate, integrated through the truth
// motion with Gauss-Legendre quadrature between the motion's knots (exact to rounding for the
// smooth pieces), the error model applied at every quadrature node (so nonlinear terms, size
// effect and time delay are exact), then noise and quantization.
#pragma once

#include <algorithm>
#include <cstdint>

#include "models/imu_error_model.hpp"
#include "models/noise_model.hpp"
#include "rig/imu_sample.hpp"
#include "rig/motion.hpp"
#include "rig/thermal.hpp"

namespace sinscal {

struct SimulatorOptions {
  double rate_hz = 100.0;
  bool noise = true;
  std::uint64_t noise_seed = 1;
  double gyro_range = 0.0;    // rad/s; outputs beyond it are clipped (0: no limit)
  double accel_range = 0.0;   // m/s^2
  bool table_angles = false;  // fill the table's axis angles (the motion must be table moves)
  /// Log time at which the motion starts (s; TableDynamics::start_offset): the IMU rests in the
  /// start attitude before; negative, the log begins inside the motion.
  double motion_start = 0.0;
  /// The sensor's temperature over the motion's time (a chamber; null: at the reference
  /// temperature, no column). Not owned: it must outlive the simulator. Both triads read it, the
  /// samples carry it (deg C at the end of each interval).
  const SensorTemperature* temperature = nullptr;
};

class ImuSimulator : public SampleSource {
 public:
  ImuSimulator(const Motion& motion, const ImuErrorModel& errors, const NoiseModel& noise,
               const SimulatorOptions& options);
  /// Next sample, until the end of the motion.
  bool next(ImuSample& sample) override;
  /// Number of samples: enough to cover the whole motion (the IMU rests after its end).
  std::size_t total_samples() const { return total_; }
  /// Goes on from sample `k` (0-based: the next sample read is the one ending at (k + 1) / rate);
  /// the samples before it are skipped, not simulated.
  void skip_to(std::size_t k) { k_ = std::min(k, total_); }
  /// Samples clipped by the measurement range so far.
  std::size_t saturated() const { return saturated_; }

 private:
  Eigen::Vector3d integrate(double a, double b, double shift, bool gyro) const;
  const Motion& motion_;
  ImuErrorModel errors_;
  SimulatorOptions options_;
  NoiseGenerator noise_;
  double dt_;
  std::size_t k_ = 0, total_ = 0, saturated_ = 0;
};

}  // namespace sinscal
