// IMU logs. The native format (written by `sinscal simulate`) is CSV with a header naming each
// column and its unit; a configurable reader also takes foreign logs: column order, delimiter,
// header lines, units including raw counts with a scale and offset, increments or rates, axis
// mapping with signs. Format and [log] keys: docs/formats.md.
#pragma once

#include <array>
#include <cstdint>
#include <fstream>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "rig/imu_sample.hpp"

namespace sinscal {

class IniFile;

/// A problem in a log file; what() reads "FILE:LINE: cause".
class LogError : public std::runtime_error {
 public:
  LogError(const std::string& file, std::size_t line, const std::string& cause);
  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }
  const std::string& cause() const { return cause_; }

 private:
  std::string file_;
  std::size_t line_;
  std::string cause_;
};

/// A bad sample that a reader may skip (a value NaN, infinite, not a number or saturated; time
/// going backwards or repeating). Other problems (gaps, truncation, wrong field counts) are not.
class BadSampleError : public LogError {
 public:
  using LogError::LogError;
  double t_prev = 0.0;  // s, time of the last good sample before it
};

/// How one triad is stored in a log.
struct TriadColumns {
  bool increments = true;  // true: angle/velocity increments; false: rates
  double scale = 1.0;      // SI per (count - offset): unit factor times counts-to-unit scale
  double offset = 0.0;     // subtracted from the raw value before scaling
  std::array<int, 3> axis{0, 1, 2};           // body axis i comes from log axis axis[i]
  std::array<double, 3> sign{1.0, 1.0, 1.0};  // with this sign
  double saturation = 0.0;  // |raw value| at or beyond which a sample is saturated (0: none)
};

struct LogFormat {
  std::string file;                  // path of the data file
  bool native = true;                // the sinscal CSV (the header is checked)
  char delimiter = ',';              // ' ' means any run of spaces or tabs
  int header_lines = 1;              // lines skipped before the data (after them, '#' lines too)
  std::vector<std::string> columns;  // t gx gy gz ax ay az [outer inner], "-" to skip
  double table_scale = 0.0;          // rad per table-angle unit (outer/inner columns)
  double time_scale = 1.0;           // s per time unit
  double rate_hz = 0.0;              // nominal rate; needed when there is no time column
  double max_gap = 1.5;              // a step in time above max_gap / rate_hz is a gap (error)
  TriadColumns gyro, accel;

  /// The native format for a rate.
  static LogFormat native_format(const std::string& file, double rate_hz);
  /// From the [log] section of a session file; relative paths are taken from `base_dir`.
  static LogFormat from_ini(const IniFile& ini, const std::string& base_dir, double rate_hz);
};

/// Writes the native CSV format.
class LogWriter {
 public:
  /// With `table_angles`, two more columns: the table's outer and inner axis angles [deg].
  LogWriter(const std::string& path, double rate_hz, bool table_angles = false);
  void write(const ImuSample& s);
  void close();

 private:
  std::string path_;
  std::ofstream out_;
  std::string buffer_;
  bool table_ = false;
};

/// Reads a log sample by sample in constant memory; every problem throws LogError with the line.
class LogReader : public SampleSource {
 public:
  explicit LogReader(const LogFormat& format);
  /// Reads from a stream (standard input, a pipe); `format.file` names it in messages.
  LogReader(std::istream& in, const LogFormat& format);
  bool next(ImuSample& sample) override;
  std::size_t line() const { return line_; }
  /// Samples read so far.
  std::size_t count() const { return count_; }
  /// Skip bad samples (BadSampleError) instead of throwing: each is passed to `on_skip` and the
  /// reading goes on. The motion of a skipped interval is bridged by holding the next good
  /// sample's rate over it (its increments are scaled to the whole interval since the last good
  /// sample).
  void skip_bad_samples(std::function<void(const BadSampleError&)> on_skip) {
    on_skip_ = std::move(on_skip);
  }

 private:
  [[noreturn]] void fail(const std::string& cause) const;
  [[noreturn]] void bad_sample(const std::string& cause) const;
  bool parse(const std::string& line, bool had_newline, ImuSample& s);
  bool read_line(std::string& line, bool& had_newline);
  void start();
  LogFormat f_;
  std::unique_ptr<std::ifstream> file_;
  std::istream* in_ = nullptr;
  std::size_t line_ = 0, count_ = 0;
  int col_t_ = -1;
  std::array<int, 3> col_g_{-1, -1, -1}, col_a_{-1, -1, -1};
  int col_outer_ = -1, col_inner_ = -1;
  double t_prev_ = 0.0;
  std::vector<double> fields_;
  std::function<void(const BadSampleError&)> on_skip_;
  bool skipped_ = false;  // a sample was skipped since the last good one
  std::size_t skipped_count_ = 0;
  std::size_t skipped_run_ = 0;  // consecutive skipped samples before the next good one
};

}  // namespace sinscal
