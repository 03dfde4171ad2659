#include "models/sensor_profile.hpp"

#include <algorithm>
#include <random>
#include <vector>

#include "models/coefficient_families.hpp"
#include "models/config.hpp"
#include "models/units.hpp"

namespace sinscal {

bool SensorProfile::has(const std::string& family) const {
  const auto it = ranges.find(family);
  return it != ranges.end() && it->second.present();
}

std::map<std::string, double> read_sigma_targets(const IniFile& ini) {
  for (const auto& key : ini.keys()) {
    if (key.rfind("targets.", 0) != 0) continue;
    try {
      coefficient_family_info(key.substr(8));
    } catch (const std::invalid_argument& e) {
      throw ConfigError(ini.where(key) + "in [targets]: " + e.what());
    }
  }
  std::map<std::string, double> out;
  for (const auto& f : coefficient_families()) {
    const std::string key = "targets." + f.name;
    if (!ini.has(key)) continue;
    const double v = ini.get_quantities(key, f.units, f.unit(), 1).front();
    if (!(v > 0.0)) throw ConfigError(ini.where(key) + "a sigma target must be positive");
    out[f.name] = v;
  }
  return out;
}

SensorProfile SensorProfile::load(const std::string& path) {
  const IniFile ini(path);
  SensorProfile p;
  p.path = path;
  p.name = ini.get_string("sensor.name", path);
  ini.check_keys("sensor", {"name", "description"});
  // Every family of the table: its range under its profile key, its sigma target under
  // [targets] family.
  for (const auto& f : coefficient_families()) {
    const std::string& key = f.profile_key;
    if (!ini.has(key)) continue;
    const auto v = ini.get_quantities(key, f.units, f.unit());
    if (v.size() > 2) throw ConfigError(ini.where(key) + "expected one value or a range 'lo hi'");
    CoefficientRange r;
    r.fixed = v.size() == 1;
    r.lo = v.front();
    r.hi = v.back();
    if (!r.fixed && (r.lo < 0.0 || r.hi < r.lo))
      throw ConfigError(ini.where(key) + "a range needs 0 <= lo <= hi");
    p.ranges[f.name] = r;
  }
  p.sigma_targets = read_sigma_targets(ini);
  using Q = QuantityKind;
  // Noise amplitudes, quanta and measurement ranges: not negative (0 or absent: none);
  // correlation times: positive.
  auto amount = [&](const std::string& key, Q kind, const std::string& unit) {
    const double v = ini.get_quantity(key, kind, unit, 0.0);
    if (!(v >= 0.0)) throw ConfigError(ini.where(key) + "must not be negative");
    return v;
  };
  auto correlation_time = [&](const std::string& key) {
    const double v = ini.get_quantity(key, Q::Time, "s", 3600.0);
    if (!(v > 0.0)) throw ConfigError(ini.where(key) + "must be positive");
    return v;
  };
  auto& g = p.noise.gyro;
  g.white = amount("gyro.arw", Q::AngleRandomWalk, "deg/sqrt(h)");
  g.bias_instability = amount("gyro.bias_instability", Q::AngularRate, "deg/h");
  g.correlation_time = correlation_time("gyro.correlation_time");
  g.random_walk = amount("gyro.rate_random_walk", Q::RateRandomWalk, "deg/h/sqrt(h)");
  g.quantum = amount("gyro.quantum", Q::Angle, "arcsec");
  p.gyro_range = amount("gyro.range", Q::AngularRate, "deg/s");
  auto& a = p.noise.accel;
  a.white = amount("accel.vrw", Q::VelocityRandomWalk, "ug/sqrt(Hz)");
  a.bias_instability = amount("accel.bias_instability", Q::Acceleration, "ug");
  a.correlation_time = correlation_time("accel.correlation_time");
  a.random_walk = amount("accel.random_walk", Q::AccelRandomWalk, "ug/sqrt(h)");
  a.quantum = amount("accel.quantum", Q::Velocity, "m/s");
  p.accel_range = amount("accel.range", Q::Acceleration, "g");
  if (ini.has("thermal.reference_temperature")) {
    p.reference_temperature_c =
        ini.get_quantities("thermal.reference_temperature", {{"C", 1.0}}, "C", 1).front();
    if (!(p.reference_temperature_c >= -60.0 && p.reference_temperature_c <= 130.0))
      throw ConfigError(ini.where("thermal.reference_temperature") +
                        "expected a temperature within -60 ... 130 C, where sensors work");
  }
  p.thermal_time_constant = amount("thermal.time_constant", Q::Time, "s");
  // Known keys: the noise and range keys above, and every family's profile key.
  std::map<std::string, std::vector<std::string>> allowed = {
      {"sensor", {"name", "description"}},
      {"gyro",
       {"arw", "bias_instability", "correlation_time", "rate_random_walk", "quantum", "range"}},
      {"accel", {"vrw", "bias_instability", "correlation_time", "random_walk", "quantum", "range"}},
      {"timing", {}},
      {"thermal", {"reference_temperature", "time_constant"}}};
  for (const auto& f : coefficient_families()) {
    const auto dot = f.profile_key.find('.');
    allowed[f.profile_key.substr(0, dot)].push_back(f.profile_key.substr(dot + 1));
  }
  std::string sections;
  for (const auto& [section, keys] : allowed) {
    ini.check_keys(section, keys);
    sections += section + ", ";
  }
  for (const auto& key : ini.keys()) {
    const auto section = key.substr(0, key.find('.'));
    if (section == "targets") {
      const std::string family = key.substr(8);
      try {
        coefficient_family_info(family);
      } catch (const std::invalid_argument& e) {
        throw ConfigError(ini.where(key) + "in [targets]: " + e.what());
      }
      continue;
    }
    if (!allowed.count(section))
      throw ConfigError(ini.where(key) + "unknown section (known: " + sections + "targets)");
  }
  return p;
}

ImuErrorModel SensorProfile::draw(std::uint64_t seed) const {
  ImuErrorModel m;
  m.reference_temperature_c = reference_temperature_c;
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
