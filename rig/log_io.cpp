#include "rig/log_io.hpp"

#include <algorithm>
#include <boost/crc.hpp>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "models/config.hpp"
#include "models/units.hpp"
#include "rig/plan.hpp"

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

// NovAtel's 32-bit CRC of ASCII logs: polynomial 0x04C11DB7 reflected (0xEDB88320), initial value
// 0, no final XOR, over the text between the '%' or '#' and the '*'.
std::uint32_t novatel_crc32(const char* data, std::size_t size) {
  boost::crc_optimal<32, 0x04C11DB7, 0, 0, true, true> crc;
  crc.process_bytes(data, size);
  return crc.checksum();
}

std::vector<std::string> tokens_of(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string t; in >> t;) out.push_back(t);
  return out;
}

void check_nonzero(const IniFile& ini, const std::string& key, double v) {
  if (v == 0.0) throw ConfigError(ini.where(key) + "must not be zero");
}

// The SI factor of a unit key; a unit of the wrong kind is an error naming the line.
double unit_of(const IniFile& ini, const std::string& key, const std::string& dflt,
               QuantityKind kind) {
  try {
    return unit_factor(ini.get_string(key, dflt), kind);
  } catch (const ConfigError& e) {
    throw ConfigError(ini.where(key) + e.what());
  }
}

// `rate_hz`: the nominal rate, which turns one count of an increment into a rate for the
// plausibility check of the scale.
TriadColumns read_triad(const IniFile& ini, const std::string& name, bool gyro, double rate_hz,
                        bool fixed_increments = false) {
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

// Columns of one file of a split log: t x y z or - (skip), x y z required.
std::vector<std::string> read_split_columns(const IniFile& ini, const std::string& key) {
  if (!ini.has(key)) return {"t", "x", "y", "z"};
  std::vector<std::string> cols;
  for (const auto& c : tokens_of(ini.get_string(key))) {
    if (c != "t" && c != "x" && c != "y" && c != "z" && c != "-")
      throw ConfigError(ini.where(key) + "unknown column '" + c + "' (known: t x y z, - to skip)");
    if (c != "-" && std::count(cols.begin(), cols.end(), c))
      throw ConfigError(ini.where(key) + "column '" + c + "' given twice");
    cols.push_back(c);
  }
  for (const char* axis : {"x", "y", "z"})
    if (!std::count(cols.begin(), cols.end(), axis))
      throw ConfigError(ini.where(key) + "column '" + axis + "' missing (need x y z, t optional)");
  return cols;
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

// The files of a log recorded as one file per dwell: `files` (and `dwells`) of [log], placed in
// the dwells of the session's plan.
std::vector<LogSegment> read_segments(const IniFile& ini, const std::string& base_dir) {
  const auto files = tokens_of(ini.get_string("log.files"));
  if (files.empty()) throw ConfigError(ini.where("log.files") + "no files given");
  std::vector<int> dwells;
  if (ini.has("log.dwells")) {
    for (const auto& d : tokens_of(ini.get_string("log.dwells"))) {
      int v = 0;
      const auto r = std::from_chars(d.data(), d.data() + d.size(), v);
      if (r.ec != std::errc() || r.ptr != d.data() + d.size() || v < 1)
        throw ConfigError(ini.where("log.dwells") + "'" + d +
                          "' is not a dwell number (1, 2, ...)");
      dwells.push_back(v);
    }
    if (dwells.size() != files.size())
      throw ConfigError(ini.where("log.dwells") + std::to_string(dwells.size()) + " dwells for " +
                        std::to_string(files.size()) + " files: give one dwell per file");
  } else {
    for (std::size_t i = 0; i < files.size(); ++i) dwells.push_back(static_cast<int>(i) + 1);
  }
  if (!ini.has("session.plan"))
    throw ConfigError(ini.where("log.files") +
                      "a log in one file per dwell needs the session's plan ([session] plan) "
                      "for the dwells' times");
  const Plan plan = Plan::load(path_in(base_dir, ini.get_string("session.plan")));
  const double offset = ini.get_quantity("session.time_offset", QuantityKind::Time, "s", 0.0);
  const Motion motion = build_motion(plan, Site{});
  const auto& plan_dwells = motion.dwells();
  std::vector<LogSegment> out;
  for (std::size_t i = 0; i < files.size(); ++i) {
    LogSegment seg;
    seg.file = path_in(base_dir, files[i]);
    seg.dwell = dwells[i];
    std::error_code ec;  // a name the system refuses (too long, ...) reads as "no such file"
    if (!std::filesystem::is_regular_file(seg.file, ec))
      throw ConfigError(ini.where("log.files") + "'" + files[i] + "': no such file (" + seg.file +
                        ")");
    if (seg.dwell > static_cast<int>(plan_dwells.size()))
      throw ConfigError(ini.where(ini.has("log.dwells") ? "log.dwells" : "log.files") + "'" +
                        files[i] + "' is assigned to dwell " + std::to_string(seg.dwell) +
                        " but the plan " + plan.path + " has " +
                        std::to_string(plan_dwells.size()) + " dwells");
    for (const auto& other : out)
      if (other.dwell == seg.dwell)
        throw ConfigError(ini.where(ini.has("log.dwells") ? "log.dwells" : "log.files") + "'" +
                          files[i] + "' and '" + other.file + "' are both assigned to dwell " +
                          std::to_string(seg.dwell) + ": their times would overlap");
    const Dwell& d = plan_dwells[static_cast<std::size_t>(seg.dwell - 1)];
    seg.t_start = offset + d.t_start;
    seg.t_end = offset + d.t_end;
    out.push_back(seg);
  }
  std::sort(out.begin(), out.end(),
            [](const LogSegment& a, const LogSegment& b) { return a.dwell < b.dwell; });
  return out;
}

std::string describe_files(const std::vector<std::string>& files) {
  std::string out;
  for (const auto& f : files) out += (out.empty() ? "" : " + ") + f;
  return out;
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
  auto add = [&](std::initializer_list<const char*> more) {
    for (const char* k : more) keys.emplace_back(k);
  };
  LogFormat f;
  if (format == "sinscal") {
    ini.check_keys("log", keys);  // table angles: from the header
    f = native_format(segmented ? std::string() : path_in(base_dir, ini.get_string("log.file")),
                      rate_hz);
  } else if (format == "custom") {
    const bool split = ini.has("log.accel_file") || ini.has("log.gyro_file");
    add({"delimiter", "header_lines", "time_unit", "gyro", "gyro_unit", "gyro_scale", "gyro_offset",
         "gyro_axes", "gyro_saturation", "accel", "accel_unit", "accel_scale", "accel_offset",
         "accel_axes", "accel_saturation"});
    if (split) {
      if (segmented)
        throw ConfigError(ini.where("log.files") +
                          "a log in one file per dwell cannot also be split per triad "
                          "(accel_file, gyro_file)");
      if (ini.has("log.file") || ini.has("log.columns"))
        throw ConfigError(ini.where(ini.has("log.file") ? "log.file" : "log.columns") +
                          "a split log names its files as accel_file and gyro_file and their "
                          "columns as accel_columns and gyro_columns");
      keys.erase(std::remove(keys.begin(), keys.end(), "file"), keys.end());
      add({"accel_file", "gyro_file", "accel_columns", "gyro_columns", "time_tolerance"});
    } else {
      add({"columns", "table_unit"});
    }
    ini.check_keys("log", keys);
    f.native = false;
    f.delimiter = read_delimiter(ini);
    f.header_lines = read_header_lines(ini);
    f.time_scale = unit_of(ini, "log.time_unit", "s", QuantityKind::Time);
    if (split) {
      f.accel_file = path_in(base_dir, ini.get_string("log.accel_file"));
      f.gyro_file = path_in(base_dir, ini.get_string("log.gyro_file"));
      f.file = describe_files({f.accel_file, f.gyro_file});
      f.accel_columns = read_split_columns(ini, "log.accel_columns");
      f.gyro_columns = read_split_columns(ini, "log.gyro_columns");
      f.time_tolerance = ini.get_quantity("log.time_tolerance", QuantityKind::Time, "s", 0.0);
      if (!(f.time_tolerance >= 0.0))
        throw ConfigError(ini.where("log.time_tolerance") + "must not be negative");
      const bool t = std::count(f.accel_columns.begin(), f.accel_columns.end(), "t") ||
                     std::count(f.gyro_columns.begin(), f.gyro_columns.end(), "t");
      f.columns = {"gx", "gy", "gz", "ax", "ay", "az"};
      if (t) f.columns.insert(f.columns.begin(), "t");
    } else {
      if (!segmented) f.file = path_in(base_dir, ini.get_string("log.file"));
      for (const auto& c : tokens_of(ini.get_string("log.columns"))) {
        static const std::vector<std::string> known = {"t",  "gx", "gy",    "gz",    "ax",
                                                       "ay", "az", "outer", "inner", "-"};
        if (std::find(known.begin(), known.end(), c) == known.end())
          throw ConfigError(ini.where("log.columns") + "unknown column '" + c +
                            "' (known: t gx gy gz ax ay az outer inner, - to skip)");
        if (c != "-" && std::count(f.columns.begin(), f.columns.end(), c))
          throw ConfigError(ini.where("log.columns") + "column '" + c + "' given twice");
        f.columns.push_back(c);
      }
      const bool outer = std::count(f.columns.begin(), f.columns.end(), "outer") > 0;
      if (outer != (std::count(f.columns.begin(), f.columns.end(), "inner") > 0))
        throw ConfigError(ini.where("log.columns") +
                          "give both table-angle columns, outer and inner");
      if (outer) f.table_scale = unit_of(ini, "log.table_unit", "deg", QuantityKind::Angle);
    }
    f.gyro = read_triad(ini, "gyro", true, rate_hz);
    f.accel = read_triad(ini, "accel", false, rate_hz);
    for (const char* c : {"gx", "gy", "gz", "ax", "ay", "az"})
      if (!split && !std::count(f.columns.begin(), f.columns.end(), c))
        throw ConfigError(ini.where("log.columns") + "column '" + c +
                          "' missing (the columns must name gx gy gz ax ay az)");
  } else if (format == "novatel") {
    add({"gyro_unit", "gyro_scale", "gyro_axes", "gyro_saturation", "accel_unit", "accel_scale",
         "accel_axes", "accel_saturation", "status_mask"});
    ini.check_keys("log", keys);
    f.kind = Kind::NovAtel;
    f.native = false;
    f.header_lines = 0;
    if (!segmented) f.file = path_in(base_dir, ini.get_string("log.file"));
    for (const char* k : {"log.gyro_scale", "log.accel_scale"})
      if (!ini.has(k))
        throw ConfigError(ini.path() + ": [log] format = novatel: missing '" +
                          std::string(k).substr(4) +
                          "', the increment per count of the IMU inside (the receiver's raw "
                          "IMU scale factors table)");
    f.gyro = read_triad(ini, "gyro", true, rate_hz, true);
    f.accel = read_triad(ini, "accel", false, rate_hz, true);
    if (ini.has("log.status_mask")) {
      std::string m = ini.get_string("log.status_mask");
      if (m.size() > 2 && m[0] == '0' && (m[1] == 'x' || m[1] == 'X')) m = m.substr(2);
      const auto r = std::from_chars(m.data(), m.data() + m.size(), f.status_mask, 16);
      if (m.empty() || r.ec != std::errc() || r.ptr != m.data() + m.size())
        throw ConfigError(ini.where("log.status_mask") +
                          "expected a hexadecimal 32-bit mask like 0x00000004");
    }
    f.columns = {"t", "gx", "gy", "gz", "ax", "ay", "az"};
  } else {
    throw ConfigError(ini.where("log.format") + "expected 'sinscal', 'custom' or 'novatel', got '" +
                      format + "'");
  }
  f.rate_hz = rate_hz;
  f.max_gap = read_max_gap(ini, f.max_gap);
  if (segmented) {
    f.segments = read_segments(ini, base_dir);
    std::vector<std::string> names;
    for (const auto& s : f.segments) names.push_back(s.file);
    f.file = describe_files(names);
  }
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

LogReader::LogReader(const LogFormat& format) : f_(format) {
  if (f_.segments.empty()) {
    open(main_, f_.split() ? f_.accel_file : f_.file);
    if (f_.split()) open(second_, f_.gyro_file);
  }
  start();
}

LogReader::LogReader(std::istream& in, const LogFormat& format) : f_(format) {
  if (f_.split() || !f_.segments.empty())
    throw LogError(f_.file, 0, "a log in several files cannot be read from a stream");
  main_.in = &in;
  main_.name = f_.file;
  start();
}

void LogReader::open(Input& input, const std::string& path) {
  input.owned = std::make_unique<std::ifstream>(path);
  input.in = input.owned.get();
  input.name = path;
  if (!*input.in) throw LogError(path, 0, "cannot open log file");
}

void LogReader::start() {
  if (!(f_.rate_hz > 0.0)) throw LogError(f_.file, 0, "the nominal sample rate is not set");
  if (!f_.segments.empty()) return;  // each file is opened when its turn comes
  if (f_.split()) {
    auto map = [&](const std::vector<std::string>& cols, std::array<int, 4>& where,
                   const std::string& file) {
      for (int i = 0; i < static_cast<int>(cols.size()); ++i) {
        const std::string& c = cols[static_cast<std::size_t>(i)];
        if (c == "t") where[0] = i;
        if (c.size() == 1 && c[0] >= 'x' && c[0] <= 'z')
          where[static_cast<std::size_t>(c[0] - 'w')] = i;
      }
      for (int k = 1; k < 4; ++k)
        if (where[static_cast<std::size_t>(k)] < 0)
          throw LogError(file, 0, "the columns of a split log's file must name x y z");
    };
    map(f_.accel_columns, acc_cols_, f_.accel_file);
    map(f_.gyro_columns, gyr_cols_, f_.gyro_file);
    f_.columns = {"gx", "gy", "gz", "ax", "ay", "az"};
    if (acc_cols_[0] >= 0 || gyr_cols_[0] >= 0) f_.columns.insert(f_.columns.begin(), "t");
  }
  for (int i = 0; i < static_cast<int>(f_.columns.size()); ++i) {
    const std::string& c = f_.columns[static_cast<std::size_t>(i)];
    if (c == "t") col_t_ = i;
    if (c.size() == 2 && c[0] == 'g') col_g_[static_cast<std::size_t>(c[1] - 'x')] = i;
    if (c.size() == 2 && c[0] == 'a') col_a_[static_cast<std::size_t>(c[1] - 'x')] = i;
    if (c == "outer") col_outer_ = i;
    if (c == "inner") col_inner_ = i;
  }
  for (std::size_t i = 0; i < 3; ++i)
    if (col_g_[i] < 0 || col_a_[i] < 0)
      throw LogError(f_.file, 0, "the log format must name columns gx gy gz ax ay az");
  if (f_.header_lines < 0 || f_.header_lines > LogFormat::kMaxHeaderLines)
    throw LogError(
        f_.file, 0,
        "header_lines must be within 0 and " + std::to_string(LogFormat::kMaxHeaderLines));
  skip_header(main_);
  if (f_.split()) skip_header(second_);
  loc_ = &main_;
  if (f_.native && f_.kind == LogFormat::Kind::Delimited && !f_.split()) {
    std::string line;
    bool nl = true;
    do {
      if (!read_line(main_, line, nl)) fail("file ends before the column header");
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

void LogReader::skip_header(Input& input) {
  loc_ = &input;
  std::string line;
  bool nl = true;
  for (int i = 0; i < f_.header_lines; ++i)
    if (!read_line(input, line, nl))
      fail("file ends inside the " + std::to_string(f_.header_lines) + " header lines");
}

void LogReader::fail(const std::string& cause) const {
  throw LogError(loc_->name, loc_->line, cause);
}

void LogReader::bad_sample(const std::string& cause) const {
  BadSampleError e(loc_->name, loc_->line, cause);
  e.t_prev = t_prev_;
  throw e;
}

bool LogReader::read_line(Input& input, std::string& line, bool& had_newline) {
  // At most kMaxLine bytes are buffered: a longer line (binary data, a file without line ends)
  // stops the reading instead of growing a string without bound.
  if (input.buffer.empty()) input.buffer.resize(LogFormat::kMaxLine + 1);
  std::istream& in = *input.in;
  in.getline(input.buffer.data(), static_cast<std::streamsize>(input.buffer.size()));
  const auto n = static_cast<std::size_t>(in.gcount());
  if (in.bad()) {
    loc_ = &input;
    fail("read error");
  }
  const bool eof = in.eof();
  if (in.fail()) {
    if (eof && n == 0) return false;
    ++input.line;
    loc_ = &input;
    fail("line longer than " + std::to_string(LogFormat::kMaxLine) +
         " bytes: not a text log of this format (binary data, or no line ends?)");
  }
  ++input.line;
  // gcount counts the line end when one was found.
  line.assign(input.buffer.data(), eof ? n : n - 1);
  had_newline = !eof;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return true;
}

bool LogReader::read_data_line(Input& input, std::string& line, bool& had_newline) {
  do {
    if (!read_line(input, line, had_newline)) return false;
  } while (line.empty() || line[0] == '#');
  return true;
}

bool LogReader::next(ImuSample& s) {
  if (!f_.segments.empty()) return next_segment_sample(s);
  for (;;) {
    try {
      if (!read_record()) {
        if (count_ == 0 && !segment_child_)  // (a file per dwell: the parent names its dwell)
          fail(skipped_count_ == 0
                   ? std::string("no samples: the log ends after its header and comments")
                   : "no good samples: all " + std::to_string(skipped_count_) +
                         " samples were bad and skipped");
        return false;
      }
      return make_sample(s);
    } catch (const BadSampleError& e) {
      if (!on_skip_) throw;
      on_skip_(e);
      skipped_ = true;
      ++skipped_count_;
      ++skipped_run_;
    }
  }
}

bool LogReader::next_segment_sample(ImuSample& s) {
  for (;;) {
    if (segment_next_ >= f_.segments.size()) return false;
    const LogSegment& seg = f_.segments[segment_next_];
    if (!segment_) {
      LogFormat one = f_;
      one.segments.clear();
      one.file = seg.file;
      segment_ = std::make_unique<LogReader>(one);
      segment_->segment_child_ = true;
      if (on_skip_) segment_->skip_bad_samples(on_skip_);
      segment_count_ = 0;
    }
    if (segment_->next(s)) {
      // The file's own time from its first sample's interval start, placed at the dwell's start.
      if (segment_count_ == 0) segment_shift_ = seg.t_start - (s.t - s.dt);
      ++segment_count_;
      ++count_;
      s.t += segment_shift_;
      if (s.t > seg.t_end + 0.5 / f_.rate_hz) {
        char msg[300];
        std::snprintf(msg, sizeof msg,
                      "this file's data reach t = %.6f s, past the end of dwell %d at %.6f s: a "
                      "file must lie within its dwell (plan and data do not match)",
                      s.t, seg.dwell, seg.t_end);
        throw LogError(seg.file, segment_->line(), msg);
      }
      return true;
    }
    if (segment_count_ == 0)
      throw LogError(seg.file, segment_->line(),
                     "no samples in the file for dwell " + std::to_string(seg.dwell));
    segment_.reset();
    ++segment_next_;
  }
}

bool LogReader::read_record() {
  if (f_.kind == LogFormat::Kind::NovAtel) return read_novatel_record();
  if (f_.split()) return read_split_record();
  loc_ = &main_;
  bool nl = true;
  if (!read_data_line(main_, text_, nl)) return false;
  // sinscal writes a line end after every sample: a last line without one was cut (its last
  // number may be cut short and still read as a number).
  if (f_.native && !nl)
    fail("truncated line: the last line has no line end (the file was cut while being written?)");
  split_fields(text_, nl, f_.columns.size(), fields_);
  return true;
}

bool LogReader::read_split_record() {
  bool nl_a = true, nl_g = true;
  const bool a = read_data_line(main_, text_, nl_a);
  const bool g = read_data_line(second_, text2_, nl_g);
  if (!a && !g) return false;
  if (a != g) {
    const Input& on = a ? main_ : second_;
    const Input& ended = a ? second_ : main_;
    loc_ = &on;
    fail("the files of a split log have different lengths: " + ended.name + " ends at line " +
         std::to_string(ended.line) + " but this file goes on");
  }
  loc_ = &main_;
  split_fields(text_, nl_a, f_.accel_columns.size(), acc_);
  loc_ = &second_;
  split_fields(text2_, nl_g, f_.gyro_columns.size(), gyr_);
  const std::vector<double>&acc = acc_, &gyr = gyr_;
  fields_.clear();
  const bool ta = acc_cols_[0] >= 0, tg = gyr_cols_[0] >= 0;
  if (ta && tg) {
    const double t_a = acc[static_cast<std::size_t>(acc_cols_[0])] * f_.time_scale;
    const double t_g = gyr[static_cast<std::size_t>(gyr_cols_[0])] * f_.time_scale;
    const double tol = f_.time_tolerance > 0.0 ? f_.time_tolerance : 0.01 / f_.rate_hz;
    if (!(std::abs(t_a - t_g) <= tol)) {
      loc_ = &main_;
      char msg[200], limit[40];
      std::snprintf(msg, sizeof msg, "t = %.9g s here but %.9g s in ", t_a, t_g);
      std::snprintf(limit, sizeof limit, "%g", tol);
      fail(msg + second_.name + ":" + std::to_string(second_.line) +
           ": the files' times differ by more than " + limit + " s (time_tolerance)");
    }
  }
  if (ta || tg)
    fields_.push_back(ta ? acc[static_cast<std::size_t>(acc_cols_[0])]
                         : gyr[static_cast<std::size_t>(gyr_cols_[0])]);
  for (std::size_t k = 1; k < 4; ++k)
    fields_.push_back(gyr[static_cast<std::size_t>(gyr_cols_[k])]);
  for (std::size_t k = 1; k < 4; ++k)
    fields_.push_back(acc[static_cast<std::size_t>(acc_cols_[k])]);
  // Time errors name the file the time comes from.
  loc_ = ta || !tg ? &main_ : &second_;
  return true;
}

bool LogReader::read_novatel_record() {
  loc_ = &main_;
  bool nl = true;
  for (;;) {
    if (!read_line(main_, text_, nl)) {
      if (novatel_message_.empty())
        fail("no RAWIMUSA, RAWIMUSXA, RAWIMUA or RAWIMUXA log in this file (" +
             std::to_string(novatel_other_) + " other lines)");
      return false;
    }
    const std::string& l = text_;
    if (l.empty() || (l[0] != '%' && l[0] != '#')) {
      ++novatel_other_;
      continue;
    }
    const std::size_t name_end = l.find_first_of(",;*");
    const std::string name = l.substr(1, name_end == std::string::npos ? l.npos : name_end - 1);
    if (name != "RAWIMUSA" && name != "RAWIMUSXA" && name != "RAWIMUA" && name != "RAWIMUXA") {
      ++novatel_other_;
      continue;
    }
    if (novatel_message_.empty()) novatel_message_ = name;
    if (name != novatel_message_) {  // the first raw IMU log found is the one read
      ++novatel_other_;
      continue;
    }
    // CRC-32 of the text between the sync character and '*'.
    const std::size_t star = l.rfind('*');
    if (star == std::string::npos) {
      if (!nl) fail("truncated line: the file ends in the middle of a log");
      bad_sample("no '*' and CRC at the end of the log: a damaged line");
    }
    const std::string crc_text = l.substr(star + 1);
    std::uint32_t crc = 0;
    const auto r = std::from_chars(crc_text.data(), crc_text.data() + crc_text.size(), crc, 16);
    if (crc_text.size() != 8 || r.ec != std::errc() || r.ptr != crc_text.data() + crc_text.size()) {
      if (!nl && crc_text.size() < 8) fail("truncated line: the file ends in the middle of a log");
      bad_sample("CRC '" + crc_text + "' is not 8 hexadecimal digits: a damaged line");
    }
    const std::uint32_t computed = novatel_crc32(l.data() + 1, star - 1);
    if (computed != crc) {
      char msg[160];
      std::snprintf(msg, sizeof msg,
                    "CRC-32 mismatch: the log says %08x, its text gives %08x (a damaged line)",
                    static_cast<unsigned>(crc), static_cast<unsigned>(computed));
      bad_sample(msg);
    }
    const std::size_t semi = l.find(';');
    if (semi == std::string::npos || semi > star) fail("no ';' after the log header");
    std::vector<std::string> body;
    for (std::size_t pos = semi + 1;;) {
      const std::size_t comma = l.find(',', pos);
      if (comma == std::string::npos || comma > star) {
        body.push_back(l.substr(pos, star - pos));
        break;
      }
      body.push_back(l.substr(pos, comma - pos));
      pos = comma + 1;
    }
    const bool extended = name == "RAWIMUSXA" || name == "RAWIMUXA";
    const std::size_t expected = extended ? 11 : 9;
    if (body.size() != expected)
      fail(name + ": expected " + std::to_string(expected) + " fields after the header, found " +
           std::to_string(body.size()));
    auto integer = [&](std::size_t i, int base) {
      const std::string& b = body[i];
      long long v = 0;
      const char* p = b.data();
      if (base == 10 && !b.empty() && b[0] == '+') ++p;
      const auto rr = std::from_chars(p, b.data() + b.size(), v, base);
      if (b.empty() || rr.ec != std::errc() || rr.ptr != b.data() + b.size())
        bad_sample(name + " field " + std::to_string(i + 2) + " '" + b + "' is not " +
                   (base == 16 ? "hexadecimal" : "a whole number"));
      return v;
    };
    const std::size_t k = extended ? 2 : 0;
    if (extended) {
      const long long info = integer(0, 16);
      if (info & 2) fail("the IMU data are encrypted (IMU Info bit 1): they cannot be used");
      if (info & 1)
        bad_sample("the receiver flags an IMU error (IMU Info bit 0; IMU status " + body[4] + ")");
    }
    const long long week = integer(k, 10);
    double sow = 0.0;
    {
      const std::string& b = body[k + 1];
      const auto rr = std::from_chars(b.data(), b.data() + b.size(), sow);
      if (b.empty() || rr.ec != std::errc() || rr.ptr != b.data() + b.size())
        bad_sample(name + " seconds into the week '" + b + "' is not a number");
    }
    if (week < 0 || week > 100000 || !(sow >= 0.0 && sow < 604800.0))
      bad_sample(name + ": GNSS week " + body[k] + ", seconds " + body[k + 1] + " out of range");
    const long long status = integer(k + 2, 16);
    if (static_cast<std::uint32_t>(status) & f_.status_mask) {
      char msg[160];
      std::snprintf(msg, sizeof msg, "IMU status %08llx has bits %08x of status_mask set",
                    static_cast<unsigned long long>(status),
                    static_cast<unsigned>(static_cast<std::uint32_t>(status) & f_.status_mask));
      bad_sample(msg);
    }
    // Body: z, -y, x accelerometer counts, then z, -y, x gyro counts (velocity and angle
    // increments per sample, IMU body frame).
    const double z_a = static_cast<double>(integer(k + 3, 10));
    const double my_a = static_cast<double>(integer(k + 4, 10));
    const double x_a = static_cast<double>(integer(k + 5, 10));
    const double z_g = static_cast<double>(integer(k + 6, 10));
    const double my_g = static_cast<double>(integer(k + 7, 10));
    const double x_g = static_cast<double>(integer(k + 8, 10));
    if (novatel_week0_ < 0) novatel_week0_ = static_cast<long>(week);
    const double t = sow + 604800.0 * static_cast<double>(week - novatel_week0_);
    fields_.assign({t, x_g, -my_g, z_g, x_a, -my_a, z_a});
    return true;
  }
}

void LogReader::split_fields(const std::string& line, bool had_newline, std::size_t expected,
                             std::vector<double>& out) {
  out.clear();
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
    const std::string which = "field " + std::to_string(out.size() + 1);
    if (r.ec == std::errc() && r.ptr == line.data() + e && !std::isfinite(v))
      bad_sample(which + " is " + (std::isnan(v) ? "NaN" : "infinite"));
    if (b == e || r.ec != std::errc() || r.ptr != line.data() + e) {
      if (!had_newline && out.size() + 1 < expected)
        fail("truncated line: the file ends in the middle of a sample");
      std::string text = line.substr(pos, std::min<std::size_t>(end - pos, 40));
      if (end - pos > 40) text += "...";
      bad_sample(which + " '" + text + "' is not a number");
    }
    out.push_back(v);
    pos = end + 1;
  }
  if (out.size() != expected) {
    if (!had_newline && out.size() < expected)
      fail("truncated line: the file ends in the middle of a sample (" +
           std::to_string(out.size()) + " of " + std::to_string(expected) + " fields)");
    fail("expected " + std::to_string(expected) + " fields, found " + std::to_string(out.size()));
  }
}

bool LogReader::make_sample(ImuSample& s) {
  // Time.
  const double nominal_dt = 1.0 / f_.rate_hz;
  const double t = col_t_ >= 0 ? fields_[static_cast<std::size_t>(col_t_)] * f_.time_scale
                               : static_cast<double>(count_ + skipped_count_ + 1) * nominal_dt;
  if (!(std::abs(t) <= LogFormat::kMaxTime))
    bad_sample("time t = " + format_number(t) +
               " s is beyond 1e10 s: not a time (a wrong time_unit or time column?)");
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
  auto triad = [&](const TriadColumns& c, const std::array<int, 3>& col, const char* name,
                   const Input* where) {
    Eigen::Vector3d v;
    for (std::size_t i = 0; i < 3; ++i) {
      const double raw =
          fields_[static_cast<std::size_t>(col[static_cast<std::size_t>(c.axis[i])])];
      if (c.saturation > 0.0 && std::abs(raw) >= c.saturation) {
        loc_ = where;
        bad_sample(std::string("saturated sample: ") + name + " log axis " + char('x' + c.axis[i]) +
                   " reads " + format_number(raw) + " (limit " + format_number(c.saturation) + ")");
      }
      v(static_cast<Eigen::Index>(i)) = c.sign[i] * (raw - c.offset) * c.scale;
      // An increment covers the sample's interval (one nominal interval after a skip).
      const double rate = std::abs(v(static_cast<Eigen::Index>(i))) /
                          (c.increments ? (skipped_ ? nominal_dt : dt) : 1.0);
      const bool gyro = name[0] == 'g';
      const double limit = gyro ? LogFormat::kMaxRate : LogFormat::kMaxSpecificForce;
      if (!(rate <= limit)) {
        loc_ = where;
        char msg[300];
        std::snprintf(msg, sizeof msg,
                      "%s log axis %c reads %s: %g %s, beyond any sensor (limit %g %s): a wrong "
                      "unit or scale, or a damaged value",
                      name, char('x' + c.axis[i]), format_number(raw).c_str(), rate,
                      gyro ? "rad/s" : "m/s^2", limit, gyro ? "rad/s" : "m/s^2");
        bad_sample(msg);
      }
    }
    // After a skipped sample, hold this sample's rate over the whole interval since the last
    // good one (increments cover one nominal interval only).
    if (c.increments && skipped_) return Eigen::Vector3d(v * (dt / nominal_dt));
    return c.increments ? v : Eigen::Vector3d(v * dt);
  };
  s.dtheta_b = triad(f_.gyro, col_g_, "gyro", f_.split() ? &second_ : loc_);
  s.dv_b = triad(f_.accel, col_a_, "accel", f_.split() ? &main_ : loc_);
  s.has_table = col_outer_ >= 0;
  if (s.has_table) {
    s.table_outer = fields_[static_cast<std::size_t>(col_outer_)] * f_.table_scale;
    s.table_inner = fields_[static_cast<std::size_t>(col_inner_)] * f_.table_scale;
    for (const double a : {s.table_outer, s.table_inner})
      if (!(std::abs(a) <= LogFormat::kMaxTableAngle))
        bad_sample("table angle " + format_number(a) +
                   " rad is beyond 1e6 rad: a wrong table_unit or a damaged value");
  }
  s.t = t;
  s.dt = dt;
  t_prev_ = t;
  ++count_;
  skipped_ = false;
  skipped_run_ = 0;
  return true;
}

std::string path_in(const std::string& dir, const std::string& file) {
  const std::filesystem::path p(file);
  if (file.empty() || dir.empty() || p.is_absolute()) return file;
  return (std::filesystem::path(dir) / p).string();
}

}  // namespace sinscal
