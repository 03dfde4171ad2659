// libFuzzer target: LogReader over an std::istream in NovAtel RAWIMUSA / RAWIMUSXA ASCII format
// (rig/io/log_io.hpp). Input: one option byte (bit 0: skip bad samples; bit 1: check the IMU status
// against a mask; bit 2: a 200 Hz nominal rate), then the log text. Every error is a LogError
// naming the file; every sample read is finite and moves time forward.
#include <cmath>
#include <sstream>

#include "fuzz_log.hpp"
#include "models/units.hpp"
#include "rig/io/log_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::fuzz::finding;
  if (size < 1) return 0;
  const unsigned a = data[0];
  sinscal::LogFormat f;
  f.file = "fuzz.asc";
  f.kind = sinscal::LogFormat::Kind::NovAtel;
  f.native = false;
  f.header_lines = 0;
  f.rate_hz = (a & 4) != 0 ? 200.0 : 100.0;
  f.gyro.increments = f.accel.increments = true;
  f.gyro.scale = 9.5367431640625e-07 * sinscal::units::arcsec;  // 2^-20 arcsec per count
  f.accel.scale = 1.862645149230957e-09;                        // 2^-29 m/s per count
  if ((a & 2) != 0) f.status_mask = 0x00000ff0;
  std::istringstream in(sinscal::fuzz::text_of(data + 1, size - 1));
  try {
    sinscal::LogReader reader(in, f);
    if ((a & 1) != 0) reader.skip_bad_samples([](const sinscal::BadSampleError&) {});
    sinscal::fuzz::read_all_samples(reader);
  } catch (const sinscal::LogError& e) {
    sinscal::fuzz::check_message(e, f.file + ":");
  } catch (const std::exception& e) {
    finding("not a LogError", e.what());
  }
  return 0;
}
