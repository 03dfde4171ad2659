// The reader every format shares: files and streams read line by line with a bounded line length,
// header lines, delimited numbers, and the sample made of a record (time, gaps, units, axes,
// saturation, skipped bad samples); each format's record comes from its own file.
#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "models/units.hpp"
#include "rig/io/log_keys.hpp"

namespace sinscal {

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
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw LogError(path, 0, "is a directory, not a log file (name the file in it)");
  input.owned = std::make_unique<std::ifstream>(path);
  input.in = input.owned.get();
  input.name = path;
  if (!*input.in) throw LogError(path, 0, "cannot open log file");
}

void LogReader::start() {
  if (!(f_.rate_hz > 0.0)) throw LogError(f_.file, 0, "the nominal sample rate is not set");
  if (!f_.segments.empty()) return;  // each file is opened when its turn comes
  if (f_.split()) map_split_columns();
  for (int i = 0; i < static_cast<int>(f_.columns.size()); ++i) {
    const std::string& c = f_.columns[static_cast<std::size_t>(i)];
    if (c == "t") col_t_ = i;
    if (c.size() == 2 && c[0] == 'g') col_g_[static_cast<std::size_t>(c[1] - 'x')] = i;
    if (c.size() == 2 && c[0] == 'a') col_a_[static_cast<std::size_t>(c[1] - 'x')] = i;
    if (c == "outer") col_outer_ = i;
    if (c == "inner") col_inner_ = i;
    if (c == "label") col_label_ = i;
    if (c == "temp") col_temp_ = {i, i};
    if (c == "temp_a") col_temp_[0] = i;
    if (c == "temp_g") col_temp_[1] = i;
    text_cols_.push_back(!f_.native && (c == "-" || c == "label") ? 1 : 0);
  }
  for (std::size_t i = 0; i < 3; ++i)
    if (col_g_[i] < 0 || col_a_[i] < 0)
      throw LogError(f_.file, 0, "the log format must name columns gx gy gz ax ay az");
  if ((col_temp_[0] < 0) != (col_temp_[1] < 0))
    throw LogError(f_.file, 0, "the log format must name both temp_a and temp_g, or temp");
  if (f_.header_lines < 0 || f_.header_lines > LogFormat::kMaxHeaderLines)
    throw LogError(
        f_.file, 0,
        "header_lines must be within 0 and " + std::to_string(LogFormat::kMaxHeaderLines));
  skip_header(main_);
  if (f_.split()) skip_header(second_);
  loc_ = &main_;
  if (f_.native && f_.kind == LogFormat::Kind::Delimited && !f_.split()) read_native_header();
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

void LogReader::gap_or_disorder(double t, const std::string& gap) {
  // Samples out of order look like a gap (a time ahead) whose next line goes back: the reading
  // stops here either way, so the next record may be read to tell which.
  const double t_prev = t_prev_;
  const std::size_t line = loc_->line;
  double t_next = t;
  try {
    if (col_t_ >= 0 && read_record())
      t_next = fields_[static_cast<std::size_t>(col_t_)] * f_.time_scale;
  } catch (const LogError&) {
    t_next = t;  // the next line is bad in its own way: the gap is what this line shows
  }
  if (!(t_next < t)) throw LogError(loc_->name, line, gap);
  char msg[300];
  std::snprintf(msg, sizeof msg,
                "time goes backwards: t = %.6f s after %.6f s at line %zu (samples out of order: "
                "line %zu jumps ahead from %.6f s)",
                t_next, t, loc_->line, line, t_prev);
  fail(msg);
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

void LogReader::split_fields(const std::string& line, bool had_newline, std::size_t expected,
                             std::vector<double>& out, const std::vector<char>* text_cols,
                             const std::vector<std::string>& names) {
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
    if (text_cols && out.size() < text_cols->size() && (*text_cols)[out.size()]) {
      if (static_cast<int>(out.size()) == col_label_) label_text_.assign(line, b, e - b);
      out.push_back(0.0);
      pos = end + 1;
      continue;
    }
    if (b < e && line[b] == '+') ++b;
    double v = 0.0;
    const auto r = std::from_chars(line.data() + b, line.data() + e, v);
    // The field's number, and what it is when a temperature (messages only).
    auto which = [&] {
      const std::size_t k = out.size();
      const bool temp = k < names.size() && names[k].compare(0, 4, "temp") == 0;
      return "field " + std::to_string(k + 1) + (temp ? " (temperature)" : "");
    };
    if (r.ec == std::errc() && r.ptr == line.data() + e && !std::isfinite(v))
      bad_sample(which() + " is " + (std::isnan(v) ? "NaN" : "infinite"));
    if (b == e || r.ec != std::errc() || r.ptr != line.data() + e) {
      if (!had_newline && out.size() + 1 < expected)
        fail("truncated line: the file ends in the middle of a sample");
      std::string text = line.substr(pos, std::min<std::size_t>(end - pos, 40));
      if (end - pos > 40) text += "...";
      bad_sample(which() + " '" + text + "' is not a number");
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
    bad_sample("time t = " + log_keys::format_number(t) +
               " s is beyond 1e10 s: not a time (a wrong time_unit or time column?)");
  double dt = nominal_dt;
  if (count_ > 0) {
    dt = t - t_prev_;
    char msg[200];
    if (dt <= 0.0) {
      std::snprintf(msg, sizeof msg, "time goes backwards: t = %.6f s after %.6f s", t, t_prev_);
      bad_sample(dt == 0.0 ? "time repeats: t = " + log_keys::format_number(t) + " s twice" : msg);
    }
    // Skipped samples leave their intervals to the next good one (bridged, see skip_bad_samples).
    if (dt > (f_.max_gap + static_cast<double>(skipped_run_)) * nominal_dt) {
      std::snprintf(msg, sizeof msg,
                    "gap in the data: %.6f s from t = %.6f s to %.6f s (about %.0f samples missing "
                    "at %g Hz)",
                    dt, t_prev_, t, dt / nominal_dt - 1.0, f_.rate_hz);
      gap_or_disorder(t, msg);
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
                   " reads " + log_keys::format_number(raw) + " (limit " +
                   log_keys::format_number(c.saturation) + ")");
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
                      name, char('x' + c.axis[i]), log_keys::format_number(raw).c_str(), rate,
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
  s.label = -1;
  if (col_label_ >= 0) {
    const auto it = std::find(labels_.begin(), labels_.end(), label_text_);
    if (it == labels_.end()) {
      if (labels_.size() >= kMaxLabels)
        fail("more than " + std::to_string(kMaxLabels) +
             " different labels in the label column: not a label column (wrong column?)");
      labels_.push_back(label_text_);
    }
    s.label =
        static_cast<int>(std::find(labels_.begin(), labels_.end(), label_text_) - labels_.begin());
  }
  if (s.has_table) {
    s.table_outer = fields_[static_cast<std::size_t>(col_outer_)] * f_.table_scale;
    s.table_inner = fields_[static_cast<std::size_t>(col_inner_)] * f_.table_scale;
    for (const double a : {s.table_outer, s.table_inner})
      if (!(std::abs(a) <= LogFormat::kMaxTableAngle))
        bad_sample("table angle " + log_keys::format_number(a) +
                   " rad is beyond 1e6 rad: a wrong table_unit or a damaged value");
  }
  read_temperatures(s, t);
  s.t = t;
  s.dt = dt;
  t_prev_ = t;
  ++count_;
  skipped_ = false;
  skipped_run_ = 0;
  accept_temperatures(s);
  return true;
}

}  // namespace sinscal
