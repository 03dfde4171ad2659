// A custom log split over one file per triad (accel_file, gyro_file), each with its own columns
// (t x y z, - to skip); the two files are read line by line together and their times must agree
// within time_tolerance.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "models/config.hpp"
#include "rig/io/log_keys.hpp"

namespace sinscal {

namespace log_keys {

// Columns of one file of a split log: t x y z temp or - (skip), x y z required.
namespace {

std::vector<std::string> read_split_columns(const IniFile& ini, const std::string& key) {
  if (!ini.has(key)) return {"t", "x", "y", "z"};
  std::vector<std::string> cols;
  for (const auto& c : tokens_of(ini.get_string(key))) {
    if (c != "t" && c != "x" && c != "y" && c != "z" && c != "temp" && c != "-")
      throw ConfigError(ini.where(key) + "unknown column '" + c +
                        "' (known: t x y z temp, - to skip)");
    if (c != "-" && std::count(cols.begin(), cols.end(), c))
      throw ConfigError(ini.where(key) + "column '" + c + "' given twice");
    cols.push_back(c);
  }
  for (const char* axis : {"x", "y", "z"})
    if (!std::count(cols.begin(), cols.end(), axis))
      throw ConfigError(ini.where(key) + "column '" + axis + "' missing (need x y z, t optional)");
  return cols;
}

}  // namespace

void add_split_keys(const IniFile& ini, bool segmented, std::vector<std::string>& keys) {
  if (segmented)
    throw ConfigError(ini.where("log.files") +
                      "a log in one file per dwell cannot also be split per triad "
                      "(accel_file, gyro_file)");
  if (ini.has("log.file") || ini.has("log.columns"))
    throw ConfigError(ini.where(ini.has("log.file") ? "log.file" : "log.columns") +
                      "a split log names its files as accel_file and gyro_file and their "
                      "columns as accel_columns and gyro_columns");
  keys.erase(std::remove(keys.begin(), keys.end(), "file"), keys.end());
  keys.insert(keys.end(),
              {"accel_file", "gyro_file", "accel_columns", "gyro_columns", "time_tolerance"});
}

void read_split_format(const IniFile& ini, const std::string& base_dir, LogFormat& f) {
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
  const bool temp = std::count(f.accel_columns.begin(), f.accel_columns.end(), "temp") ||
                    std::count(f.gyro_columns.begin(), f.gyro_columns.end(), "temp");
  read_temperature_keys(ini, temp, "neither accel_columns nor gyro_columns names temp", f);
}

}  // namespace log_keys

void LogReader::map_split_columns() {
  auto map = [&](const std::vector<std::string>& cols, std::array<int, 4>& where, int& temp,
                 const std::string& file) {
    for (int i = 0; i < static_cast<int>(cols.size()); ++i) {
      const std::string& c = cols[static_cast<std::size_t>(i)];
      if (c == "t") where[0] = i;
      if (c == "temp") temp = i;
      if (c.size() == 1 && c[0] >= 'x' && c[0] <= 'z')
        where[static_cast<std::size_t>(c[0] - 'w')] = i;
    }
    for (int k = 1; k < 4; ++k)
      if (where[static_cast<std::size_t>(k)] < 0)
        throw LogError(file, 0, "the columns of a split log's file must name x y z");
  };
  map(f_.accel_columns, acc_cols_, acc_temp_col_, f_.accel_file);
  map(f_.gyro_columns, gyr_cols_, gyr_temp_col_, f_.gyro_file);
  f_.columns = {"gx", "gy", "gz", "ax", "ay", "az"};
  if (acc_cols_[0] >= 0 || gyr_cols_[0] >= 0) f_.columns.insert(f_.columns.begin(), "t");
  // Each file's temperature is its triad's; in one file only, the unit's (read_split_record
  // appends them to the record).
  if (acc_temp_col_ >= 0 && gyr_temp_col_ >= 0) {
    f_.columns.insert(f_.columns.end(), {"temp_a", "temp_g"});
    temp_from_ = {&main_, &second_};
  } else if (acc_temp_col_ >= 0 || gyr_temp_col_ >= 0) {
    f_.columns.emplace_back("temp");
    const Input* from = acc_temp_col_ >= 0 ? &main_ : &second_;
    temp_from_ = {from, from};
  }
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
  split_fields(text_, nl_a, f_.accel_columns.size(), acc_, nullptr, f_.accel_columns);
  loc_ = &second_;
  split_fields(text2_, nl_g, f_.gyro_columns.size(), gyr_, nullptr, f_.gyro_columns);
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
  if (acc_temp_col_ >= 0) fields_.push_back(acc[static_cast<std::size_t>(acc_temp_col_)]);
  if (gyr_temp_col_ >= 0) fields_.push_back(gyr[static_cast<std::size_t>(gyr_temp_col_)]);
  // Time errors name the file the time comes from.
  loc_ = ta || !tg ? &main_ : &second_;
  return true;
}

}  // namespace sinscal
