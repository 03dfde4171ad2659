// The native format, written by `sinscal simulate`: CSV with a header naming each column and its
// unit, increments over (t - dt, t] in body axes, optionally the table's two axis angles, then
// optionally each triad's temperature.
#include <charconv>

#include "models/units.hpp"
#include "rig/io/log_keys.hpp"

namespace sinscal {

namespace log_keys {

const char* const kNativeHeader =
    "t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],dv_y [m/s],dv_z [m/s]";
const char* const kNativeTableColumns = ",outer [deg],inner [deg]";
const char* const kNativeTemperatureColumns = ",temperature_accel [C],temperature_gyro [C]";

std::string format_number(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);  // shortest exact round trip
  return std::string(buf, r.ptr);
}

}  // namespace log_keys

LogFormat LogFormat::native_format(const std::string& file, double rate_hz) {
  LogFormat f;
  f.file = file;
  f.native = true;
  f.header_lines = 0;
  f.columns = {"t", "gx", "gy", "gz", "ax", "ay", "az"};
  f.rate_hz = rate_hz;
  return f;
}

void LogReader::read_native_header() {
  std::string line;
  bool nl = true;
  do {
    if (!read_line(main_, line, nl)) fail("file ends before the column header");
  } while (!line.empty() && line[0] == '#');
  // The header, then optionally the table's columns, then optionally the temperatures.
  const std::string base = log_keys::kNativeHeader, table = log_keys::kNativeTableColumns,
                    temp = log_keys::kNativeTemperatureColumns;
  const bool with_table = line == base + table || line == base + table + temp;
  const bool with_temp = line == base + temp || line == base + table + temp;
  if (!with_table && !with_temp && line != base)
    fail("not a sinscal log: expected the column header '" + base + "' (optionally followed by '" +
         table + "', then optionally by '" + temp + "')");
  if (with_table) {
    f_.columns.push_back("outer");
    f_.columns.push_back("inner");
    col_outer_ = static_cast<int>(f_.columns.size()) - 2;
    col_inner_ = col_outer_ + 1;
    f_.table_scale = units::deg;
  }
  if (with_temp) {
    f_.columns.push_back("temp_a");
    f_.columns.push_back("temp_g");
    col_temp_ = {static_cast<int>(f_.columns.size()) - 2, static_cast<int>(f_.columns.size()) - 1};
    f_.temperature = TemperatureColumns{};  // deg C
  }
}

LogWriter::LogWriter(const std::string& path, double rate_hz, bool table_angles, bool temperature)
    : path_(path), out_(path), table_(table_angles), temperature_(temperature) {
  if (!out_) throw std::runtime_error(path + ": cannot create log file");
  out_ << "# sinscal IMU log, format 1: increments over (t - dt, t], body axes\n"
       << "# rate_hz = " << log_keys::format_number(rate_hz) << "\n"
       << log_keys::kNativeHeader << (table_ ? log_keys::kNativeTableColumns : "")
       << (temperature_ ? log_keys::kNativeTemperatureColumns : "") << "\n";
  buffer_.reserve(1 << 16);
}

void LogWriter::write(const ImuSample& s) {
  buffer_ += log_keys::format_number(s.t);
  for (int i = 0; i < 3; ++i) (buffer_ += ',') += log_keys::format_number(s.dtheta_b(i));
  for (int i = 0; i < 3; ++i) (buffer_ += ',') += log_keys::format_number(s.dv_b(i));
  if (table_) {
    if (!s.has_table)
      throw std::invalid_argument(path_ + ": a sample without the table angles the log declares");
    (buffer_ += ',') += log_keys::format_number(s.table_outer / units::deg);
    (buffer_ += ',') += log_keys::format_number(s.table_inner / units::deg);
  }
  if (temperature_) {
    if (!s.has_temperature)
      throw std::invalid_argument(path_ + ": a sample without the temperatures the log declares");
    (buffer_ += ',') += log_keys::format_number(s.accel_temperature_c);
    (buffer_ += ',') += log_keys::format_number(s.gyro_temperature_c);
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

}  // namespace sinscal
