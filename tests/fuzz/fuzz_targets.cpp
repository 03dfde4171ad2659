// libFuzzer target: the sigma targets of `design --optimize --targets` (read_sigma_targets,
// models/sensor_profile.hpp): the first byte chooses a [targets] file or the inline form
// ("family = value unit; ..." made a [targets] section as apps/cmd_design.cpp does). Every error is
// a ConfigError whose message starts with the name; every target read is a finite number > 0 of a
// known family.
#include <cmath>

#include "fuzz_support.hpp"
#include "models/coefficient_families.hpp"
#include "models/config.hpp"
#include "models/sensor_profile.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::fuzz::finding;
  if (size < 1) return 0;
  const bool inline_form = (data[0] & 1) != 0;
  const std::string name = inline_form ? "--targets" : "targets.ini";
  std::string text = sinscal::fuzz::text_of(data + 1, size - 1);
  if (inline_form) {
    std::string ini = "[targets]\n";
    for (char c : text) ini += c == ';' ? '\n' : c;
    text = ini;
  }
  try {
    for (const auto& [family, sigma] : sinscal::read_sigma_targets(sinscal::IniFile(name, text))) {
      sinscal::coefficient_family_info(family);  // throws std::invalid_argument: a finding
      if (!(std::isfinite(sigma) && sigma > 0.0))
        finding("a target is not a finite number > 0", family + " " + std::to_string(sigma));
    }
  } catch (const sinscal::ConfigError& e) {
    sinscal::fuzz::check_message(e, name);
  } catch (const std::exception& e) {
    finding("not a ConfigError", e.what());
  }
  return 0;
}
