// Inside the log readers (rig/io/): the [log] keys every format shares and each format's part of
// LogFormat::from_ini, one file per format. Not an interface for the rest of sinscal, which uses
// rig/io/log_io.hpp.
#pragma once

#include <initializer_list>
#include <string>
#include <vector>

#include "models/config.hpp"
#include "rig/io/log_io.hpp"

namespace sinscal {
namespace log_keys {

/// The native log's column header, without and with the table angles (native.cpp).
extern const char* const kNativeHeader;
extern const char* const kNativeTableColumns;
extern const char* const kNativeTemperatureColumns;
/// The shortest text of `v` that reads back exactly.
std::string format_number(double v);

// Keys every format shares (log_format.cpp).
std::vector<std::string> tokens_of(const std::string& text);
/// The SI factor of a unit key; a unit of the wrong kind is an error naming the line.
double unit_of(const IniFile& ini, const std::string& key, const std::string& dflt,
               QuantityKind kind);
/// One triad's keys (`log.gyro*` or `log.accel*`): increments or rates, unit, scale and offset of
/// counts, axes with signs, saturation. `rate_hz` turns one count of an increment into a rate for
/// the check of the scale.
TriadColumns read_triad(const IniFile& ini, const std::string& name, bool gyro, double rate_hz,
                        bool fixed_increments = false);
/// The temperature keys (`temperature_unit`, `_scale`, `_offset`) into `f.temperature`
/// (temperature.cpp). Without a temperature column (`has_column` false) any of them is an error
/// naming its line and saying `no_column` (where a column would be named).
void read_temperature_keys(const IniFile& ini, bool has_column, const std::string& no_column,
                           LogFormat& f);
/// The [log] keys of the temperature columns.
extern const std::vector<std::string> kTemperatureKeys;
/// [log] header_lines: a whole number within 0 ... kMaxHeaderLines.
int read_header_lines(const IniFile& ini);
char read_delimiter(const IniFile& ini);
double read_max_gap(const IniFile& ini, double dflt);
std::string describe_files(const std::vector<std::string>& files);

/// format = custom (custom_csv.cpp): `keys` are the [log] keys allowed so far.
void read_custom_format(const IniFile& ini, const std::string& base_dir, double rate_hz,
                        bool segmented, std::vector<std::string>& keys, LogFormat& f);
/// A custom log split per triad (split_files.cpp): its keys, then its files and columns.
void add_split_keys(const IniFile& ini, bool segmented, std::vector<std::string>& keys);
void read_split_format(const IniFile& ini, const std::string& base_dir, LogFormat& f);
/// format = novatel (novatel.cpp).
void read_novatel_format(const IniFile& ini, const std::string& base_dir, double rate_hz,
                         bool segmented, std::vector<std::string>& keys, LogFormat& f);
/// The files of a log recorded as one file per dwell: `files` (and `dwells`) of [log], placed in
/// the dwells of the session's plan (dwell_files.cpp).
std::vector<LogSegment> read_segments(const IniFile& ini, const std::string& base_dir);

}  // namespace log_keys
}  // namespace sinscal
