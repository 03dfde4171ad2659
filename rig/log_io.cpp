#include "rig/log_io.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "models/config.hpp"
#include "models/units.hpp"

namespace sinscal {
namespace {

const char* kNativeHeader =
    "t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],dv_y [m/s],dv_z [m/s]";
const char* kNativeTableColumns = ",outer [deg],inner [deg]";

std::string format_number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest exact round trip
  return std::string(buf, r.ptr);
}

std::string join_path(const std::string& base, const std::string& file) {
  if (file.empty() || file.front() == '/' || base.empty()) return file;
  return base + "/" + file;
}

TriadColumns read_triad(const IniFile& ini, const std::string& name, bool gyro) {
  TriadColumns c;
  const std::string p = "log." + name;
  const std::string kind = ini.get_string(p, "increment");
  if (kind != "increment" && kind != "rate")
    throw ConfigError(ini.where(p) + "expected 'increment' or 'rate', got '" + kind + "'");
  c.increments = kind == "increment";
  QuantityKind q;
  std::string dflt;
  if (gyro) {
    q = c.increments ? QuantityKind::Angle : QuantityKind::AngularRate;
    dflt = c.increments ? "rad" : "rad/s";
  } else {
    q = c.increments ? QuantityKind::Velocity : QuantityKind::Acceleration;
    dflt = c.increments ? "m/s" : "m/s^2";
  }
  const std::string unit = ini.get_string(p + "_unit", dflt);
  try {
    c.scale = unit_factor(unit, q);
  } catch (const ConfigError& e) {
    throw ConfigError(ini.where(p + "_unit") + e.what());
  }
  c.scale *= ini.get_double(p + "_scale", 1.0);
  c.offset = ini.get_double(p + "_offset", 0.0);
  c.saturation = ini.get_double(p + "_saturation", 0.0);
  if (ini.has(p + "_axes")) {
    std::istringstream in(ini.get_string(p + "_axes"));
    std::array<bool, 3> used{false, false, false};
    for (int i = 0; i < 3; ++i) {
      std::string a;
      if (!(in >> a))
        throw ConfigError(ini.where(p + "_axes") + "expected three axes like 'x -z y'");
      double sign = 1.0;
      if (a.size() == 2 && (a[0] == '-' || a[0] == '+')) {
        sign = a[0] == '-' ? -1.0 : 1.0;
        a = a.substr(1);
      }
      if (a.size() != 1 || a[0] < 'x' || a[0] > 'z' || used[a[0] - 'x'])
        throw ConfigError(ini.where(p + "_axes") + "expected a permutation of x y z with signs");
      used[a[0] - 'x'] = true;
      c.axis[i] = a[0] - 'x';
      c.sign[i] = sign;
    }
  }
  return c;
}

}  // namespace

LogError::LogError(const std::string& file, std::size_t line, const std::string& cause)
    : std::runtime_error(file + ":" + std::to_string(line) + ": " + cause),
      file_(file),
      line_(line),
      cause_(cause) {}

LogFormat LogFormat::native_format(const std::string& file, double rate_hz) {
  LogFormat f;
  f.file = file;
  f.native = true;
  f.header_lines = 0;
  f.columns = {"t", "gx", "gy", "gz", "ax", "ay", "az"};
  f.rate_hz = rate_hz;
  return f;
}

LogFormat LogFormat::from_ini(const IniFile& ini, const std::string& base_dir, double rate_hz) {
  const std::string file = join_path(base_dir, ini.get_string("log.file"));
  const std::string format = ini.get_string("log.format", "sinscal");
  if (format == "sinscal") {
    ini.check_keys("log", {"file", "format", "max_gap"});  // table angles: from the header
    LogFormat f = native_format(file, rate_hz);
    f.max_gap = ini.get_double("log.max_gap", f.max_gap);
    return f;
  }
  if (format != "custom")
    throw ConfigError(ini.where("log.format") + "expected 'sinscal' or 'custom', got '" + format +
                      "'");
  ini.check_keys("log", {"file",
                         "format",
                         "delimiter",
                         "header_lines",
                         "columns",
                         "time_unit",
                         "max_gap",
                         "gyro",
                         "gyro_unit",
                         "gyro_scale",
                         "gyro_offset",
                         "gyro_axes",
                         "gyro_saturation",
                         "accel",
                         "accel_unit",
                         "accel_scale",
                         "accel_offset",
                         "accel_axes",
                         "accel_saturation",
                         "table_unit"});
  LogFormat f;
  f.file = file;
  f.native = false;
  f.rate_hz = rate_hz;
  const std::string d = ini.get_string("log.delimiter", "comma");
  if (d == "comma")
    f.delimiter = ',';
  else if (d == "semicolon")
    f.delimiter = ';';
  else if (d == "tab")
    f.delimiter = '\t';
  else if (d == "whitespace")
    f.delimiter = ' ';
  else
    throw ConfigError(ini.where("log.delimiter") + "expected comma, semicolon, tab or whitespace");
  f.header_lines = ini.get_int("log.header_lines", 0);
  std::istringstream cols(ini.get_string("log.columns"));
  for (std::string c; cols >> c;) {
    static const std::vector<std::string> known = {"t",  "gx", "gy",    "gz",    "ax",
                                                   "ay", "az", "outer", "inner", "-"};
    if (std::find(known.begin(), known.end(), c) == known.end())
      throw ConfigError(ini.where("log.columns") + "unknown column '" + c +
                        "' (known: t gx gy gz ax ay az outer inner, - to skip)");
    if (c != "-" && std::count(f.columns.begin(), f.columns.end(), c))
      throw ConfigError(ini.where("log.columns") + "column '" + c + "' given twice");
    f.columns.push_back(c);
  }
  f.time_scale = unit_factor(ini.get_string("log.time_unit", "s"), QuantityKind::Time);
  const bool outer = std::count(f.columns.begin(), f.columns.end(), "outer") > 0;
  if (outer != (std::count(f.columns.begin(), f.columns.end(), "inner") > 0))
    throw ConfigError(ini.where("log.columns") + "give both table-angle columns, outer and inner");
  if (outer)
    f.table_scale = unit_factor(ini.get_string("log.table_unit", "deg"), QuantityKind::Angle);
  f.max_gap = ini.get_double("log.max_gap", f.max_gap);
  f.gyro = read_triad(ini, "gyro", true);
  f.accel = read_triad(ini, "accel", false);
  return f;
}

LogWriter::LogWriter(const std::string& path, double rate_hz, bool table_angles)
    : path_(path), out_(path), table_(table_angles) {
  if (!out_) throw std::runtime_error(path + ": cannot create log file");
  out_ << "# sinscal IMU log, format 1: increments over (t - dt, t], body axes\n"
       << "# rate_hz = " << format_number(rate_hz) << "\n"
       << kNativeHeader << (table_ ? kNativeTableColumns : "") << "\n";
  buffer_.reserve(1 << 16);
}

void LogWriter::write(const ImuSample& s) {
  buffer_ += format_number(s.t);
  for (int i = 0; i < 3; ++i) (buffer_ += ',') += format_number(s.dtheta_b(i));
  for (int i = 0; i < 3; ++i) (buffer_ += ',') += format_number(s.dv_b(i));
  if (table_) {
    if (!s.has_table)
      throw std::invalid_argument(path_ + ": a sample without the table angles the log declares");
    (buffer_ += ',') += format_number(s.table_outer / units::deg);
    (buffer_ += ',') += format_number(s.table_inner / units::deg);
  }
  buffer_ += '\n';
  if (buffer_.size() > (1 << 16) - 256) {
    out_ << buffer_;
    buffer_.clear();
  }
}

void LogWriter::close() {
  out_ << buffer_;
  buffer_.clear();
  out_.close();
  if (!out_) throw std::runtime_error(path_ + ": write failed (disk full?)");
}

LogReader::LogReader(const LogFormat& format)
    : f_(format), file_(std::make_unique<std::ifstream>(format.file)), in_(file_.get()) {
  if (!*in_) throw LogError(f_.file, 0, "cannot open log file");
  start();
}

LogReader::LogReader(std::istream& in, const LogFormat& format) : f_(format), in_(&in) { start(); }

void LogReader::start() {
  if (!(f_.rate_hz > 0.0)) throw LogError(f_.file, 0, "the nominal sample rate is not set");
  for (int i = 0; i < static_cast<int>(f_.columns.size()); ++i) {
    const std::string& c = f_.columns[i];
    if (c == "t") col_t_ = i;
    if (c.size() == 2 && c[0] == 'g') col_g_[c[1] - 'x'] = i;
    if (c.size() == 2 && c[0] == 'a') col_a_[c[1] - 'x'] = i;
    if (c == "outer") col_outer_ = i;
    if (c == "inner") col_inner_ = i;
  }
  for (int i = 0; i < 3; ++i)
    if (col_g_[i] < 0 || col_a_[i] < 0)
      throw LogError(f_.file, 0, "the log format must name columns gx gy gz ax ay az");
  std::string line;
  bool nl = true;
  for (int i = 0; i < f_.header_lines; ++i)
    if (!read_line(line, nl))
      fail("file ends inside the " + std::to_string(f_.header_lines) + " header lines");
  if (f_.native) {
    do {
      if (!read_line(line, nl)) fail("file ends before the column header");
    } while (!line.empty() && line[0] == '#');
    if (line == std::string(kNativeHeader) + kNativeTableColumns) {
      f_.columns.push_back("outer");
      f_.columns.push_back("inner");
      col_outer_ = static_cast<int>(f_.columns.size()) - 2;
      col_inner_ = col_outer_ + 1;
      f_.table_scale = units::deg;
    } else if (line != kNativeHeader) {
      fail("not a sinscal log: expected the column header '" + std::string(kNativeHeader) +
           "' (optionally followed by '" + kNativeTableColumns + "')");
    }
  }
}

void LogReader::fail(const std::string& cause) const { throw LogError(f_.file, line_, cause); }

void LogReader::bad_sample(const std::string& cause) const {
  BadSampleError e(f_.file, line_, cause);
  e.t_prev = t_prev_;
  throw e;
}

bool LogReader::read_line(std::string& line, bool& had_newline) {
  if (!std::getline(*in_, line)) {
    if (in_->bad()) fail("read error");
    return false;
  }
  ++line_;
  had_newline = !in_->eof();
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return true;
}

bool LogReader::next(ImuSample& s) {
  std::string line;
  bool had_newline = true;
  for (;;) {
    do {
      if (!read_line(line, had_newline)) return false;
    } while (line.empty() || line[0] == '#');
    try {
      return parse(line, had_newline, s);
    } catch (const BadSampleError& e) {
      if (!on_skip_) throw;
      on_skip_(e);
      skipped_ = true;
      ++skipped_count_;
      ++skipped_run_;
    }
  }
}

bool LogReader::parse(const std::string& line, bool had_newline, ImuSample& s) {
  // Split and parse.
  fields_.clear();
  const std::size_t expected = f_.columns.size();
  std::size_t pos = 0;
  const bool ws = f_.delimiter == ' ';
  while (pos <= line.size()) {
    if (ws) {
      pos = line.find_first_not_of(" \t", pos);
      if (pos == std::string::npos) break;
    }
    std::size_t end = ws ? line.find_first_of(" \t", pos) : line.find(f_.delimiter, pos);
    if (end == std::string::npos) end = line.size();
    std::size_t b = pos, e = end;
    while (b < e && (line[b] == ' ' || line[b] == '\t')) ++b;
    while (e > b && (line[e - 1] == ' ' || line[e - 1] == '\t')) --e;
    if (b < e && line[b] == '+') ++b;
    double v = 0.0;
    const auto r = std::from_chars(line.data() + b, line.data() + e, v);
    const std::string text = line.substr(pos, end - pos);
    const std::string which = "field " + std::to_string(fields_.size() + 1);
    if (r.ec == std::errc() && r.ptr == line.data() + e && !std::isfinite(v))
      bad_sample(which + " is " + (std::isnan(v) ? "NaN" : "infinite"));
    if (b == e || r.ec != std::errc() || r.ptr != line.data() + e) {
      if (!had_newline && fields_.size() + 1 < expected)
        fail("truncated line: the file ends in the middle of a sample");
      bad_sample(which + " '" + text + "' is not a number");
    }
    fields_.push_back(v);
    pos = end + 1;
  }
  if (fields_.size() != expected) {
    if (!had_newline && fields_.size() < expected)
      fail("truncated line: the file ends in the middle of a sample (" +
           std::to_string(fields_.size()) + " of " + std::to_string(expected) + " fields)");
    fail("expected " + std::to_string(expected) + " fields, found " +
         std::to_string(fields_.size()));
  }

  // Time.
  const double nominal_dt = 1.0 / f_.rate_hz;
  const double t = col_t_ >= 0 ? fields_[col_t_] * f_.time_scale
                               : static_cast<double>(count_ + skipped_count_ + 1) * nominal_dt;
  double dt = nominal_dt;
  if (count_ > 0) {
    dt = t - t_prev_;
    char msg[200];
    if (dt <= 0.0) {
      std::snprintf(msg, sizeof msg, "time goes backwards: t = %.6f s after %.6f s", t, t_prev_);
      bad_sample(dt == 0.0 ? "time repeats: t = " + format_number(t) + " s twice" : msg);
    }
    // Skipped samples leave their intervals to the next good one (bridged, see skip_bad_samples).
    if (dt > (f_.max_gap + static_cast<double>(skipped_run_)) * nominal_dt) {
      std::snprintf(msg, sizeof msg,
                    "gap in the data: %.6f s from t = %.6f s to %.6f s (about %.0f samples missing "
                    "at %g Hz)",
                    dt, t_prev_, t, dt / nominal_dt - 1.0, f_.rate_hz);
      fail(msg);
    }
    if (dt < 0.5 * nominal_dt) {
      std::snprintf(msg, sizeof msg,
                    "samples %.6f s apart at t = %.6f s, less than half the nominal interval of "
                    "%g Hz: wrong rate in the session or duplicated samples",
                    dt, t, f_.rate_hz);
      fail(msg);
    }
  }

  // Sensors: raw -> SI -> body axes -> increments.
  auto triad = [&](const TriadColumns& c, const std::array<int, 3>& col, const char* name) {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i) {
      const double raw = fields_[col[c.axis[i]]];
      if (c.saturation > 0.0 && std::abs(raw) >= c.saturation)
        bad_sample(std::string("saturated sample: ") + name + " log axis " + char('x' + c.axis[i]) +
                   " reads " + format_number(raw) + " (limit " + format_number(c.saturation) + ")");
      v(i) = c.sign[i] * (raw - c.offset) * c.scale;
    }
    // After a skipped sample, hold this sample's rate over the whole interval since the last
    // good one (increments cover one nominal interval only).
    if (c.increments && skipped_) return Eigen::Vector3d(v * (dt / nominal_dt));
    return c.increments ? v : Eigen::Vector3d(v * dt);
  };
  s.dtheta_b = triad(f_.gyro, col_g_, "gyro");
  s.dv_b = triad(f_.accel, col_a_, "accel");
  s.has_table = col_outer_ >= 0;
  if (s.has_table) {
    s.table_outer = fields_[col_outer_] * f_.table_scale;
    s.table_inner = fields_[col_inner_] * f_.table_scale;
  }
  s.t = t;
  s.dt = dt;
  t_prev_ = t;
  ++count_;
  skipped_ = false;
  skipped_run_ = 0;
  return true;
}

}  // namespace sinscal
