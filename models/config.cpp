#include "models/config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
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

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return s.substr(b, e - b + 1);
}

// The whole token read as a number (finite or not: "inf", "nan", "1e999" are numbers here).
bool read_number(const std::string& token, double& value) {
  if (token.empty()) return false;
  char* end = nullptr;
  value = std::strtod(token.c_str(), &end);
  return end == token.c_str() + token.size();
}

bool parse_number(const std::string& token, double& value) {
  return read_number(token, value) && std::isfinite(value);
}

// User text quoted in a message: at most 80 characters, control characters shown as '?'.
std::string shown(const std::string& text) {
  const std::size_t max = 80;
  std::string out = "'";
  for (std::size_t i = 0; i < text.size() && i < max; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    out += c < 0x20 || c == 0x7f ? '?' : text[i];
  }
  return out + (text.size() > max ? "...'" : "'");
}

double factor_of(const std::string& unit, const std::vector<UnitToken>& units) {
  for (const auto& u : units)
    if (unit == u.token) return u.si_per_unit;
  throw ConfigError("unit " + shown(unit) +
                    " is not a unit of this quantity (accepted: " + accepted_units(units) + ")");
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
  if (!read_number(tokens.back(), v)) {
    unit = tokens.back();
    tokens.pop_back();
  }
  const double factor = factor_of(unit, units);
  std::vector<double> values;
  for (const auto& t : tokens) {
    if (!read_number(t, v)) throw ConfigError(shown(t) + " is not a number");
    if (!std::isfinite(v)) throw ConfigError(shown(t) + " is not a finite number");
    const double si = v * factor;
    if (!std::isfinite(si))
      throw ConfigError(shown(t) + " " + unit + " is out of range once converted to SI");
    values.push_back(si);
  }
  if (values.empty()) throw ConfigError("no number before the unit " + shown(unit));
  return values;
}

IniFile::IniFile(const std::string& path) : path_(path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw ConfigError(path + ": is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path + ": cannot open file");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw ConfigError(path + ": read error");
  parse(buffer.str());
}

IniFile::IniFile(const std::string& path, const std::string& text) : path_(path) { parse(text); }

void IniFile::syntax_error(std::size_t line, const std::string& cause) const {
  throw ConfigError(path_ + ":" + std::to_string(line) + ": " + cause);
}

void IniFile::parse(const std::string& text) {
  auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  std::size_t pos = 0;
  if (text.compare(0, 3, "\xEF\xBB\xBF") == 0) pos = 3;  // a UTF-8 byte order mark
  Section* section = nullptr;
  std::string section_name;
  for (std::size_t n = 1; pos < text.size(); ++n) {
    const std::size_t nl = std::min(text.find('\n', pos), text.size());
    // The line without its comment, trimmed: [b, e).
    std::size_t e = pos;
    while (e < nl && text[e] != '#') ++e;
    std::size_t b = pos;
    pos = nl + 1;
    while (b < e && is_space(text[b])) ++b;
    while (e > b && is_space(text[e - 1])) --e;
    if (b == e) continue;
    const std::string line = text.substr(b, e - b);
    if (line.front() == '[') {
      if (line.back() != ']')
        syntax_error(n, "a section header needs a closing ']': " + shown(line));
      section_name = trim(line.substr(1, line.size() - 2));
      if (section_name.empty()) syntax_error(n, "empty section name '[]'");
      if (section_name.find_first_of("[]=") != std::string::npos)
        syntax_error(n, "section name " + shown(section_name) + " contains '[', ']' or '='");
      const auto inserted = sections_.emplace(section_name, Section{});
      if (inserted.second) {
        inserted.first->second.line = n;
        section_names_.push_back(section_name);
      }
      section = &inserted.first->second;
      continue;
    }
    const std::size_t eq = line.find('=');
    if (eq == std::string::npos)
      syntax_error(n, "expected '[section]' or 'key = value', got " + shown(line));
    const std::string name = trim(line.substr(0, eq));
    if (name.empty()) syntax_error(n, "a value without a key: " + shown(line));
    if (section == nullptr) syntax_error(n, "key " + shown(name) + " before the first [section]");
    const std::string key = section_name + "." + name;
    const auto inserted = entries_.emplace(key, Entry{trim(line.substr(eq + 1)), n});
    if (!inserted.second)
      syntax_error(n, "key " + shown(name) + " in [" + section_name +
                          "] is given twice (first at line " +
                          std::to_string(inserted.first->second.line) + ")");
    section->keys.push_back(name);
    order_.push_back(key);
  }
}

bool IniFile::has(const std::string& key) const { return entries_.count(key) != 0; }

std::size_t IniFile::line_of(const std::string& key) const {
  const auto it = entries_.find(key);
  return it == entries_.end() ? 0 : it->second.line;
}

std::string IniFile::where(const std::string& key) const {
  const auto it = entries_.find(key);
  std::string out = path_;
  if (it != entries_.end()) out += ":" + std::to_string(it->second.line);
  return out + ": '" + key + "': ";
}

std::string IniFile::missing(const std::string& key) const {
  // The section is the longest prefix of the key (before a dot) that is a section of the file.
  for (auto dot = key.rfind('.'); dot != std::string::npos && dot > 0;
       dot = key.rfind('.', dot - 1)) {
    const auto s = sections_.find(key.substr(0, dot));
    if (s != sections_.end())
      return path_ + ":" + std::to_string(s->second.line) + ": [" + s->first + "]: missing key '" +
             key.substr(dot + 1) + "'";
  }
  const auto dot = key.find('.');
  return path_ + ": missing key '" + key + "'" +
         (dot == std::string::npos ? std::string()
                                   : " (there is no [" + key.substr(0, dot) + "] section)");
}

std::string IniFile::get_string(const std::string& key) const {
  const auto it = entries_.find(key);
  if (it == entries_.end()) throw ConfigError(missing(key));
  return it->second.value;
}

std::string IniFile::get_string(const std::string& key, const std::string& fallback) const {
  return has(key) ? get_string(key) : fallback;
}

double IniFile::get_double(const std::string& key) const {
  double v = 0.0;
  const std::string s = get_string(key);
  if (!parse_number(s, v)) throw ConfigError(where(key) + shown(s) + " is not a finite number");
  return v;
}

double IniFile::get_double(const std::string& key, double fallback) const {
  return has(key) ? get_double(key) : fallback;
}

int IniFile::get_int(const std::string& key, int fallback, int min_value, int max_value) const {
  if (min_value > max_value)
    throw std::invalid_argument("IniFile::get_int: empty range for '" + key + "'");
  if (!has(key)) return fallback;
  const std::string s = get_string(key);
  double v = 0.0;
  if (!parse_number(s, v)) throw ConfigError(where(key) + shown(s) + " is not a finite number");
  if (v != std::floor(v))
    throw ConfigError(where(key) + "expected a whole number, got " + shown(s));
  // Both bounds are exact in a double: the comparison decides before any conversion.
  if (v < static_cast<double>(min_value) || v > static_cast<double>(max_value)) {
    std::string range;
    if (min_value == INT_MIN && max_value == INT_MAX)
      range = "an int, " + std::to_string(min_value) + " to " + std::to_string(max_value);
    else if (max_value == INT_MAX)
      range = "at least " + std::to_string(min_value);
    else if (min_value == INT_MIN)
      range = "at most " + std::to_string(max_value);
    else
      range = std::to_string(min_value) + " to " + std::to_string(max_value);
    throw ConfigError(where(key) + shown(s) + " is out of range (expected " + range + ")");
  }
  return static_cast<int>(v);
}

bool IniFile::get_bool(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const std::string s = get_string(key);
  if (s == "true" || s == "yes" || s == "on" || s == "1") return true;
  if (s == "false" || s == "no" || s == "off" || s == "0") return false;
  throw ConfigError(where(key) + "expected true or false, got " + shown(s));
}

std::vector<double> IniFile::get_quantities(const std::string& key, QuantityKind kind,
                                            const std::string& default_unit, int count) const {
  return get_quantities(key, units_for(kind), default_unit, count);
}

std::vector<double> IniFile::get_quantities(const std::string& key,
                                            const std::vector<UnitToken>& units,
                                            const std::string& default_unit, int count) const {
  std::vector<double> v;
  const std::string text = get_string(key);
  try {
    v = parse_quantities(text, units, default_unit);
  } catch (const ConfigError& e) {
    throw ConfigError(where(key) + e.what());
  }
  if (count >= 0 && v.size() != static_cast<std::size_t>(count))
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
  for (const auto& s : section_names_)
    if (s.compare(0, prefix.size(), prefix) == 0) out.push_back(s);
  return out;
}

void IniFile::check_keys(const std::string& section,
                         const std::vector<std::string>& allowed) const {
  const auto s = sections_.find(section);
  if (s == sections_.end()) return;
  std::vector<std::string> sorted = allowed;
  std::sort(sorted.begin(), sorted.end());
  for (const auto& name : s->second.keys) {
    if (std::binary_search(sorted.begin(), sorted.end(), name)) continue;
    std::string list;
    for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
    throw ConfigError(where(section + "." + name) + "unknown key in [" + section +
                      "] (known: " + list + ")");
  }
}

}  // namespace sinscal
