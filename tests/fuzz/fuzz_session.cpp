// libFuzzer target: Session::load (rig/session.hpp). The input is a session.ini in a directory
// that also holds a copy of the bundled seed8 plan as plan.ini (the seed corpus names it). Every
// error is a ConfigError whose message starts with a file's path in that directory.
#include "fuzz_support.hpp"
#include "models/config.hpp"
#include "rig/session.hpp"

#ifndef SINSCAL_SOURCE_DIR
#error "SINSCAL_SOURCE_DIR must name the source tree (for config/plans/seed8.ini)"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string dir = [] {
    const std::string d = sinscal::fuzz::work_dir() + "/session";
    std::filesystem::create_directories(d);
    std::filesystem::copy_file(std::string(SINSCAL_SOURCE_DIR) + "/config/plans/seed8.ini",
                               d + "/plan.ini", std::filesystem::copy_options::overwrite_existing);
    return d;
  }();
  const std::string path = dir + "/session.ini";
  sinscal::fuzz::write_file(path, sinscal::fuzz::text_of(data, size));
  try {
    sinscal::Session::load(path);
  } catch (const sinscal::ConfigError& e) {
    sinscal::fuzz::check_message(e, dir + "/");
  } catch (const std::exception& e) {
    sinscal::fuzz::finding("not a ConfigError", e.what());
  }
  return 0;
}
