// libFuzzer target: the plan loader, Plan::parse(name, text) (rig/plan.hpp). Every error is a
// ConfigError whose message starts with the file name; a plan that loads has finite values.
#include <cmath>

#include "fuzz_support.hpp"
#include "models/config.hpp"
#include "rig/plan.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::fuzz::finding;
  const std::string name = "fuzz_plan.ini";
  const std::string text = sinscal::fuzz::text_of(data, size);
  try {
    const sinscal::Plan plan = sinscal::Plan::parse(name, text);
    for (const auto& o : plan.orientations)
      if (!std::isfinite(o.angles.heading + o.angles.pitch + o.angles.roll + o.dwell))
        finding("an orientation is not finite", o.label);
    for (const auto& s : plan.steps)
      if (!std::isfinite(s.angle + s.duration + s.rate + s.pause))
        finding("a step is not finite", s.axis_name);
  } catch (const sinscal::ConfigError& e) {
    sinscal::fuzz::check_message(e, name);
  } catch (const std::exception& e) {
    finding("not a ConfigError", e.what());
  }
  return 0;
}
