// libFuzzer target: LogReader over an std::istream in the native format (rig/io/log_io.hpp). Input:
// one option byte (bit 0: skip bad samples), then the log text. Every error is a LogError naming
// the file; every sample read is finite and moves time forward.
#include <cmath>
#include <sstream>

#include "fuzz_log.hpp"
#include "rig/io/log_io.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::fuzz::finding;
  if (size < 1) return 0;
  const bool skip = (data[0] & 1) != 0;
  std::istringstream in(sinscal::fuzz::text_of(data + 1, size - 1));
  const std::string name = "fuzz.csv";
  try {
    sinscal::LogReader reader(in, sinscal::LogFormat::native_format(name, 100.0));
    if (skip) reader.skip_bad_samples([](const sinscal::BadSampleError&) {});
    sinscal::fuzz::read_all_samples(reader);
  } catch (const sinscal::LogError& e) {
    sinscal::fuzz::check_message(e, name + ":");
  } catch (const std::exception& e) {
    finding("not a LogError", e.what());
  }
  return 0;
}
