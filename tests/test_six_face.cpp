// The six-face and known-turn calibration (filter/six_face/six_face.hpp) on simulated Ferraris
// sessions (rig/ferraris.hpp).
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "filter/six_face/six_face.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/sensor_profile.hpp"
#include "rig/ferraris.hpp"
#include "rig/imu_sim.hpp"
#include "rig/session.hpp"

using namespace sinscal;

namespace {

struct Run {
  ImuErrorModel truth;
  SixFaceResult result;
};

// A MEMS unit (the profile's base terms; its extended terms zero unless `keep_extended`) on a
// simulated Ferraris session at 100 Hz, calibrated with the session's own accuracies declared.
Run run_session(std::uint64_t seed, const FerrarisOptions& fo, bool keep_g_sensitivity = false,
                bool g_sensitivity_test = false, double g_scale = 1.0) {
  const SensorProfile prof = SensorProfile::load(test::source_path("config/sensors/mems.ini"));
  Site site;
  site.lat_rad = 49.6 * units::deg;
  site.h_m = 280.0;
  const FerrarisSession session = ferraris_session(site, fo, seed);
  Run r;
  r.truth = prof.draw(seed + 17);
  r.truth.accel.k2.setZero();
  if (keep_g_sensitivity)
    r.truth.gyro_g_sensitivity *= g_scale;
  else
    r.truth.gyro_g_sensitivity.setZero();
  SimulatorOptions so;
  so.rate_hz = 100.0;
  so.noise_seed = seed + 31;
  ImuSimulator sim(session.motion, r.truth, prof.noise, so);
  PartAccumulator parts({"x_rot", "y_rot", "z_rot"});
  ImuSample s;
  while (sim.next(s)) parts.push(s, session.label_at(s.t - 0.5 * s.dt));
  SixFaceOptions o;
  o.site = site;
  o.declared.face_accuracy = fo.face_tilt;
  o.declared.turn_accuracy = fo.turn_angle_error;
  o.gyro_bias_instability = prof.noise.gyro.bias_instability;
  o.accel_bias_instability = prof.noise.accel.bias_instability;
  o.g_sensitivity = g_sensitivity_test;
  r.result = six_face_calibrate(parts.parts(), o);
  return r;
}

double truth_of(const ImuErrorModel& m, const std::string& name) {
  const auto& cat = coefficient_catalog();
  const Eigen::VectorXd v = m.vector();
  for (std::size_t i = 0; i < cat.size(); ++i)
    if (cat[i].name == name) return v(static_cast<Eigen::Index>(i));
  FAIL("no coefficient " << name);
  return 0.0;
}

}  // namespace

TEST_CASE("Six-face: a simulated Ferraris session calibrates every base coefficient",
          "[six_face]") {
  const Run r = run_session(3, FerrarisOptions{});
  REQUIRE(r.result.coefficients.size() == 24);
  for (const auto& c : r.result.coefficients) {
    const double err = c.value - truth_of(r.truth, c.name);
    CAPTURE(c.name, c.value, err, c.sigma);
    CHECK(c.sigma > 0.0);
    CHECK(std::abs(err) < 4.0 * c.sigma);
  }
  // The turns' calibrated angles are the declared one within the hand's error.
  for (const auto& t : r.result.turns) CHECK(std::abs(t.angle - 2.0 * M_PI) < 4.0 * units::deg);
  CHECK(r.result.undetermined.size() >= 3);
}

TEST_CASE("Six-face: Monte Carlo, errors as the sigmas say", "[six_face][long]") {
  // Per family, the RMS over seeds and components of error / sigma within 0.8-1.25, and at most
  // 1 % of the coefficients beyond 3 sigma.
  const char* env = std::getenv("SINSCAL_SIX_FACE_SEEDS");
  const int seeds = env ? std::atoi(env) : 30;
  FerrarisOptions fo;
  if (const char* tremor = std::getenv("SINSCAL_SIX_FACE_TREMOR"))  // deg, 1-sigma
    fo.tremor = std::atof(tremor) * units::deg;
  std::map<std::string, std::pair<double, int>> sum;
  int beyond = 0, total = 0;
  for (int k = 0; k < seeds; ++k) {
    const Run r = run_session(100 + static_cast<std::uint64_t>(k), fo);
    for (const auto& c : r.result.coefficients) {
      const double z = (c.value - truth_of(r.truth, c.name)) / c.sigma;
      const std::string family = c.name.substr(0, c.name.rfind('.'));
      sum[family].first += z * z;
      ++sum[family].second;
      beyond += std::abs(z) > 3.0;
      ++total;
    }
  }
  for (const auto& [family, s] : sum) {
    const double rms = std::sqrt(s.first / s.second);
    WARN(family << ": RMS error / sigma " << rms << " over " << s.second);
    CHECK(rms > 0.8);
    CHECK(rms < 1.25);
  }
  WARN(beyond << " of " << total << " beyond 3 sigma");
  CHECK(beyond <= total / 100 + 1);
}

TEST_CASE("Six-face: imucal's recording against its stored calibration", "[six_face][real]") {
  // data/imucal: the sensitivities (counts per unit along each sensor's own axis) within
  // 0.1 % (accelerometers) and 0.5 % (gyros) of imucal's, as the issue asks; the biases within
  // their sigma's reach. Measured: 0.004-0.012 % and 0.009-0.050 %.
  const Session s = Session::load(test::source_path("config/measured/imucal-ferraris/session.ini"),
                                  Session::PlanNeed::Optional);
  REQUIRE(s.six_face);
  const SixFaceResult r = six_face_calibrate(read_parts(s), six_face_options(s));
  const nlohmann::json ref =
      nlohmann::json::parse(std::ifstream(test::source_path("data/imucal/example_cal.json")));
  const Eigen::Matrix3d A = r.model.accel.linear(), G = r.model.gyro.linear();
  for (int i = 0; i < 3; ++i) {
    const double ka = A.row(i).norm() / s.log.accel.scale;              // counts per m/s^2
    const double kg = G.row(i).norm() / s.log.gyro.scale * units::deg;  // counts per deg/s
    CAPTURE(i, ka, kg);
    CHECK(ka == Approx(ref["K_a"][i][i].get<double>()).epsilon(1e-3));
    CHECK(kg == Approx(ref["K_g"][i][i].get<double>()).epsilon(5e-3));
    const double ba = s.log.accel.offset + r.model.accel.bias(i) / s.log.accel.scale;
    CHECK(std::abs(ba - ref["b_a"][i].get<double>()) < 1.0);  // counts (sigma 0.2-0.3)
  }
  for (const auto& t : r.turns) CHECK(std::abs(t.angle - 2.0 * M_PI) < 0.1 * units::deg);
}

TEST_CASE("Six-face: a hidden gyro g-sensitivity is found on the rests, none is not",
          "[six_face][diagnosis]") {
  // The MEMS profile's g-sensitivity (0.01-0.1 deg/s/g per term) hidden in the session: the test
  // names it and every term is within 4 sigma of the truth; with none hidden it stays silent and
  // states its detection limit; hidden at a tenth of its size (near that limit) the estimate is
  // still within 4 sigma, whatever the verdict.
  // The faces rest on a table (no tremor): with a hand's 0.02 deg tremor the rests' means carry
  // its net turns and the detection limit rises to 5.0e-5 rad/s per m/s^2 (100 deg/h/g), above
  // the profile's smallest term.
  FerrarisOptions still;
  still.tremor = 0.0;
  const Run hidden = run_session(5, still, true, true);
  REQUIRE(hidden.result.g_test);
  const GSensitivityTest& t = *hidden.result.g_test;
  CAPTURE(t.statistic, t.p_value, t.detection_limit);
  CHECK(t.significant);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      CAPTURE(i, j, t.K(i, j), hidden.truth.gyro_g_sensitivity(i, j), t.K_sigma(i, j));
      CHECK(std::abs(t.K(i, j) - hidden.truth.gyro_g_sensitivity(i, j)) < 4.0 * t.K_sigma(i, j));
    }
  // The base terms stay right with K estimated.
  for (const auto& c : hidden.result.coefficients)
    CHECK(std::abs(c.value - truth_of(hidden.truth, c.name)) < 4.0 * c.sigma);
  const Run none = run_session(5, still, false, true);
  CHECK_FALSE(none.result.g_test->significant);
  CHECK(none.result.g_test->detection_limit > 0.0);
  CHECK(none.result.g_test->detection_limit <
        0.01 * units::deg_per_s / 9.80665);  // below the profile's smallest term
  const Run weak = run_session(5, still, true, true, 0.1);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      CHECK(std::abs(weak.result.g_test->K(i, j) - weak.truth.gyro_g_sensitivity(i, j)) <
            4.0 * weak.result.g_test->K_sigma(i, j));
}
