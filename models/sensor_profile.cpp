#include "models/sensor_profile.hpp"

#include <algorithm>
#include <random>
#include <vector>

#include "models/config.hpp"
#include "models/units.hpp"

namespace sinscal {

std::string coefficient_family(const std::string& name) {
  if (name == "time_delay") return name;
  const auto first = name.find('.');
  const auto second = name.find('.', first + 1);
  return name.substr(0, second);
}

bool SensorProfile::has(const std::string& family) const {
  const auto it = ranges.find(family);
  return it != ranges.end() && it->second.present();
}

SensorProfile SensorProfile::load(const std::string& path) {
  const IniFile ini(path);
  SensorProfile p;
  p.path = path;
  p.name = ini.get_string("sensor.name", path);
  ini.check_keys("sensor", {"name", "description"});
  struct Family {
    const char* section;
    const char* key;
    QuantityKind kind;
    const char* unit;
  };
  const std::vector<Family> families = {
      {"gyro", "bias", QuantityKind::AngularRate, "deg/h"},
      {"gyro", "scale", QuantityKind::Ratio, "ppm"},
      {"gyro", "misalignment", QuantityKind::Angle, "arcsec"},
      {"gyro", "scale_asym", QuantityKind::Ratio, "ppm"},
      {"gyro", "g_sensitivity", QuantityKind::GSensitivity, "deg/h/g"},
      {"accel", "bias", QuantityKind::Acceleration, "ug"},
      {"accel", "scale", QuantityKind::Ratio, "ppm"},
      {"accel", "misalignment", QuantityKind::Angle, "arcsec"},
      {"accel", "scale_asym", QuantityKind::Ratio, "ppm"},
      {"accel", "k2", QuantityKind::QuadraticScale, "ug/g^2"},
      {"accel", "lever_arm", QuantityKind::Length, "mm"},
      {"timing", "time_delay", QuantityKind::Time, "ms"},
  };
  for (const auto& f : families) {
    const std::string key = std::string(f.section) + "." + f.key;
    if (!ini.has(key)) continue;
    const auto v = ini.get_quantities(key, f.kind, f.unit);
    if (v.size() > 2) throw ConfigError(ini.where(key) + "expected one value or a range 'lo hi'");
    CoefficientRange r;
    r.fixed = v.size() == 1;
    r.lo = v.front();
    r.hi = v.back();
    if (!r.fixed && (r.lo < 0.0 || r.hi < r.lo))
      throw ConfigError(ini.where(key) + "a range needs 0 <= lo <= hi");
    p.ranges[f.section == std::string("timing") ? std::string(f.key) : key] = r;
  }
  for (const auto& f : families) {
    const std::string family = f.section == std::string("timing")
                                   ? std::string(f.key)
                                   : std::string(f.section) + "." + f.key;
    const std::string key = "targets." + family;
    if (!ini.has(key)) continue;
    const double v = ini.get_quantity(key, f.kind, f.unit);
    if (!(v > 0.0)) throw ConfigError(ini.where(key) + "a sigma target must be positive");
    p.sigma_targets[family] = v;
  }
  using Q = QuantityKind;
  auto& g = p.noise.gyro;
  g.white = ini.get_quantity("gyro.arw", Q::AngleRandomWalk, "deg/sqrt(h)", 0.0);
  g.bias_instability = ini.get_quantity("gyro.bias_instability", Q::AngularRate, "deg/h", 0.0);
  g.correlation_time = ini.get_quantity("gyro.correlation_time", Q::Time, "s", 3600.0);
  g.random_walk =
      ini.get_quantity("gyro.rate_random_walk", Q::RateRandomWalk, "deg/h/sqrt(h)", 0.0);
  g.quantum = ini.get_quantity("gyro.quantum", Q::Angle, "arcsec", 0.0);
  p.gyro_range = ini.get_quantity("gyro.range", Q::AngularRate, "deg/s", 0.0);
  auto& a = p.noise.accel;
  a.white = ini.get_quantity("accel.vrw", Q::VelocityRandomWalk, "ug/sqrt(Hz)", 0.0);
  a.bias_instability = ini.get_quantity("accel.bias_instability", Q::Acceleration, "ug", 0.0);
  a.correlation_time = ini.get_quantity("accel.correlation_time", Q::Time, "s", 3600.0);
  a.random_walk = ini.get_quantity("accel.random_walk", Q::AccelRandomWalk, "ug/sqrt(h)", 0.0);
  a.quantum = ini.get_quantity("accel.quantum", Q::Velocity, "m/s", 0.0);
  p.accel_range = ini.get_quantity("accel.range", Q::Acceleration, "g", 0.0);
  for (const auto* tn : {&g, &a})
    if (tn->correlation_time <= 0.0)
      throw ConfigError(path + ": correlation_time must be positive");
  ini.check_keys("gyro",
                 {"bias", "scale", "misalignment", "scale_asym", "g_sensitivity", "arw",
                  "bias_instability", "correlation_time", "rate_random_walk", "quantum", "range"});
  ini.check_keys("accel",
                 {"bias", "scale", "misalignment", "scale_asym", "k2", "lever_arm", "vrw",
                  "bias_instability", "correlation_time", "random_walk", "quantum", "range"});
  ini.check_keys("timing", {"time_delay"});
  for (const auto& key : ini.keys()) {
    const auto section = key.substr(0, key.find('.'));
    if (section == "targets") {
      const std::string family = key.substr(8);
      if (std::none_of(families.begin(), families.end(), [&](const Family& f) {
            return family == (f.section == std::string("timing")
                                  ? std::string(f.key)
                                  : std::string(f.section) + "." + f.key);
          }))
        throw ConfigError(ini.where(key) +
                          "unknown coefficient family in [targets] (e.g. gyro.bias, accel.k2, "
                          "time_delay)");
      continue;
    }
    if (section != "sensor" && section != "gyro" && section != "accel" && section != "timing")
      throw ConfigError(ini.where(key) +
                        "unknown section (known: sensor, gyro, accel, timing, targets)");
  }
  return p;
}

ImuErrorModel SensorProfile::draw(std::uint64_t seed) const {
  ImuErrorModel m;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (auto& [info, value] : m.coefficient_refs()) {
    const auto it = ranges.find(coefficient_family(info.name));
    if (it == ranges.end() || !it->second.present()) continue;
    const CoefficientRange& r = it->second;
    if (r.fixed) {
      *value = r.lo;
    } else {
      const double magnitude = r.lo + (r.hi - r.lo) * unit(rng);
      *value = unit(rng) < 0.5 ? -magnitude : magnitude;
    }
  }
  return m;
}

}  // namespace sinscal
