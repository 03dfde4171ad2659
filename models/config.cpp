#include "models/config.hpp"

#include <algorithm>
#include <boost/program_options/parsers.hpp>
#include <cmath>
#include <fstream>
#include <sstream>
#include <utility>

#include "models/units.hpp"

namespace sinscal {
namespace {

const std::vector<UnitToken>& units_for(QuantityKind kind) {
  using namespace units;
  static const std::map<QuantityKind, std::vector<UnitToken>> table = {
      {QuantityKind::Angle,
       {{"rad", 1.0}, {"mrad", mrad}, {"deg", deg}, {"arcmin", arcmin}, {"arcsec", arcsec}}},
      {QuantityKind::AngularRate, {{"rad/s", 1.0}, {"deg/s", deg_per_s}, {"deg/h", deg_per_h}}},
      {QuantityKind::AngularAcceleration, {{"rad/s^2", 1.0}, {"deg/s^2", deg}}},
      {QuantityKind::Acceleration, {{"m/s^2", 1.0}, {"ug", ug}, {"mg", mg}, {"g", g0}}},
      {QuantityKind::Length, {{"m", 1.0}, {"cm", cm}, {"mm", mm}}},
      {QuantityKind::Time, {{"s", 1.0}, {"ms", ms}, {"us", us}, {"min", 60.0}, {"h", hour}}},
      {QuantityKind::Frequency, {{"Hz", 1.0}}},
      {QuantityKind::Ratio, {{"1", 1.0}, {"ppm", ppm}}},
      {QuantityKind::AngleRandomWalk, {{"rad/sqrt(s)", 1.0}, {"deg/sqrt(h)", deg_per_sqrt_h}}},
      {QuantityKind::VelocityRandomWalk,
       {{"m/s/sqrt(s)", 1.0}, {"ug/sqrt(Hz)", ug_per_sqrt_hz}, {"m/s/sqrt(h)", 1.0 / 60.0}}},
      {QuantityKind::RateRandomWalk,
       {{"rad/s/sqrt(s)", 1.0}, {"deg/h/sqrt(h)", deg_per_h_per_sqrt_h}}},
      {QuantityKind::AccelRandomWalk, {{"m/s^2/sqrt(s)", 1.0}, {"ug/sqrt(h)", ug_per_sqrt_h}}},
      {QuantityKind::GSensitivity,
       {{"rad/s/(m/s^2)", 1.0}, {"deg/h/g", deg_per_h_per_g}, {"deg/s/g", deg / g0}}},
      {QuantityKind::QuadraticScale, {{"1/(m/s^2)", 1.0}, {"ug/g^2", ug_per_g2}}},
      {QuantityKind::Velocity, {{"m/s", 1.0}, {"mm/s", mm}}},
  };
  return table.at(kind);
}

std::string accepted_units(const std::vector<UnitToken>& units) {
  std::string out;
  for (const auto& u : units) out += (out.empty() ? "" : ", ") + u.token;
  return out;
}

double factor_of(const std::string& unit, const std::vector<UnitToken>& units) {
  for (const auto& u : units)
    if (unit == u.token) return u.si_per_unit;
  throw ConfigError("unit '" + unit +
                    "' is not a unit of this quantity (accepted: " + accepted_units(units) + ")");
}

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

bool parse_number(const std::string& token, double& value) {
  if (token.empty()) return false;
  char* end = nullptr;
  value = std::strtod(token.c_str(), &end);
  return end == token.c_str() + token.size() && std::isfinite(value);
}

}  // namespace

double unit_factor(const std::string& unit, QuantityKind kind) {
  return factor_of(unit, units_for(kind));
}

std::vector<double> parse_quantities(const std::string& text, QuantityKind kind,
                                     const std::string& default_unit) {
  return parse_quantities(text, units_for(kind), default_unit);
}

std::vector<double> parse_quantities(const std::string& text, const std::vector<UnitToken>& units,
                                     const std::string& default_unit) {
  std::istringstream in(text);
  std::vector<std::string> tokens;
  for (std::string t; in >> t;) tokens.push_back(t);
  if (tokens.empty()) throw ConfigError("no value given");
  std::string unit = default_unit;
  double v = 0.0;
  if (!parse_number(tokens.back(), v)) {
    unit = tokens.back();
    tokens.pop_back();
  }
  const double factor = factor_of(unit, units);
  std::vector<double> values;
  for (const auto& t : tokens) {
    if (!parse_number(t, v)) throw ConfigError("'" + t + "' is not a finite number");
    values.push_back(v * factor);
  }
  if (values.empty()) throw ConfigError("no number before the unit '" + unit + "'");
  return values;
}

IniFile::IniFile(const std::string& path) : path_(path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  parse(buffer.str());
}

IniFile::IniFile(const std::string& path, const std::string& text) : path_(path) { parse(text); }

void IniFile::parse(const std::string& text) {
  namespace po = boost::program_options;
  std::istringstream in(text);
  po::options_description none;
  po::parsed_options parsed(&none);
  try {
    parsed = po::parse_config_file(in, none, /*allow_unregistered=*/true);
  } catch (const po::error& e) {
    throw ConfigError(path_ + ": " + e.what());
  }
  for (const auto& opt : parsed.options) {
    const std::string value = opt.value.empty() ? std::string() : trim(opt.value.front());
    if (values_.count(opt.string_key))
      throw ConfigError(path_ + ": key '" + opt.string_key + "' is given twice");
    values_[opt.string_key] = value;
    order_.push_back(opt.string_key);
    const auto dot = opt.string_key.rfind('.');
    const std::string section = dot == std::string::npos ? "" : opt.string_key.substr(0, dot);
    if (std::find(sections_.begin(), sections_.end(), section) == sections_.end())
      sections_.push_back(section);
  }
  // Line numbers for messages: a light scan of the same text (Boost does not report them).
  std::istringstream lines(text);
  std::string line, section;
  for (int n = 1; std::getline(lines, line); ++n) {
    line = trim(line.substr(0, line.find('#')));
    if (line.empty()) continue;
    if (line.front() == '[' && line.back() == ']') {
      section = trim(line.substr(1, line.size() - 2));
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos) continue;
    const std::string key = trim(line.substr(0, eq));
    lines_[section.empty() ? key : section + "." + key] = n;
  }
}

bool IniFile::has(const std::string& key) const { return values_.count(key) != 0; }

std::string IniFile::where(const std::string& key) const {
  const auto l = lines_.find(key);
  std::string out = path_;
  if (l != lines_.end()) out += ":" + std::to_string(l->second);
  return out + ": '" + key + "': ";
}

std::string IniFile::get_string(const std::string& key) const {
  const auto it = values_.find(key);
  if (it == values_.end()) throw ConfigError(path_ + ": missing key '" + key + "'");
  return it->second;
}

std::string IniFile::get_string(const std::string& key, const std::string& fallback) const {
  return has(key) ? get_string(key) : fallback;
}

double IniFile::get_double(const std::string& key) const {
  double v = 0.0;
  const std::string s = get_string(key);
  if (!parse_number(s, v)) throw ConfigError(where(key) + "'" + s + "' is not a finite number");
  return v;
}

double IniFile::get_double(const std::string& key, double fallback) const {
  return has(key) ? get_double(key) : fallback;
}

int IniFile::get_int(const std::string& key, int fallback) const {
  if (!has(key)) return fallback;
  const double v = get_double(key);
  if (v != std::floor(v)) throw ConfigError(where(key) + "expected a whole number");
  return static_cast<int>(v);
}

bool IniFile::get_bool(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const std::string s = get_string(key);
  if (s == "true" || s == "yes" || s == "on" || s == "1") return true;
  if (s == "false" || s == "no" || s == "off" || s == "0") return false;
  throw ConfigError(where(key) + "expected true or false, got '" + s + "'");
}

std::vector<double> IniFile::get_quantities(const std::string& key, QuantityKind kind,
                                            const std::string& default_unit, int count) const {
  return get_quantities(key, units_for(kind), default_unit, count);
}

std::vector<double> IniFile::get_quantities(const std::string& key,
                                            const std::vector<UnitToken>& units,
                                            const std::string& default_unit, int count) const {
  std::vector<double> v;
  try {
    v = parse_quantities(get_string(key), units, default_unit);
  } catch (const ConfigError& e) {
    if (!has(key)) throw;
    throw ConfigError(where(key) + e.what());
  }
  if (count >= 0 && static_cast<int>(v.size()) != count)
    throw ConfigError(where(key) + "expected " + std::to_string(count) + " value(s), got " +
                      std::to_string(v.size()));
  return v;
}

double IniFile::get_quantity(const std::string& key, QuantityKind kind,
                             const std::string& default_unit) const {
  return get_quantities(key, kind, default_unit, 1).front();
}

double IniFile::get_quantity(const std::string& key, QuantityKind kind,
                             const std::string& default_unit, double fallback_si) const {
  return has(key) ? get_quantity(key, kind, default_unit) : fallback_si;
}

std::vector<std::string> IniFile::sections_with_prefix(const std::string& prefix) const {
  std::vector<std::string> out;
  for (const auto& s : sections_)
    if (s.compare(0, prefix.size(), prefix) == 0) out.push_back(s);
  return out;
}

void IniFile::check_keys(const std::string& section,
                         const std::vector<std::string>& allowed) const {
  for (const auto& key : order_) {
    const auto dot = key.rfind('.');
    const std::string sec = dot == std::string::npos ? "" : key.substr(0, dot);
    if (sec != section) continue;
    const std::string name = key.substr(dot == std::string::npos ? 0 : dot + 1);
    if (std::find(allowed.begin(), allowed.end(), name) == allowed.end()) {
      std::string list;
      for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
      throw ConfigError(where(key) + "unknown key in [" + section + "] (known: " + list + ")");
    }
  }
}

}  // namespace sinscal
