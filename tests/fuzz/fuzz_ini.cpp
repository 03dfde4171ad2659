// libFuzzer target: the INI parser, IniFile(path, text) (models/config.hpp), and its getters on
// every key. Every error is a ConfigError whose message starts with the file name.
#include <climits>
#include <cmath>

#include "fuzz_support.hpp"
#include "models/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::ConfigError;
  using sinscal::fuzz::check_message;
  using sinscal::fuzz::finding;
  const std::string name = "fuzz.ini";
  const std::string text = sinscal::fuzz::text_of(data, size);
  try {
    const sinscal::IniFile ini(name, text);
    for (const auto& section : ini.sections()) {
      if (section.empty()) finding("empty section name accepted", text);
      try {
        ini.check_keys(section, {"heading", "pitch", "roll", "dwell"});
      } catch (const ConfigError& e) {
        check_message(e, name + ":");
      }
    }
    for (const auto& key : ini.keys()) {
      if (!ini.has(key) || ini.line_of(key) == 0) finding("a key without value or line", key);
      // Each getter either returns a valid value or throws a ConfigError naming file and line.
      const auto located = name + ":" + std::to_string(ini.line_of(key)) + ":";
      try {
        const double v = ini.get_double(key);
        if (!std::isfinite(v)) finding("get_double returned a non-finite value", key);
      } catch (const ConfigError& e) {
        check_message(e, located);
      }
      try {
        const int v = ini.get_int(key, 0, 0, INT_MAX);
        if (v < 0) finding("get_int returned a value below its minimum", key);
        ini.get_int(key, 0);
      } catch (const ConfigError& e) {
        check_message(e, located);
      }
      try {
        ini.get_bool(key, false);
      } catch (const ConfigError& e) {
        check_message(e, located);
      }
      try {
        for (double v : ini.get_quantities(key, sinscal::QuantityKind::Angle, "deg"))
          if (!std::isfinite(v)) finding("get_quantities returned a non-finite value", key);
      } catch (const ConfigError& e) {
        check_message(e, located);
      }
    }
    try {
      ini.get_string("plan.type");
    } catch (const ConfigError& e) {
      check_message(e, name);
    }
  } catch (const ConfigError& e) {
    check_message(e, name + ":");
  } catch (const std::exception& e) {
    finding("not a ConfigError", e.what());
  }
  return 0;
}
