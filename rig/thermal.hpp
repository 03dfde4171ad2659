// A thermal chamber around the table, for simulations (docs/formats.md "Chamber files"): the
// chamber's air temperature as a program of soaks or a ramp, and the sensor's own temperature,
// which follows the air with a first-order lag (the sensor profile's [thermal] time_constant).
//
//   soaks: the air moves to each soak's temperature at `air_rate` and holds it; `settle` seconds
//          after it got there the plan runs (one session per soak), then the next soak begins;
//   ramp:  the air moves to `from` at `air_rate`, holds it for `settle` seconds, then changes at
//          `rate` to `to` and holds it; the plan, repeated, runs from the end of the settling to
//          the end of the ramp (one session).
// Before the program, the air and the sensor are at `start`.
#pragma once

#include <string>
#include <vector>

namespace sinscal {

/// The air temperature of a chamber as a piecewise-linear function of time (deg C, s).
struct ChamberAir {
  std::vector<double> t;        // s, increasing knots
  std::vector<double> celsius;  // deg C at the knots; constant before the first and after the last
  double at(double time) const;
};

/// The sensor's temperature in a chamber: tau dT/dt = T_air(t) - T, exact for piecewise-linear
/// air (each piece's closed form), from T(t_0) = the air's at the first knot.
class SensorTemperature {
 public:
  SensorTemperature(ChamberAir air, double time_constant_s);
  /// deg C at `time` (s).
  double at(double time) const;
  /// deg C/s at `time`.
  double rate(double time) const;

 private:
  void piece(double time, std::size_t& k, double& slope) const;
  ChamberAir air_;
  double tau_;
  std::vector<double> start_;  // the sensor's temperature at each knot
};

/// The rate of change of a measured temperature in constant memory: the slope between the
/// latest reading and the one `window` seconds before it (readings kept every window / 8 s), so
/// a sensor's quantization and noise average out. 0 until a tenth of the window has passed.
class TemperatureRate {
 public:
  explicit TemperatureRate(double window_s = 60.0) : window_(window_s) {}
  /// Adds the reading at `t` (s, increasing) and returns the rate (deg C/s).
  double add(double t, double celsius);

 private:
  static constexpr std::size_t kKept = 9;
  double window_;
  double t_[kKept] = {}, c_[kKept] = {};
  std::size_t count_ = 0, head_ = 0;  // ring of readings, head_: the oldest
};

/// A chamber file ([chamber]): what simulate runs.
struct ChamberProgram {
  enum class Type { Soaks, Ramp };
  std::string path;
  Type type = Type::Soaks;
  double start_c = 25.0;            // deg C: the air and the sensor before the program
  std::vector<double> soaks_c;      // deg C (soaks)
  double settle_s = 3600.0;         // s at each soak's (the ramp's start) temperature
  double from_c = 0.0, to_c = 0.0;  // deg C (ramp)
  double rate_c_per_s = 0.0;        // deg C/s (ramp, positive)
  double air_rate_c_per_s = 0.05;   // deg C/s: how fast the air moves between temperatures

  /// Reads and checks a chamber file; throws ConfigError naming file, line and key.
  static ChamberProgram load(const std::string& path);
  /// The air from the start of the program in the time of soak `k`'s session (0-based; 0 s: its
  /// plan starts), each soak's plan lasting `plan_s`.
  ChamberAir soak_air(std::size_t k, double plan_s) const;
  /// The air from the start of the program in the time of the ramp's session (0 s: the plan
  /// starts, after the settling).
  ChamberAir ramp_air() const;
  /// Seconds from the end of the settling to the end of the ramp (ramp).
  double ramp_duration() const { return std::abs(to_c - from_c) / rate_c_per_s; }
};

}  // namespace sinscal
