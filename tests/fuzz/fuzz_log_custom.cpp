// libFuzzer target: LogReader over an std::istream in a custom format (rig/io/log_io.hpp). Input:
// two option bytes choosing the format (delimiter, header lines, rates or increments, units, axis
// mapping, time and table columns, saturation, skipping bad samples), then the log text. Every
// error is a LogError naming the file; every sample read is finite and moves time forward.
#include <cmath>
#include <sstream>

#include "fuzz_log.hpp"
#include "models/units.hpp"
#include "rig/io/log_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::fuzz::finding;
  if (size < 2) return 0;
  const unsigned a = data[0], b = data[1];
  sinscal::LogFormat f;
  f.file = "fuzz.log";
  f.native = false;
  f.rate_hz = (b & 0x80) != 0 ? 200.0 : 100.0;
  static const char delimiters[] = {',', ';', '\t', ' '};
  f.delimiter = delimiters[a & 3];
  f.header_lines = static_cast<int>(b & 3);
  const bool time_column = (a & 0x10) != 0, table = (a & 0x20) != 0;
  f.columns = {time_column ? "t" : "-", "gx", "gy", "gz", "ax", "ay", "az"};
  if ((b & 0x04) != 0)
    f.columns = {"az", "ay", "ax", "-", "gz", "gy", "gx", time_column ? "t" : "-"};
  if (table) {
    f.columns.push_back("outer");
    f.columns.push_back("inner");
    f.table_scale = sinscal::units::deg;
  }
  f.time_scale = (b & 0x08) != 0 ? 1e-3 : 1.0;
  f.gyro.increments = (a & 0x04) == 0;
  f.gyro.scale = f.gyro.increments ? sinscal::units::arcsec : sinscal::units::deg_per_h;
  f.accel.increments = (a & 0x08) == 0;
  f.accel.scale = f.accel.increments ? 1e-3 : sinscal::units::g0;
  f.accel.offset = (b & 0x10) != 0 ? 32768.0 : 0.0;
  if ((b & 0x20) != 0) {
    f.gyro.axis = {2, 0, 1};
    f.gyro.sign = {-1.0, 1.0, -1.0};
  }
  if ((a & 0x80) != 0) f.gyro.saturation = f.accel.saturation = 1e6;
  if ((b & 0x40) != 0) f.max_gap = 3.0;
  const bool skip = (a & 0x40) != 0;
  std::istringstream in(sinscal::fuzz::text_of(data + 2, size - 2));
  try {
    sinscal::LogReader reader(in, f);
    if (skip) reader.skip_bad_samples([](const sinscal::BadSampleError&) {});
    sinscal::fuzz::read_all_samples(reader);
  } catch (const sinscal::LogError& e) {
    sinscal::fuzz::check_message(e, f.file + ":");
  } catch (const std::exception& e) {
    finding("not a LogError", e.what());
  }
  return 0;
}
