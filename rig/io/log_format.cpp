// The session's [log] section read into a LogFormat: the keys every format shares (units, scales,
// axes of a triad, delimiter, header lines, gaps) and the choice of format; each format's own keys
// are read in its file (native.cpp, custom_csv.cpp, split_files.cpp, novatel.cpp, dwell_files.cpp).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "models/config.hpp"
#include "rig/io/log_keys.hpp"

namespace sinscal {

LogError::LogError(const std::string& file, std::size_t line, const std::string& cause)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + cause),
      file_(file),
      line_(line),
      cause_(cause) {}

namespace {

void check_nonzero(const IniFile& ini, const std::string& key, double v) {
  if (v == 0.0) throw ConfigError(ini.where(key) + "must not be zero");
}

}  // namespace

namespace log_keys {

std::vector<std::string> tokens_of(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string t; in >> t;) out.push_back(t);
  return out;
}

double unit_of(const IniFile& ini, const std::string& key, const std::string& dflt,
               QuantityKind kind) {
  try {
    return unit_factor(ini.get_string(key, dflt), kind);
  } catch (const ConfigError& e) {
    throw ConfigError(ini.where(key) + e.what());
  }
}

TriadColumns read_triad(const IniFile& ini, const std::string& name, bool gyro, double rate_hz,
                        bool fixed_increments) {
  TriadColumns c;
  const std::string p = "log." + name;
  if (!fixed_increments) {
    const std::string kind = ini.get_string(p, "increment");
    if (kind != "increment" && kind != "rate")
      throw ConfigError(ini.where(p) + "expected 'increment' or 'rate', got '" + kind + "'");
    c.increments = kind == "increment";
  }
  QuantityKind q;
  std::string dflt;
  if (gyro) {
    q = c.increments ? QuantityKind::Angle : QuantityKind::AngularRate;
    dflt = c.increments ? "rad" : "rad/s";
  } else {
    q = c.increments ? QuantityKind::Velocity : QuantityKind::Acceleration;
    dflt = c.increments ? "m/s" : "m/s^2";
  }
  c.scale = unit_of(ini, p + "_unit", dflt, q);
  const double scale = ini.get_double(p + "_scale", 1.0);
  check_nonzero(ini, p + "_scale", scale);
  c.scale *= scale;
  // One count beyond any sensor (LogFormat::kMaxRate, kMaxSpecificForce) is a wrong scale.
  const double limit = gyro ? LogFormat::kMaxRate : LogFormat::kMaxSpecificForce;
  const double per_count = std::abs(c.scale) * (c.increments ? rate_hz : 1.0);
  if (!(per_count <= limit)) {
    char msg[200];
    std::snprintf(msg, sizeof msg,
                  "one count would be %g %s, beyond any sensor (limit %g %s): a wrong scale or "
                  "unit",
                  per_count, gyro ? "rad/s" : "m/s^2", limit, gyro ? "rad/s" : "m/s^2");
    throw ConfigError(ini.where(ini.has(p + "_scale") ? p + "_scale" : p + "_unit") + msg);
  }
  c.offset = ini.get_double(p + "_offset", 0.0);
  c.counts = ini.has(p + "_scale") || ini.has(p + "_offset");
  c.saturation = ini.get_double(p + "_saturation", 0.0);
  if (c.saturation < 0.0) throw ConfigError(ini.where(p + "_saturation") + "must not be negative");
  if (ini.has(p + "_axes")) {
    const auto axes = tokens_of(ini.get_string(p + "_axes"));
    if (axes.size() != 3)
      throw ConfigError(ini.where(p + "_axes") + "expected three axes like 'x -z y', got " +
                        std::to_string(axes.size()));
    std::array<bool, 3> used{false, false, false};
    for (int i = 0; i < 3; ++i) {
      std::string a = axes[static_cast<std::size_t>(i)];
      double sign = 1.0;
      if (a.size() == 2 && (a[0] == '-' || a[0] == '+')) {
        sign = a[0] == '-' ? -1.0 : 1.0;
        a = a.substr(1);
      }
      if (a.size() != 1 || a[0] < 'x' || a[0] > 'z' || used[static_cast<std::size_t>(a[0] - 'x')])
        throw ConfigError(ini.where(p + "_axes") + "expected a permutation of x y z with signs");
      used[static_cast<std::size_t>(a[0] - 'x')] = true;
      c.axis[static_cast<std::size_t>(i)] = a[0] - 'x';
      c.sign[static_cast<std::size_t>(i)] = sign;
    }
  }
  return c;
}

// [log] header_lines: a whole number within 0 ... kMaxHeaderLines.
int read_header_lines(const IniFile& ini) {
  return ini.get_int("log.header_lines", 0, 0, LogFormat::kMaxHeaderLines);
}

char read_delimiter(const IniFile& ini) {
  const std::string d = ini.get_string("log.delimiter", "comma");
  if (d == "comma") return ',';
  if (d == "semicolon") return ';';
  if (d == "tab") return '\t';
  if (d == "whitespace") return ' ';
  throw ConfigError(ini.where("log.delimiter") + "expected comma, semicolon, tab or whitespace");
}

double read_max_gap(const IniFile& ini, double dflt) {
  const double g = ini.get_double("log.max_gap", dflt);
  if (!(g >= 1.0 && g <= LogFormat::kMaxGap))
    throw ConfigError(ini.where("log.max_gap") + "must be from 1 to 1000 (samples)");
  return g;
}

std::string describe_files(const std::vector<std::string>& files) {
  std::string out;
  for (const auto& f : files) out += (out.empty() ? "" : " + ") + f;
  return out;
}

}  // namespace log_keys

LogFormat LogFormat::from_ini(const IniFile& ini, const std::string& base_dir, double rate_hz) {
  const std::string format = ini.get_string("log.format", "sinscal");
  const bool segmented = ini.has("log.files");
  std::vector<std::string> keys = {"format", "max_gap"};
  if (segmented) {
    keys.insert(keys.end(), {"files", "dwells"});
    if (ini.has("log.file"))
      throw ConfigError(ini.where("log.file") +
                        "give either 'file' (one log) or 'files' (one file per dwell), not both");
  } else {
    keys.push_back("file");
  }
  LogFormat f;
  if (format == "sinscal") {
    ini.check_keys("log", keys);  // table angles: from the header
    f = native_format(segmented ? std::string() : path_in(base_dir, ini.get_string("log.file")),
                      rate_hz);
  } else if (format == "custom") {
    log_keys::read_custom_format(ini, base_dir, rate_hz, segmented, keys, f);
  } else if (format == "novatel") {
    log_keys::read_novatel_format(ini, base_dir, rate_hz, segmented, keys, f);
  } else {
    throw ConfigError(ini.where("log.format") + "expected 'sinscal', 'custom' or 'novatel', got '" +
                      format + "'");
  }
  f.rate_hz = rate_hz;
  f.max_gap = log_keys::read_max_gap(ini, f.max_gap);
  if (segmented) {
    f.segments = log_keys::read_segments(ini, base_dir);
    std::vector<std::string> names;
    for (const auto& s : f.segments) names.push_back(s.file);
    f.file = log_keys::describe_files(names);
  }
  return f;
}

std::string path_in(const std::string& dir, const std::string& file) {
  const std::filesystem::path p(file);
  if (file.empty() || dir.empty() || p.is_absolute()) return file;
  return (std::filesystem::path(dir) / p).string();
}

}  // namespace sinscal
