// Temperature columns, shared by the formats that have them (custom, split per triad, one file per
// dwell, native): the [log] keys of their unit and raw-count conversion, the checks of each value
// (a sensor's range, with the unit a value out of it more likely has; jumps faster than a sensor
// warms or cools) and of a whole log (a stuck sensor). Bounds and reasons: LogFormat,
// docs/formats.md "Temperature columns".
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "models/config.hpp"
#include "rig/io/log_keys.hpp"

namespace sinscal {

namespace {

constexpr double kKelvinAtZeroCelsius = 273.15;
constexpr TemperatureColumns::Unit kUnits[] = {TemperatureColumns::Unit::Celsius,
                                               TemperatureColumns::Unit::Kelvin,
                                               TemperatureColumns::Unit::Fahrenheit};

bool in_sensor_range(double c) {
  return c >= LogFormat::kMinTemperature && c <= LogFormat::kMaxTemperature;
}

// What a temperature is, in messages: the unit's (one column) or a triad's.
const char* temperature_name(bool one_per_unit, std::size_t k) {
  if (one_per_unit) return "temperature";
  return k == 0 ? "accelerometer temperature" : "gyro temperature";
}

}  // namespace

double TemperatureColumns::to_celsius(double value, Unit unit) {
  switch (unit) {
    case Unit::Kelvin:
      return value - kKelvinAtZeroCelsius;
    case Unit::Fahrenheit:
      return (value - 32.0) * 5.0 / 9.0;
    case Unit::Celsius:
      break;
  }
  return value;
}

const char* TemperatureColumns::symbol(Unit unit) {
  switch (unit) {
    case Unit::Kelvin:
      return "K";
    case Unit::Fahrenheit:
      return "F";
    case Unit::Celsius:
      break;
  }
  return "C";
}

namespace log_keys {

const std::vector<std::string> kTemperatureKeys = {"temperature_unit", "temperature_scale",
                                                   "temperature_offset"};

void read_temperature_keys(const IniFile& ini, bool has_column, const std::string& no_column,
                           LogFormat& f) {
  for (const auto& k : kTemperatureKeys)
    if (!has_column && ini.has("log." + k))
      throw ConfigError(ini.where("log." + k) +
                        "a temperature key without a temperature column: " + no_column);
  TemperatureColumns& c = f.temperature;
  const std::string unit = ini.get_string("log.temperature_unit", "C");
  if (unit == "K") {
    c.unit = TemperatureColumns::Unit::Kelvin;
  } else if (unit == "F") {
    c.unit = TemperatureColumns::Unit::Fahrenheit;
  } else if (unit != "C") {
    throw ConfigError(ini.where("log.temperature_unit") + "expected C, K or F, got '" + unit + "'");
  }
  c.scale = ini.get_double("log.temperature_scale", 1.0);
  if (c.scale == 0.0) throw ConfigError(ini.where("log.temperature_scale") + "must not be zero");
  // One count beyond the whole range of a sensor's temperature is a wrong scale.
  const double per_count =
      std::abs(c.scale) * (c.unit == TemperatureColumns::Unit::Fahrenheit ? 5.0 / 9.0 : 1.0);
  const double span = LogFormat::kMaxTemperature - LogFormat::kMinTemperature;
  if (!(per_count <= span)) {
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  "one count would be %g C, more than the whole range of a sensor's temperature "
                  "(%g ... %g C): a wrong scale",
                  per_count, LogFormat::kMinTemperature, LogFormat::kMaxTemperature);
    throw ConfigError(ini.where("log.temperature_scale") + msg);
  }
  c.offset = ini.get_double("log.temperature_offset", 0.0);
}

}  // namespace log_keys

void TemperatureSummary::add(const ImuSample& s, const std::string& file, std::size_t line) {
  if (!s.has_temperature) return;
  if (samples == 0) {
    t_first = s.t;
    file_first = file;
    line_first = line;
    accel_min_c = accel_max_c = s.accel_temperature_c;
    gyro_min_c = gyro_max_c = s.gyro_temperature_c;
    one_per_unit = true;
  }
  one_per_unit = one_per_unit && s.accel_temperature_c == s.gyro_temperature_c;
  ++samples;
  t_last = s.t;
  if (file_last != file) file_last = file;
  line_last = line;
  accel_min_c = std::min(accel_min_c, s.accel_temperature_c);
  accel_max_c = std::max(accel_max_c, s.accel_temperature_c);
  gyro_min_c = std::min(gyro_min_c, s.gyro_temperature_c);
  gyro_max_c = std::max(gyro_max_c, s.gyro_temperature_c);
}

void check_temperature_not_stuck(const TemperatureSummary& summary, double min_span_s) {
  const double span = summary.t_last - summary.t_first;
  if (summary.samples < 2 || !(span > min_span_s)) return;
  for (std::size_t k = 0; k < 2; ++k) {
    const double lo = k == 0 ? summary.accel_min_c : summary.gyro_min_c;
    const double hi = k == 0 ? summary.accel_max_c : summary.gyro_max_c;
    if (lo != hi) continue;
    char what[200], why[200];
    std::snprintf(what, sizeof what,
                  "the %s reads exactly %s C over the whole log, %.1f min (t = %.3f to %.3f s, "
                  "from ",
                  temperature_name(summary.one_per_unit, k), log_keys::format_number(lo).c_str(),
                  span / 60.0, summary.t_first, summary.t_last);
    std::snprintf(why, sizeof why,
                  "): a stuck sensor (constant over more than %g min); a thermal calibration "
                  "needs the sensor's real temperature",
                  min_span_s / 60.0);
    throw LogError(summary.file_last, summary.line_last,
                   what + summary.file_first + ":" + std::to_string(summary.line_first) + why);
  }
}

void LogReader::read_temperatures(ImuSample& s, double t) {
  s.has_temperature = col_temp_[0] >= 0;
  if (!s.has_temperature) return;
  const TemperatureColumns& c = f_.temperature;
  const Input* const record = loc_;  // restored after a triad's file was named
  // One column for the unit: checked once, both triads read it.
  const bool one = col_temp_[0] == col_temp_[1] && temp_from_[0] == temp_from_[1];
  std::array<double, 2> celsius{};
  for (std::size_t k = 0; k < (one ? 1U : 2U); ++k) {
    const double raw = fields_[static_cast<std::size_t>(col_temp_[k])];
    celsius[k] = c.celsius(raw);
    if (temp_from_[k]) loc_ = temp_from_[k];
    if (!in_sensor_range(celsius[k])) {
      // The unit a value out of range more likely has: kelvin declared as C reads 233 ... 403.
      std::string hint;
      const double value = (raw - c.offset) * c.scale;
      for (const auto u : kUnits) {
        const double alt = TemperatureColumns::to_celsius(value, u);
        if (u != c.unit && in_sensor_range(alt))
          hint += std::string(hint.empty() ? ": " : "; ") + "read as " +
                  TemperatureColumns::symbol(u) + " it would be " +
                  log_keys::format_number(std::round(alt * 100.0) / 100.0) +
                  " C (temperature_unit = " + TemperatureColumns::symbol(u) + "?)";
      }
      // The field as it reads, then in deg C when that differs (another unit, raw counts).
      char in_c[40] = "";
      if (celsius[k] != raw) std::snprintf(in_c, sizeof in_c, " (%.6g C)", celsius[k]);
      char msg[200];
      std::snprintf(msg, sizeof msg, "%s reads %s%s, outside %g ... %g C where sensors work",
                    temperature_name(one, k), log_keys::format_number(raw).c_str(),
                    in_c[0] != 0 ? in_c : " C", LogFormat::kMinTemperature,
                    LogFormat::kMaxTemperature);
      bad_sample(msg + (hint.empty() ? std::string(": a wrong unit, scale or column?") : hint));
    }
    // Against every earlier good sample of the file (TemperatureTrack): an upward jump from the
    // lowest T - r (t - t0), a downward one from the highest T + r (t - t0).
    const TemperatureTrack& h = temp_track_[k];
    if (!h.started) continue;
    const double r = LogFormat::kTemperatureRate, tau = t - h.t0;
    const bool up = (celsius[k] - r * tau) - h.low_key > LogFormat::kTemperatureStep;
    const bool down = h.high_key - (celsius[k] + r * tau) > LogFormat::kTemperatureStep;
    if (!up && !down) continue;
    const double t_ref = up ? h.low_t : h.high_t, c_ref = up ? h.low_c : h.high_c;
    char msg[400];
    std::snprintf(msg, sizeof msg,
                  "%s jumps to %.6g C at t = %.6f s from %.6g C at t = %.6f s (line "
                  "%zu): %.3g C in %.3g s, beyond %g C + %g C/s x the time between them (no sensor "
                  "warms or cools that fast: a glitch, a wrong column or temperature_scale?)",
                  temperature_name(one, k), celsius[k], t, c_ref, t_ref,
                  up ? h.low_line : h.high_line, std::abs(celsius[k] - c_ref), t - t_ref,
                  LogFormat::kTemperatureStep, LogFormat::kTemperatureRate);
    bad_sample(msg);
  }
  loc_ = record;
  s.accel_temperature_c = celsius[0];
  s.gyro_temperature_c = one ? celsius[0] : celsius[1];
}

void LogReader::accept_temperatures(const ImuSample& s) {
  if (!s.has_temperature) return;
  const Input& record = f_.split() ? main_ : *loc_;
  temperature_summary_.add(s, record.name, record.line);
  for (std::size_t k = 0; k < 2; ++k) {
    TemperatureTrack& h = temp_track_[k];
    const double c = k == 0 ? s.accel_temperature_c : s.gyro_temperature_c;
    const std::size_t at = temp_from_[k] ? temp_from_[k]->line : record.line;
    const bool first = !h.started;
    if (first) {
      h.started = true;
      h.t0 = s.t;
    }
    const double tau = s.t - h.t0, r = LogFormat::kTemperatureRate;
    if (first || c - r * tau <= h.low_key) {
      h.low_key = c - r * tau;
      h.low_t = s.t;
      h.low_c = c;
      h.low_line = at;
    }
    if (first || c + r * tau >= h.high_key) {
      h.high_key = c + r * tau;
      h.high_t = s.t;
      h.high_c = c;
      h.high_line = at;
    }
  }
}

}  // namespace sinscal
