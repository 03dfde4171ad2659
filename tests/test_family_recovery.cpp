// Every extended family of the family table is recovered by the Kalman filter: rot19 simulated
// with the base FOG profile plus that family (a range well above its detection sigma), calibrated
// with the same profile, one seeded run: the family's coefficients within 3 sigma of the truth,
// every other estimated coefficient within 4 sigma. A family added to the table without a range
// here fails the test.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

#include "filter/kalman/kalman_calibrator.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "rig/thermal.hpp"

using namespace sinscal;

namespace {
// The profile line that gives each extended family a range, by family.
const std::map<std::string, std::pair<std::string, std::string>> kRanges = {
    {"accel.k2", {"accel", "k2 = 10 30 ug/g^2"}},
    {"gyro.scale_asym", {"gyro", "scale_asym = 5 20 ppm"}},
    {"accel.scale_asym", {"accel", "scale_asym = 5 20 ppm"}},
    {"gyro.g_sensitivity", {"gyro", "g_sensitivity = 0.2 0.5 deg/h/g"}},
    {"accel.lever_arm", {"accel", "lever_arm = 10 60 mm"}},
    {"time_delay", {"timing", "time_delay = 5 ms"}},
    // (The table base heading estimated, the gyro drift sigma is ~0.22 deg/h/h on rot19.)
    {"gyro.bias_drift", {"gyro", "bias_drift = 1.5 3 deg/h/h"}},
    {"accel.bias_drift", {"accel", "bias_drift = 200 400 ug/h"}},
    // Thermal families, a FOG unit's size, on rot19 repeated while the chamber ramps from -10 to
    // 50 C at 1 C/min (T0 = 20 C in the middle, the sensor lagging by 300 s).
    {"gyro.bias_temp1", {"gyro", "bias_temp1 = 0.005 0.01 deg/h/C"}},
    {"gyro.bias_temp2", {"gyro", "bias_temp2 = 2e-4 5e-4 deg/h/C^2"}},
    {"gyro.bias_temp3", {"gyro", "bias_temp3 = 1e-5 2e-5 deg/h/C^3"}},
    {"accel.bias_temp1", {"accel", "bias_temp1 = 5 10 ug/C"}},
    {"accel.bias_temp2", {"accel", "bias_temp2 = 0.2 0.5 ug/C^2"}},
    {"accel.bias_temp3", {"accel", "bias_temp3 = 0.01 0.02 ug/C^3"}},
    {"gyro.scale_temp1", {"gyro", "scale_temp1 = 0.5 1 ppm/C"}},
    {"gyro.scale_temp2", {"gyro", "scale_temp2 = 0.02 0.05 ppm/C^2"}},
    {"gyro.scale_temp3", {"gyro", "scale_temp3 = 0.001 0.002 ppm/C^3"}},
    {"accel.scale_temp1", {"accel", "scale_temp1 = 0.5 1 ppm/C"}},
    {"accel.scale_temp2", {"accel", "scale_temp2 = 0.02 0.05 ppm/C^2"}},
    {"accel.scale_temp3", {"accel", "scale_temp3 = 0.001 0.002 ppm/C^3"}},
    {"gyro.misalignment_temp1", {"gyro", "misalignment_temp1 = 0.5 1 arcsec/C"}},
    {"accel.misalignment_temp1", {"accel", "misalignment_temp1 = 0.5 1 arcsec/C"}},
    {"gyro.bias_temp_rate", {"gyro", "bias_temp_rate = 0.1 0.2 deg/h/(C/min)"}},
};

// rot19 repeated while a chamber ramps (the thermal families' session).
const char* const kRamp =
    "[chamber]\ntype = ramp\nstart = -10 C\nfrom = -10 C\nto = 50 C\nrate = 1 C/min\n"
    "settle = 3600 s\n";

// nav-fog.ini with one more line in the given section.
std::string profile_with(const std::string& section, const std::string& line) {
  std::ifstream in(test::source_path("config/sensors/nav-fog.ini"));
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const std::string header = "[" + section + "]\n";
  const auto at = s.find(header);
  if (at == std::string::npos)
    s += "\n" + header + line + "\n";
  else
    s.insert(at + header.size(), line + "\n");
  return s;
}
}  // namespace

TEST_CASE("Every extended family is recovered by the Kalman filter within 3 sigma on rot19",
          "[long][kalman][families]") {
  const Plan p = test::load_plan("rot19.ini");
  const Motion m = build_motion(p, p.site);
  const std::string dir = test::temp_dir("family_recovery");
  const auto& cat = coefficient_catalog();
  for (const auto& f : coefficient_families()) {
    if (f.base) continue;
    CAPTURE(f.name);
    REQUIRE(kRanges.count(f.name) == 1);
    const auto& [section, line] = kRanges.at(f.name);
    const std::string path = dir + "/" + f.name + ".ini";
    test::write_file(path, profile_with(section, line) +
                               (f.thermal() ? "\n[thermal]\nreference_temperature = 20 C\n" : ""));
    const SensorProfile prof = SensorProfile::load(path);
    REQUIRE(prof.has(f.name));
    const ImuErrorModel truth = prof.draw(derive_seed(7, 1));
    std::optional<Plan> repeated;
    std::optional<Motion> ramp_motion;
    std::optional<SensorTemperature> temperature;
    if (f.thermal()) {
      test::write_file(dir + "/ramp.ini", kRamp);
      const ChamberProgram chamber = ChamberProgram::load(dir + "/ramp.ini");
      std::string text = p.text;
      text.insert(text.find("[plan]\n") + 7,
                  "repeat = " +
                      std::to_string(
                          static_cast<int>(std::ceil(chamber.ramp_duration() / m.duration()) + 1)) +
                      "\n");
      repeated = Plan::parse(p.path, text);
      ramp_motion.emplace(build_motion(*repeated, repeated->site));
      temperature.emplace(chamber.ramp_air(), 300.0);
    }
    const Plan& plan = repeated ? *repeated : p;
    const auto samples = test::simulate(ramp_motion ? *ramp_motion : m, truth, 100.0, &prof.noise,
                                        derive_seed(7, 2), temperature ? &*temperature : nullptr);
    CalibratorOptions o = calibrator_options_from_profile(prof);
    Calibrator kf(test::timeline(plan), plan.site, o);
    const auto est = test::run_filter(kf, samples);
    REQUIRE(kf.layout().block(f.name) != nullptr);
    const Eigen::VectorXd theta = truth.vector();
    int family_coefficients = 0;
    for (std::size_t c = 0; c < cat.size(); ++c) {
      if (est[c].status != CoefficientEstimate::Status::Estimated) continue;
      const double z = (est[c].value - theta(static_cast<Eigen::Index>(c))) / est[c].sigma;
      CAPTURE(cat[c].name, est[c].value, theta(static_cast<Eigen::Index>(c)), est[c].sigma, z);
      if (cat[c].family == f.name) {
        ++family_coefficients;
        CHECK(std::abs(z) < 3.0);
        // Recovered, not left at the prior: the data determine it (the injected value is many
        // sigma away from zero).
        CHECK(est[c].observed());
        CHECK(std::abs(theta(static_cast<Eigen::Index>(c))) > 5.0 * est[c].sigma);
      } else {
        CHECK(std::abs(z) < 4.0);
      }
    }
    CHECK(family_coefficients == f.size());
  }
}
