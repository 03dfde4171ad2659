// libFuzzer target: SensorProfile::load (models/sensor_profile.hpp), which takes a path: the input
// is written to a file first. Every error is a ConfigError whose message starts with the path.
#include "fuzz_support.hpp"
#include "models/config.hpp"
#include "models/sensor_profile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = sinscal::fuzz::work_dir() + "/sensor.ini";
  sinscal::fuzz::write_file(path, sinscal::fuzz::text_of(data, size));
  try {
    const sinscal::SensorProfile p = sinscal::SensorProfile::load(path);
    p.draw(1);
  } catch (const sinscal::ConfigError& e) {
    sinscal::fuzz::check_message(e, path);
  } catch (const std::exception& e) {
    sinscal::fuzz::finding("not a ConfigError", e.what());
  }
  return 0;
}
