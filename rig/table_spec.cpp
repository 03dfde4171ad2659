#include "rig/table_spec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "models/config.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

double positive(const IniFile& ini, const std::string& key, QuantityKind kind,
                const std::string& unit, double upper) {
  const double v = ini.get_quantity(key, kind, unit);
  if (!(v > 0.0 && v <= upper))
    throw ConfigError(ini.where(key) + "must be positive and at most " + std::to_string(upper) +
                      " (SI)");
  return v;
}

}  // namespace

TableSpec TableSpec::load(const std::string& path) {
  if (path.empty()) throw ConfigError("table: no file name given");
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw ConfigError(path + ": is a directory, not a table file");
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open table file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse(path, buffer.str());
}

TableSpec TableSpec::parse(const std::string& path, const std::string& text) {
  const IniFile ini(path, text);
  for (const auto& s : ini.sections())
    if (s != "table")
      throw ConfigError(path + ": unknown section [" + s + "] (a table file has [table] only)");
  ini.check_keys("table", {"name", "description", "axes", "max_rate", "max_acceleration",
                           "settling_time", "attitude_accuracy", "reference_on_axes", "jerk_time",
                           "smoothing", "servo_frequency", "servo_damping", "ripple_frequency",
                           "ripple_damping", "rate_ripple", "rate_ripple_period"});
  TableSpec t;
  t.path = path;
  t.name = ini.get_string("table.name", "table");
  t.axes = ini.get_int("table.axes", 2, 2, 3);
  using Q = QuantityKind;
  t.max_rate = positive(ini, "table.max_rate", Q::AngularRate, "deg/s", 100.0);
  t.max_acceleration =
      positive(ini, "table.max_acceleration", Q::AngularAcceleration, "deg/s^2", 1000.0);
  t.settling_time = ini.get_quantity("table.settling_time", Q::Time, "s", 0.0);
  if (!(t.settling_time >= 0.0 && t.settling_time <= 3600.0))
    throw ConfigError(ini.where("table.settling_time") + "must be within 0 and 3600 s");
  t.attitude_sigma = positive(ini, "table.attitude_accuracy", Q::Angle, "arcsec", 0.01);
  t.reference_on_axes = ini.get_bool("table.reference_on_axes", true);
  TableDynamics& d = t.dynamics;
  d.max_rate = t.max_rate;
  d.max_acceleration = t.max_acceleration;
  d.jerk_time = ini.get_quantity("table.jerk_time", Q::Time, "s", 0.0);
  d.smoothing = ini.get_quantity("table.smoothing", Q::Time, "s", 0.0);
  d.servo_frequency = ini.get_quantity("table.servo_frequency", Q::Frequency, "Hz", 0.0);
  d.servo_damping = ini.get_quantity("table.servo_damping", Q::Ratio, "1", 0.7);
  d.ripple_frequency = ini.get_quantity("table.ripple_frequency", Q::Frequency, "Hz", 0.0);
  d.ripple_damping = ini.get_quantity("table.ripple_damping", Q::Ratio, "1", 0.05);
  d.rate_ripple = ini.get_quantity("table.rate_ripple", Q::Angle, "arcsec", 0.0);
  d.rate_ripple_period = ini.get_quantity("table.rate_ripple_period", Q::Angle, "deg", 0.0);
  try {
    d.validate();
  } catch (const std::invalid_argument& e) {
    throw ConfigError(path + ": " + e.what());
  }
  return t;
}

std::vector<TableViolation> check_against_table(const Motion& motion, const TableSpec& table,
                                                double margin) {
  std::vector<TableViolation> out;
  const auto& segs = motion.segments();
  // Rates and accelerations within 1e-9 relative of a limit are at the limit.
  const double tol = 1.0 + 1e-9;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    const MotionSegment& s = segs[i];
    char msg[240];
    for (const AngleProfile* p : {&s.alpha, &s.beta}) {
      if (p->angle() == 0.0) continue;
      const double rate = std::abs(p->peak_rate());
      const double accel = std::abs(p->acceleration());
      if (rate > table.max_rate * tol) {
        std::snprintf(msg, sizeof msg, "peak rate %.3f deg/s above the table's %.3f deg/s",
                      rate / units::deg_per_s, table.max_rate / units::deg_per_s);
        out.push_back({static_cast<int>(i) + 1, s.t0, msg});
      }
      if (accel > table.max_acceleration * tol) {
        std::snprintf(msg, sizeof msg,
                      "angular acceleration %.3f deg/s^2 above the table's %.3f deg/s^2",
                      accel / units::deg_per_s, table.max_acceleration / units::deg_per_s);
        out.push_back({static_cast<int>(i) + 1, s.t0, msg});
      }
    }
    if (s.is_static() && i > 0 && s.t1 - s.t0 < table.settling_time + margin) {
      std::snprintf(msg, sizeof msg,
                    "a dwell of %.3f s after a move: shorter than the table's settling time "
                    "%.3f s plus the %.3f s the updates keep from each end",
                    s.t1 - s.t0, table.settling_time, margin);
      out.push_back({static_cast<int>(i) + 1, s.t0, msg});
    }
  }
  return out;
}

}  // namespace sinscal
