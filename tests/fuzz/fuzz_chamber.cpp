// libFuzzer target: the chamber files. The first byte chooses the reader: a chamber program
// (ChamberProgram::load, config/chambers/*.ini, simulate --chamber) or a chamber session
// (ChamberSoaks::load, [thermal] soaks, sinscal thermal); the rest is the file. Every error is a
// ConfigError whose message starts with the file's path; what loads is finite and bounded (a
// ramp's duration, a soak's temperature, the tolerance).
#include <cmath>

#include "filter/thermal/soak_run.hpp"
#include "fuzz_support.hpp"
#include "models/config.hpp"
#include "rig/thermal.hpp"

namespace {

void program(const std::string& path) {
  using sinscal::fuzz::finding;
  const sinscal::ChamberProgram p = sinscal::ChamberProgram::load(path);
  for (double c : p.soaks_c)
    if (!std::isfinite(c)) finding("a soak temperature is not finite", std::to_string(c));
  if (!std::isfinite(p.settle_s + p.start_c + p.air_rate_c_per_s) || !(p.air_rate_c_per_s > 0.0))
    finding("the program's settling, start or air rate is not finite", path);
  if (p.type == sinscal::ChamberProgram::Type::Ramp &&
      !(std::isfinite(p.ramp_duration()) && p.ramp_duration() >= 0.0))
    finding("the ramp's duration is not finite", std::to_string(p.ramp_duration()));
}

void soaks(const std::string& path) {
  using sinscal::fuzz::finding;
  const sinscal::ChamberSoaks s = sinscal::ChamberSoaks::load(path);
  if (s.sessions.empty()) finding("a chamber session without soaks loaded", path);
  if (!(std::isfinite(s.tolerance_c) && s.tolerance_c > 0.0))
    finding("the soak tolerance is not a positive number", std::to_string(s.tolerance_c));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string path = sinscal::fuzz::work_dir() + "/chamber.ini";
  sinscal::fuzz::write_file(path, sinscal::fuzz::text_of(data + 1, size - 1));
  try {
    if ((data[0] & 1) != 0)
      soaks(path);
    else
      program(path);
  } catch (const sinscal::ConfigError& e) {
    sinscal::fuzz::check_message(e, path);
  } catch (const std::exception& e) {
    sinscal::fuzz::finding("not a ConfigError", e.what());
  }
  return 0;
}
