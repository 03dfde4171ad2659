// IMU logs. The native format (written by `sinscal simulate`) is CSV with a header naming each
// column and its unit; a configurable reader also takes foreign logs: column order, delimiter,
// header lines, units including raw counts with a scale and offset, increments or rates, axis
// mapping with signs; a log split over one file per triad (accelerometers, gyros) sharing a time
// column; NovAtel RAWIMUSA / RAWIMUSXA ASCII logs (CRC-32 checked); and a session recorded as
// one file per dwell of the plan; temperature columns (one per unit or per triad) checked for
// range and jumps. Format and [log] keys: docs/formats.md.
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
  /// The log holds raw counts (`_scale` or `_offset` given): scale and offset are then the
  /// nominal conversion, the starting point of a calibration in counts (raw-count views).
  bool counts = false;
};

/// How the temperature columns of a log are stored (docs/formats.md "Temperature columns").
struct TemperatureColumns {
  enum class Unit { Celsius, Kelvin, Fahrenheit };
  Unit unit = Unit::Celsius;  // of the values after scale and offset
  double scale = 1.0;         // units per (count - offset); 1 when values are in the unit
  double offset = 0.0;        // subtracted from the raw value before scaling
  /// deg C of a raw field.
  double celsius(double raw) const { return to_celsius((raw - offset) * scale, unit); }
  /// deg C of a value in `unit`.
  static double to_celsius(double value, Unit unit);
  /// The unit's symbol: C, K or F.
  static const char* symbol(Unit unit);
};

/// The temperatures of a log, summarized sample by sample in constant memory (LogReader keeps
/// one): span, extremes and where the first and last samples are.
struct TemperatureSummary {
  std::size_t samples = 0;
  double t_first = 0.0, t_last = 0.0;  // s
  std::string file_first, file_last;
  std::size_t line_first = 0, line_last = 0;
  double accel_min_c = 0.0, accel_max_c = 0.0;  // deg C
  double gyro_min_c = 0.0, gyro_max_c = 0.0;    // deg C
  bool one_per_unit = false;  // every sample's two temperatures equal (one column for the unit)
  /// Adds a sample that has temperatures (others are ignored), read at `file`:`line`.
  void add(const ImuSample& s, const std::string& file, std::size_t line);
};

/// One file of a log recorded as one file per dwell: its samples are placed in the dwell.
struct LogSegment {
  std::string file;      // path
  int dwell = 0;         // the plan's dwell (1-based, as Dwell::index)
  double t_start = 0.0;  // s, log time at which the dwell starts (time_offset included)
  double t_end = 0.0;    // s, log time at which it ends
};

/// `file` as seen from the current directory when it is named relative to `dir` (a session's
/// directory): unchanged when absolute or when `dir` is empty.
std::string path_in(const std::string& dir, const std::string& file);

struct LogFormat {
  enum class Kind { Delimited, NovAtel };
  /// Longest line a reader accepts (bytes); a longer one is an error, never buffered whole.
  static constexpr std::size_t kMaxLine = 65536;
  /// Most header lines a format may skip.
  static constexpr int kMaxHeaderLines = 100000;
  /// Largest `max_gap` (samples).
  static constexpr double kMaxGap = 1000.0;
  /// Plausibility bounds of a sample (docs/formats.md): beyond them a value is not a measurement
  /// (a wrong unit or scale, a damaged field) and the sample is bad. Angular rate (an angle
  /// increment over its interval): 1e6 rad/s; specific force (a velocity increment over its
  /// interval): 1e6 m/s^2 (about 100,000 g); time: within 1e10 s of 0 (GPS and Unix seconds are
  /// about 1e9 s); table angles: within 1e6 rad (about 160,000 turns).
  static constexpr double kMaxRate = 1e6;           // rad/s
  static constexpr double kMaxSpecificForce = 1e6;  // m/s^2
  static constexpr double kMaxTime = 1e10;          // s
  static constexpr double kMaxTableAngle = 1e6;     // rad
  /// Temperature bounds (docs/formats.md "Temperature columns"). A sensor's temperature lies
  /// within kMinTemperature ... kMaxTemperature (the -55 ... +125 C military range of parts, 5 C
  /// beyond). Any two samples of a file differ by at most kTemperatureStep (a temperature
  /// sensor's quantization and noise) plus kTemperatureRate times the time between them (15 times
  /// the fastest chamber ramp, 20 C/min; a packaged sensor's thermal time constant is seconds to
  /// minutes). A temperature exactly constant over more than kStuckTemperatureSpan is a stuck
  /// sensor (check_temperature_not_stuck).
  static constexpr double kMinTemperature = -60.0;        // deg C
  static constexpr double kMaxTemperature = 130.0;        // deg C
  static constexpr double kTemperatureStep = 2.0;         // deg C
  static constexpr double kTemperatureRate = 5.0;         // deg C/s
  static constexpr double kStuckTemperatureSpan = 600.0;  // s

  std::string file;  // path of the data file (split and segmented logs: a
                     // description naming their files, for messages)
  Kind kind = Kind::Delimited;
  bool native = true;    // the sinscal CSV (the header is checked)
  char delimiter = ',';  // ' ' means any run of spaces or tabs
  int header_lines = 1;  // lines skipped before the data (after them, '#' lines too)
  /// t gx gy gz ax ay az [outer inner] [temp | temp_a temp_g] [label], "-" to skip (any text);
  /// `label`: a text column whose value labels each sample (ImuSample::label,
  /// LogReader::labels()); `temp`: the unit's temperature, `temp_a`, `temp_g`: each triad's.
  std::vector<std::string> columns;
  /// The temperature columns' unit, scale and offset.
  TemperatureColumns temperature;
  double table_scale = 0.0;  // rad per table-angle unit (outer/inner columns)
  double time_scale = 1.0;   // s per time unit
  double rate_hz = 0.0;      // nominal rate; needed when there is no time column
  double max_gap = 1.5;      // a step in time above max_gap / rate_hz is a gap (error)
  TriadColumns gyro, accel;

  /// A log split over two files sharing a time column (imu_tk style): both set. Each file's
  /// columns are named t x y z temp or - (skip); without t in either, the time is sample number /
  /// rate; `temp` is that triad's temperature (in one file only: the unit's).
  std::string accel_file, gyro_file;
  std::vector<std::string> accel_columns, gyro_columns;
  double time_tolerance = 0.0;  // s: split files' times may differ this much (0: 1 % of 1/rate)

  /// NovAtel: IMU status bits that make a sample bad (0: the status is not checked).
  std::uint32_t status_mask = 0;

  /// A log recorded as one file per dwell (non-empty): each file in the format above, its time
  /// relative to its own start placed at its dwell's start, in dwell order.
  std::vector<LogSegment> segments;

  bool split() const { return !accel_file.empty(); }

  /// The native format for a rate.
  static LogFormat native_format(const std::string& file, double rate_hz);
  /// From the [log] section of a session file; relative paths are taken from `base_dir`. A log
  /// in one file per dwell (`files`) takes the dwells' times from the session's plan
  /// ([session] plan, time_offset).
  static LogFormat from_ini(const IniFile& ini, const std::string& base_dir, double rate_hz);
};

/// A stuck temperature sensor, the check a thermal calibration calls (a non-thermal one does not
/// need the column): throws LogError naming the last sample's file and line when a triad's
/// temperature reads exactly the same over a log longer than `min_span_s`; a shorter log, or one
/// without temperatures, passes.
void check_temperature_not_stuck(const TemperatureSummary& summary,
                                 double min_span_s = LogFormat::kStuckTemperatureSpan);

/// Writes the native CSV format.
class LogWriter {
 public:
  /// With `table_angles`, two more columns: the table's outer and inner axis angles [deg]; with
  /// `temperature`, two more after them: each triad's temperature [C].
  LogWriter(const std::string& path, double rate_hz, bool table_angles = false,
            bool temperature = false);
  void write(const ImuSample& s);
  void close();

 private:
  std::string path_;
  std::ofstream out_;
  std::string buffer_;
  bool table_ = false;
  bool temperature_ = false;
};

/// Reads a log sample by sample in constant memory; every problem throws LogError with the line.
class LogReader : public SampleSource {
 public:
  explicit LogReader(const LogFormat& format);
  /// Reads from a stream (standard input, a pipe); `format.file` names it in messages.
  LogReader(std::istream& in, const LogFormat& format);
  LogReader(const LogReader&) = delete;  // holds pointers into itself
  LogReader& operator=(const LogReader&) = delete;
  bool next(ImuSample& sample) override;
  /// Line of the last record read (split logs: of the accelerometer file; one file per dwell:
  /// of the current file).
  std::size_t line() const { return segment_ ? segment_->line() : loc_->line; }
  /// Samples read so far.
  std::size_t count() const { return count_; }
  /// The distinct texts of the label column in the order first seen (ImuSample::label indexes
  /// them); empty without a label column.
  const std::vector<std::string>& labels() const { return labels_; }
  /// The temperatures read so far (samples 0 without temperature columns): what
  /// check_temperature_not_stuck takes.
  const TemperatureSummary& temperature_summary() const { return temperature_summary_; }
  /// Most distinct labels a log may have (more: not a label column).
  static constexpr std::size_t kMaxLabels = 10000;
  /// Skip bad samples (BadSampleError) instead of throwing: each is passed to `on_skip` and the
  /// reading goes on. The motion of a skipped interval is bridged by holding the next good
  /// sample's rate over it (its increments are scaled to the whole interval since the last good
  /// sample).
  void skip_bad_samples(std::function<void(const BadSampleError&)> on_skip) {
    on_skip_ = std::move(on_skip);
    if (segment_) segment_->skip_bad_samples(on_skip_);
  }

 private:
  /// One input file or stream, read line by line with a bounded line length.
  struct Input {
    std::unique_ptr<std::ifstream> owned;
    std::istream* in = nullptr;
    std::string name;
    std::size_t line = 0;
    std::vector<char> buffer;
  };
  [[noreturn]] void fail(const std::string& cause) const;
  [[noreturn]] void bad_sample(const std::string& cause) const;
  void open(Input& input, const std::string& path);
  bool read_line(Input& input, std::string& line, bool& had_newline);
  /// Next line that is neither empty nor a '#' comment.
  bool read_data_line(Input& input, std::string& line, bool& had_newline);
  void skip_header(Input& input);
  /// Splits a delimited line into numbers (exactly `expected` of them).
  /// Fields flagged in `text_cols` (the record's skipped and label columns) are not read as
  /// numbers.
  /// `names` (the columns' names) lets a message say which field is a temperature.
  void split_fields(const std::string& line, bool had_newline, std::size_t expected,
                    std::vector<double>& out, const std::vector<char>* text_cols,
                    const std::vector<std::string>& names);
  /// The next record's fields in the layout of f_.columns; false at the end.
  bool read_record();
  /// A gap at time `t` (message `gap`) or, when the next record's time is before `t`, samples out
  /// of order: throws LogError naming the line.
  [[noreturn]] void gap_or_disorder(double t, const std::string& gap);
  bool read_split_record();
  bool read_novatel_record();
  bool make_sample(ImuSample& s);
  /// The record's temperatures into `s`, checked (range, jumps) against the file's earlier
  /// samples (temperature.cpp); `t` the sample's time.
  void read_temperatures(ImuSample& s, double t);
  /// After a good sample: its temperatures join the jump checks' history and the summary.
  void accept_temperatures(const ImuSample& s);
  bool next_segment_sample(ImuSample& s);
  void start();
  /// The split log's columns (split_files.cpp), the native log's column header (native.cpp).
  void map_split_columns();
  void read_native_header();

  LogFormat f_;
  Input main_, second_;        // the log (split: accelerometer file), the split gyro file
  const Input* loc_ = &main_;  // the file and line messages name
  std::size_t count_ = 0;
  int col_t_ = -1;
  std::array<int, 3> col_g_{-1, -1, -1}, col_a_{-1, -1, -1};
  int col_outer_ = -1, col_inner_ = -1, col_label_ = -1;
  std::array<int, 2> col_temp_{-1, -1};  // accel, gyro temperature (one per unit: the same)
  std::array<const Input*, 2> temp_from_{nullptr, nullptr};  // split: the file of each
  /// The history of one triad's temperature in this file for the jump check: the extremes of
  /// T - r (t - t0) and T + r (t - t0) over the good samples so far, r = kTemperatureRate.
  struct TemperatureTrack {
    bool started = false;
    double t0 = 0.0;
    double low_key = 0.0, low_t = 0.0, low_c = 0.0;
    std::size_t low_line = 0;
    double high_key = 0.0, high_t = 0.0, high_c = 0.0;
    std::size_t high_line = 0;
  };
  std::array<TemperatureTrack, 2> temp_track_;
  TemperatureSummary temperature_summary_;
  /// One file per dwell: whether the first file has temperatures (1) or not (0); -1: not known.
  int segment_temperature_ = -1;
  std::vector<char> text_cols_;  // per column of the record: not a number ("-", label)
  std::string label_text_;       // the label field of the current record
  std::vector<std::string> labels_;
  double t_prev_ = 0.0;
  std::vector<double> fields_, acc_, gyr_;  // a record; a split log's two lines
  std::string text_, text2_;
  // A native log's last field's significant digits on the line before (a last line without a
  // line end is complete when its last number is not shorter; -1: no line yet).
  int last_field_digits_ = -1;
  // split: where t, x, y, z are in each file's columns (-1: absent)
  std::array<int, 4> acc_cols_{-1, -1, -1, -1}, gyr_cols_{-1, -1, -1, -1};
  int acc_temp_col_ = -1, gyr_temp_col_ = -1;
  // NovAtel
  std::string novatel_message_;  // the raw IMU log read (the first one found)
  long novatel_week0_ = -1;
  std::size_t novatel_other_ = 0;  // lines of other logs skipped
  // one file per dwell
  std::unique_ptr<LogReader> segment_;
  std::size_t segment_next_ = 0;
  std::size_t segment_count_ = 0;  // samples of the current segment
  double segment_shift_ = 0.0;
  std::function<void(const BadSampleError&)> on_skip_;
  bool skipped_ = false;  // a sample was skipped since the last good one
  std::size_t skipped_count_ = 0;
  std::size_t skipped_run_ = 0;  // consecutive skipped samples before the next good one
  bool segment_child_ = false;   // one file of a log in one file per dwell (the parent checks)
};

}  // namespace sinscal
