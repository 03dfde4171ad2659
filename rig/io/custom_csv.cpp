// A foreign delimited log (format = custom): column order, delimiter, header lines, units including
// raw counts with a scale and offset, increments or rates, axis mapping with signs, optional table
// angles. Its record is one line of numbers in the order of `columns`.
#include <algorithm>

#include "models/config.hpp"
#include "rig/io/log_keys.hpp"

namespace sinscal {

namespace log_keys {

void read_custom_format(const IniFile& ini, const std::string& base_dir, double rate_hz,
                        bool segmented, std::vector<std::string>& keys, LogFormat& f) {
  const bool split = ini.has("log.accel_file") || ini.has("log.gyro_file");
  keys.insert(keys.end(),
              {"delimiter", "header_lines", "time_unit", "gyro", "gyro_unit", "gyro_scale",
               "gyro_offset", "gyro_axes", "gyro_saturation", "accel", "accel_unit", "accel_scale",
               "accel_offset", "accel_axes", "accel_saturation"});
  keys.insert(keys.end(), kTemperatureKeys.begin(), kTemperatureKeys.end());
  if (split) {
    add_split_keys(ini, segmented, keys);
  } else {
    keys.insert(keys.end(), {"columns", "table_unit"});
  }
  ini.check_keys("log", keys);
  f.native = false;
  f.delimiter = read_delimiter(ini);
  f.header_lines = read_header_lines(ini);
  // A sample counter as the time column: time_unit = samples (each count one 1/rate).
  const bool counter = ini.has("log.time_unit") && ini.get_string("log.time_unit") == "samples";
  if (counter && !(rate_hz > 0.0))
    throw ConfigError(ini.where("log.time_unit") +
                      "'samples' needs the sample rate ([session] rate)");
  f.time_scale = counter ? 1.0 / rate_hz : unit_of(ini, "log.time_unit", "s", QuantityKind::Time);
  if (split) {
    read_split_format(ini, base_dir, f);
  } else {
    if (!segmented) f.file = path_in(base_dir, ini.get_string("log.file"));
    for (const auto& c : tokens_of(ini.get_string("log.columns"))) {
      static const std::vector<std::string> known = {"t",      "gx",     "gy",    "gz",    "ax",
                                                     "ay",     "az",     "outer", "inner", "temp",
                                                     "temp_a", "temp_g", "label", "-"};
      if (std::find(known.begin(), known.end(), c) == known.end())
        throw ConfigError(ini.where("log.columns") + "unknown column '" + c +
                          "' (known: t gx gy gz ax ay az outer inner temp temp_a temp_g label, - "
                          "to skip)");
      if (c != "-" && std::count(f.columns.begin(), f.columns.end(), c))
        throw ConfigError(ini.where("log.columns") + "column '" + c + "' given twice");
      f.columns.push_back(c);
    }
    const bool outer = std::count(f.columns.begin(), f.columns.end(), "outer") > 0;
    if (outer != (std::count(f.columns.begin(), f.columns.end(), "inner") > 0))
      throw ConfigError(ini.where("log.columns") +
                        "give both table-angle columns, outer and inner");
    if (outer) f.table_scale = unit_of(ini, "log.table_unit", "deg", QuantityKind::Angle);
    // Temperature: one column for the unit (temp) or one per triad (temp_a and temp_g).
    auto has = [&](const char* c) { return std::count(f.columns.begin(), f.columns.end(), c) > 0; };
    if (has("temp") && (has("temp_a") || has("temp_g")))
      throw ConfigError(ini.where("log.columns") +
                        "give either temp (one temperature for the unit) or temp_a and temp_g "
                        "(one per triad), not both");
    if (has("temp_a") != has("temp_g"))
      throw ConfigError(ini.where("log.columns") + "give both per-triad temperature columns, " +
                        "temp_a and temp_g (or temp for one temperature for the unit)");
    read_temperature_keys(ini, has("temp") || has("temp_a"),
                          "'columns' names none (temp, or temp_a and temp_g)", f);
  }
  f.gyro = read_triad(ini, "gyro", true, rate_hz);
  f.accel = read_triad(ini, "accel", false, rate_hz);
  for (const char* c : {"gx", "gy", "gz", "ax", "ay", "az"})
    if (!split && !std::count(f.columns.begin(), f.columns.end(), c))
      throw ConfigError(ini.where("log.columns") + "column '" + c +
                        "' missing (the columns must name gx gy gz ax ay az)");
}

}  // namespace log_keys

namespace {
// The significant digits of a line's last field (its mantissa's digits, leading zeros not
// counted): "0.0980665" 6, "25" 2, "1.5e-3" 2.
int last_field_digits(const std::string& line, char delimiter) {
  std::size_t start = delimiter == ' ' ? line.find_last_of(" \t") : line.rfind(delimiter);
  start = start == std::string::npos ? 0 : start + 1;
  int digits = 0;
  bool leading = true;
  for (std::size_t i = start; i < line.size(); ++i) {
    const char c = line[i];
    if (c == 'e' || c == 'E') break;
    if (c < '0' || c > '9') continue;
    if (leading && c == '0') continue;
    leading = false;
    ++digits;
  }
  return digits;
}
}  // namespace

bool LogReader::read_record() {
  if (f_.kind == LogFormat::Kind::NovAtel) return read_novatel_record();
  if (f_.split()) return read_split_record();
  loc_ = &main_;
  bool nl = true;
  if (!read_data_line(main_, text_, nl)) return false;
  // sinscal writes a line end after every sample: a last line without one is complete unless
  // its last number has fewer digits than the line before's, which a cut while writing would
  // make (and still read as a number). A cut past the 12th digit changes nothing measurable
  // (round-trip numbers hold 15 to 17, varying line to line).
  if (f_.native) {
    constexpr int kHarmlessDigits = 12;
    const int digits = last_field_digits(text_, f_.delimiter);
    if (!nl && digits < std::min(last_field_digits_, kHarmlessDigits))
      fail(
          "truncated line: the last line has no line end and its last number has fewer digits "
          "than the line before's (the file was cut while being written?); if the line is "
          "complete, end it with a line end");
    last_field_digits_ = digits;
  }
  split_fields(text_, nl, f_.columns.size(), fields_, &text_cols_, f_.columns);
  return true;
}

}  // namespace sinscal
