// Sensor profiles (config/sensors/*.ini): the ranges from which true coefficients are drawn, the
// noise, the measurement ranges, and which error terms the sensor has. Format: docs/formats.md.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/noise_model.hpp"

namespace sinscal {

/// How one family of coefficients (e.g. "gyro.bias") is drawn, SI units.
/// `key = lo hi`: each coefficient's magnitude uniform in [lo, hi], sign random;
/// `key = v`: every coefficient of the family exactly v.
struct CoefficientRange {
  bool fixed = false;
  double lo = 0.0;
  double hi = 0.0;
  bool present() const { return hi != 0.0 || lo != 0.0; }
};

class IniFile;
/// The [targets] section of an INI (a sensor profile, a targets file): every family's sigma
/// target (SI). Unknown families and targets that are not positive are errors naming the line.
std::map<std::string, double> read_sigma_targets(const IniFile& ini);

struct SensorProfile {
  std::string name;
  std::string path;
  std::map<std::string, CoefficientRange> ranges;  // by family: "gyro.bias", "accel.k2", ...
  NoiseModel noise;
  double gyro_range = 0.0;   // rad/s, |rate| at which the gyros saturate (0: none)
  double accel_range = 0.0;  // m/s^2, |specific force| at which the accels saturate (0: none)
  /// Sigma targets by family ([targets] gyro.bias = 0.005 deg/h): calibration has converged when
  /// every estimated coefficient's sigma is below its family's target. SI.
  std::map<std::string, double> sigma_targets;
  /// [thermal]: T0, the temperature the thermal coefficients are relative to (deg C, default 25),
  /// and the sensor's first-order lag behind the chamber's air (s; the simulator's; 0: none).
  double reference_temperature_c = 25.0;
  double thermal_time_constant = 0.0;

  /// Loads and validates a profile; throws ConfigError naming the file, line and key.
  static SensorProfile load(const std::string& path);
  /// Draws true coefficients; families absent from the profile stay zero.
  ImuErrorModel draw(std::uint64_t seed) const;
  /// True if the family (e.g. "accel.k2") is present in the profile.
  bool has(const std::string& family) const;
};

}  // namespace sinscal
