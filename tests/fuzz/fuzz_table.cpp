// libFuzzer target: the table description, TableSpec::parse(name, text) (rig/table_spec.hpp,
// config/tables/*.ini). Every error is a ConfigError whose message starts with the file name; a
// table that loads has finite, positive limits.
#include <cmath>

#include "fuzz_support.hpp"
#include "models/config.hpp"
#include "rig/table_spec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::fuzz::finding;
  const std::string name = "fuzz_table.ini";
  try {
    const sinscal::TableSpec t =
        sinscal::TableSpec::parse(name, sinscal::fuzz::text_of(data, size));
    if (!(std::isfinite(t.max_rate) && t.max_rate > 0.0 && std::isfinite(t.max_acceleration) &&
          t.max_acceleration > 0.0))
      finding("a table's rate or acceleration is not a positive number", t.name);
    if (!(std::isfinite(t.settling_time) && t.settling_time >= 0.0 &&
          std::isfinite(t.attitude_sigma) && t.attitude_sigma >= 0.0))
      finding("a table's settling time or attitude accuracy is not a number >= 0", t.name);
    if (t.axes != 2 && t.axes != 3) finding("a table with neither 2 nor 3 axes", t.name);
  } catch (const sinscal::ConfigError& e) {
    sinscal::fuzz::check_message(e, name);
  } catch (const std::exception& e) {
    finding("not a ConfigError", e.what());
  }
  return 0;
}
