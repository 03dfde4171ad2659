// libFuzzer target: the `label` and temperature columns of a custom log (rig/io/log_io.hpp,
// docs/formats.md "Temperature columns"): one option byte chooses the columns (one `temp` for the
// unit or `temp_a temp_g` per triad, a `label` column before or after them, the temperature unit,
// scale and offset), then the log text. Every error is a LogError naming the file; every sample
// read is finite with its temperatures in range (fuzz_log.hpp) and a label that indexes labels().
#include <sstream>

#include "fuzz_log.hpp"
#include "rig/io/log_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::fuzz::finding;
  if (size < 1) return 0;
  const unsigned a = data[0];
  sinscal::LogFormat f;
  f.file = "fuzz.log";
  f.native = false;
  f.rate_hz = 100.0;
  f.delimiter = (a & 0x40) != 0 ? ' ' : ',';
  f.header_lines = 0;
  f.columns = {"t", "gx", "gy", "gz", "ax", "ay", "az"};
  const bool label_first = (a & 0x02) != 0;
  if ((a & 0x01) != 0 && label_first) f.columns.push_back("label");
  if ((a & 0x04) != 0) {
    f.columns.push_back("temp_a");
    f.columns.push_back("temp_g");
  } else {
    f.columns.push_back("temp");
  }
  if ((a & 0x01) != 0 && !label_first) f.columns.push_back("label");
  using Unit = sinscal::TemperatureColumns::Unit;
  f.temperature.unit = (a & 0x08) != 0   ? Unit::Kelvin
                       : (a & 0x10) != 0 ? Unit::Fahrenheit
                                         : Unit::Celsius;
  if ((a & 0x20) != 0) {
    f.temperature.scale = 0.01;
    f.temperature.offset = 1000.0;
  }
  f.gyro.increments = f.accel.increments = false;
  std::istringstream in(sinscal::fuzz::text_of(data + 1, size - 1));
  try {
    sinscal::LogReader reader(in, f);
    if ((a & 0x80) != 0) reader.skip_bad_samples([](const sinscal::BadSampleError&) {});
    sinscal::ImuSample s;
    while (reader.next(s)) {
      if (s.label < -1 || s.label >= static_cast<int>(reader.labels().size()))
        finding("a label outside labels()", std::to_string(s.label));
      if (s.has_temperature && !(s.accel_temperature_c >= sinscal::LogFormat::kMinTemperature &&
                                 s.accel_temperature_c <= sinscal::LogFormat::kMaxTemperature &&
                                 s.gyro_temperature_c >= sinscal::LogFormat::kMinTemperature &&
                                 s.gyro_temperature_c <= sinscal::LogFormat::kMaxTemperature))
        finding("a temperature out of range", "line " + std::to_string(reader.line()));
    }
    sinscal::check_temperature_not_stuck(reader.temperature_summary());
  } catch (const sinscal::LogError& e) {
    sinscal::fuzz::check_message(e, f.file + ":");
  } catch (const std::exception& e) {
    finding("not a LogError", e.what());
  }
  return 0;
}
