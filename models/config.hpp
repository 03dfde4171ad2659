// INI configuration files (plans, sessions, sensor profiles) and quantities with units.
//
// Files are read with Boost.Program_options' config-file parser: `[section]` headers, `key = value`
// lines, `#` comments. Keys are addressed as "section.key". A quantity is written as numbers
// optionally followed by one unit token, e.g. `bias = 0.1 0.3 deg/h`; without a unit the
// documented default unit of the key applies. A unit of the wrong kind is an error.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

namespace sinscal {

/// A configuration problem; what() names the file, the line when known, the key and the cause.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Physical kind of a quantity; decides which unit tokens are accepted.
enum class QuantityKind {
  Angle,                // rad; deg, arcsec, arcmin, mrad, rad
  AngularRate,          // rad/s; deg/h, deg/s, rad/s
  AngularAcceleration,  // rad/s^2; deg/s^2, rad/s^2
  Acceleration,         // m/s^2; ug, mg, g, m/s^2
  Length,               // m; mm, cm, m
  Time,                 // s; s, ms, us, h
  Frequency,            // Hz
  Ratio,                // dimensionless; ppm, 1
  AngleRandomWalk,      // rad/sqrt(s); deg/sqrt(h)
  VelocityRandomWalk,   // m/s/sqrt(s); ug/sqrt(Hz), m/s/sqrt(h)
  RateRandomWalk,       // rad/s/sqrt(s); deg/h/sqrt(h)
  AccelRandomWalk,      // m/s^2/sqrt(s); ug/sqrt(h)
  GSensitivity,         // rad/s/(m/s^2); deg/h/g
  QuadraticScale,       // 1/(m/s^2); ug/g^2
  Velocity,             // m/s; m/s, mm/s
};

/// An engineering unit: value_si = value_in_unit * si_per_unit.
struct UnitToken {
  std::string token;
  double si_per_unit;
};

/// Parses "v1 v2 ... [unit]" into SI values with the units of `units`; `default_unit` (one of
/// them) is used when no unit is written. Throws ConfigError (without location) on a bad number
/// or a unit not in the list.
std::vector<double> parse_quantities(const std::string& text, const std::vector<UnitToken>& units,
                                     const std::string& default_unit);

/// Parses "v1 v2 ... [unit]" into SI values. `default_unit` is used when no unit is written.
/// Throws ConfigError (without location; callers add it) on a bad number or unit.
std::vector<double> parse_quantities(const std::string& text, QuantityKind kind,
                                     const std::string& default_unit);

/// SI factor of a unit token for a kind; throws ConfigError for a unit of another kind.
double unit_factor(const std::string& unit, QuantityKind kind);

/// One INI file, parsed once, keys in file order.
class IniFile {
 public:
  explicit IniFile(const std::string& path);
  /// Parses text already in memory; `path` is only used in messages.
  IniFile(const std::string& path, const std::string& text);

  const std::string& path() const { return path_; }
  bool has(const std::string& key) const;
  std::string get_string(const std::string& key) const;
  std::string get_string(const std::string& key, const std::string& fallback) const;
  double get_double(const std::string& key) const;
  double get_double(const std::string& key, double fallback) const;
  int get_int(const std::string& key, int fallback) const;
  bool get_bool(const std::string& key, bool fallback) const;
  /// Exactly `count` values (count < 0: any number >= 1) in SI.
  std::vector<double> get_quantities(const std::string& key, QuantityKind kind,
                                     const std::string& default_unit, int count = -1) const;
  double get_quantity(const std::string& key, QuantityKind kind,
                      const std::string& default_unit) const;
  /// The same with an explicit list of accepted units.
  std::vector<double> get_quantities(const std::string& key, const std::vector<UnitToken>& units,
                                     const std::string& default_unit, int count = -1) const;
  double get_quantity(const std::string& key, QuantityKind kind, const std::string& default_unit,
                      double fallback_si) const;
  /// Section names in file order that start with `prefix` (e.g. "orientation." gives
  /// "orientation.1", "orientation.2", ...).
  std::vector<std::string> sections_with_prefix(const std::string& prefix) const;
  /// All keys in file order.
  const std::vector<std::string>& keys() const { return order_; }
  /// "file:line: [section] key: " prefix for messages about `key`.
  std::string where(const std::string& key) const;
  /// Throws ConfigError for any key of `section` not in `allowed` (catches typos).
  void check_keys(const std::string& section, const std::vector<std::string>& allowed) const;

 private:
  void parse(const std::string& text);
  std::string path_;
  std::map<std::string, std::string> values_;
  std::map<std::string, int> lines_;
  std::vector<std::string> order_;
  std::vector<std::string> sections_;
};

}  // namespace sinscal
