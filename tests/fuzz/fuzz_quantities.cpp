// libFuzzer target: parse_quantities (models/config.hpp). Input: a kind selector byte, then the
// quantity text. Every result is finite; every error is a ConfigError.
#include <cmath>

#include "fuzz_support.hpp"
#include "models/config.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using sinscal::QuantityKind;
  if (size < 1) return 0;
  static const QuantityKind kinds[] = {QuantityKind::Angle,
                                       QuantityKind::AngularRate,
                                       QuantityKind::AngularAcceleration,
                                       QuantityKind::Acceleration,
                                       QuantityKind::Length,
                                       QuantityKind::Time,
                                       QuantityKind::Frequency,
                                       QuantityKind::Ratio,
                                       QuantityKind::AngleRandomWalk,
                                       QuantityKind::VelocityRandomWalk,
                                       QuantityKind::RateRandomWalk,
                                       QuantityKind::AccelRandomWalk,
                                       QuantityKind::GSensitivity,
                                       QuantityKind::QuadraticScale,
                                       QuantityKind::Velocity};
  static const char* const default_units[] = {
      "deg",         "deg/h",       "deg/s^2",       "ug",         "mm",      "s",      "Hz", "ppm",
      "deg/sqrt(h)", "ug/sqrt(Hz)", "deg/h/sqrt(h)", "ug/sqrt(h)", "deg/h/g", "ug/g^2", "m/s"};
  const std::size_t k = data[0] % (sizeof kinds / sizeof kinds[0]);
  const std::string text = sinscal::fuzz::text_of(data + 1, size - 1);
  try {
    for (double v : sinscal::parse_quantities(text, kinds[k], default_units[k]))
      if (!std::isfinite(v)) sinscal::fuzz::finding("a quantity is not finite", text);
  } catch (const sinscal::ConfigError&) {
  } catch (const std::exception& e) {
    sinscal::fuzz::finding("not a ConfigError", e.what());
  }
  return 0;
}
