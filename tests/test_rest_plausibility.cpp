// The plausibility gate of sessions without a table (filter/plausibility/rest_plausibility.hpp):
// a clean MEMS rest passes every check; each bound fails on its own side just beyond it and
// passes just inside; wrong units, swapped triads and one signal in both triads are named.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "filter/plausibility/rest_plausibility.hpp"
#include "helpers.hpp"
#include "models/earth.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"

using namespace sinscal;

namespace {

constexpr double kG = 9.80665;
constexpr double kDt = 0.01;  // s: 100 Hz
constexpr std::size_t kCount = 1000;

// A rest of kCount readings: means `f`, `w` plus white noise of densities `accel_density`
// (m/s/sqrt(s)) and `gyro_density` (rad/sqrt(s)).
std::vector<ImuReading> rest(const Eigen::Vector3d& f, const Eigen::Vector3d& w,
                             double accel_density, double gyro_density, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<ImuReading> r(kCount);
  for (std::size_t k = 0; k < kCount; ++k) {
    r[k].t = static_cast<double>(k) * kDt;
    r[k].accel = f + accel_density / std::sqrt(kDt) * Eigen::Vector3d(n(rng), n(rng), n(rng));
    r[k].gyro = w + gyro_density / std::sqrt(kDt) * Eigen::Vector3d(n(rng), n(rng), n(rng));
  }
  return r;
}

// A consumer MEMS unit's white noise: 0.5 deg/sqrt(h), 300 ug/sqrt(Hz).
const double kGyroNoise = 0.5 * units::deg_per_sqrt_h;
const double kAccelNoise = 300.0 * units::ug_per_sqrt_hz;
const Eigen::Vector3d kUp(0.1, -0.2, 0.97);

PlausibilityReport gate(const std::vector<ImuReading>& r, const RestLimits& l) {
  return check_rests({rest_statistics(r, 0, r.size() - 1, "pose 1")}, kG, l, "imu.csv");
}

const PlausibilityCheck& named(const PlausibilityReport& report, const std::string& name) {
  for (const auto& c : report.checks)
    if (c.name == name) return c;
  FAIL("no check " << name);
  return report.checks.front();
}

}  // namespace

TEST_CASE("Rest gate: a clean MEMS rest passes, its noise measured", "[plausibility]") {
  const RestLimits l = RestLimits::from_profile(nullptr);
  const auto r =
      rest(kG * kUp.normalized(), Eigen::Vector3d(0.02, -0.05, 0.03), kAccelNoise, kGyroNoise);
  const RestStatistics s = rest_statistics(r, 0, r.size() - 1, "pose 1");
  for (int i = 0; i < 3; ++i) {
    // The differences' estimate of the density: within 10 % for 1000 readings (sigma 3 %).
    CHECK(s.gyro_density(i) == Approx(kGyroNoise).epsilon(0.1));
    CHECK(s.accel_density(i) == Approx(kAccelNoise).epsilon(0.1));
  }
  const PlausibilityReport report = gate(r, l);
  CHECK(report.passed());
  CHECK_THAT(named(report, "noise").detail, Catch::Contains("deg/sqrt(h)"));
  CHECK(check_same_signal(r, l, "imu.csv").passed);
  CHECK(check_fit(30.0, l, "imu.csv", "fit").passed);
}

TEST_CASE("Rest gate: each bound fails just beyond it, on both sides", "[plausibility]") {
  const RestLimits l = RestLimits::from_profile(nullptr);
  // A noise far below the bounds' noise terms, so the bounds are the limits' own.
  const double quiet_a = l.accel_noise_lo * 1.5, quiet_g = l.gyro_noise_lo * 1.5;
  SECTION("gravity magnitude, above and below") {
    for (const double sign : {1.0, -1.0}) {
      const double inside = kG + sign * 0.95 * l.specific_force;
      const double beyond = kG + sign * 1.05 * l.specific_force;
      CHECK(
          named(gate(rest(inside * kUp.normalized(), Eigen::Vector3d::Zero(), quiet_a, quiet_g), l),
                "gravity magnitude")
              .passed);
      CHECK_FALSE(
          named(gate(rest(beyond * kUp.normalized(), Eigen::Vector3d::Zero(), quiet_a, quiet_g), l),
                "gravity magnitude")
              .passed);
    }
  }
  SECTION("rate at rest: the bias bound plus the Earth rate") {
    const double Omega = Earth::wgs84().rate();
    const Eigen::Vector3d axis = Eigen::Vector3d(1, 2, -2).normalized();
    CHECK(named(gate(rest(kG * kUp.normalized(), 0.95 * (l.gyro_bias + Omega) * axis, quiet_a,
                          quiet_g),
                     l),
                "rate at rest")
              .passed);
    CHECK_FALSE(named(gate(rest(kG * kUp.normalized(), 1.05 * (l.gyro_bias + Omega) * axis, quiet_a,
                                quiet_g),
                           l),
                      "rate at rest")
                    .passed);
  }
  SECTION("noise band, below and above, each triad") {
    const Eigen::Vector3d f = kG * kUp.normalized(), w = Eigen::Vector3d::Zero();
    CHECK(
        named(gate(rest(f, w, l.accel_noise_lo * 1.3, l.gyro_noise_lo * 1.3), l), "noise").passed);
    CHECK(
        named(gate(rest(f, w, l.accel_noise_hi * 0.7, l.gyro_noise_hi * 0.7), l), "noise").passed);
    CHECK_FALSE(named(gate(rest(f, w, l.accel_noise_lo * 0.7, quiet_g), l), "noise").passed);
    CHECK_FALSE(named(gate(rest(f, w, quiet_a, l.gyro_noise_lo * 0.7), l), "noise").passed);
    CHECK_FALSE(named(gate(rest(f, w, quiet_a, l.gyro_noise_hi * 1.3), l), "noise").passed);
    CHECK_FALSE(named(gate(rest(f, w, l.accel_noise_hi * 1.3, quiet_g), l), "noise").passed);
  }
  SECTION("fit: chi2 per dof against its bound") {
    CHECK(check_fit(0.99 * l.max_fit_chi2_per_dof, l, "imu.csv", "fit").passed);
    const PlausibilityCheck c = check_fit(1.01 * l.max_fit_chi2_per_dof, l, "imu.csv", "fit");
    CHECK_FALSE(c.passed);
    CHECK_THAT(c.detail, Catch::Contains("not converged"));
  }
}

TEST_CASE("Rest gate: wrong units, swapped triads and one signal are named", "[plausibility]") {
  const RestLimits l = RestLimits::from_profile(nullptr);
  const Eigen::Vector3d f = kG * kUp.normalized(), w(0.03, 0.05, -0.04);  // rad/s: 3.9 deg/s
  auto scaled = [&](double accel, double gyro) {
    auto r = rest(f, w, kAccelNoise, kGyroNoise);
    for (auto& x : r) {
      x.accel *= accel;
      x.gyro *= gyro;
    }
    return gate(r, l);
  };
  SECTION("gyro data in deg/s declared rad/s") {
    const PlausibilityReport r = scaled(1.0, 1.0 / units::deg);
    CHECK_FALSE(named(r, "rate at rest").passed);
    CHECK_THAT(r.failures(), Catch::Contains("values in deg declared as rad"));
  }
  SECTION("accelerometer data in mm/s^2 declared m/s^2, in g declared m/s^2") {
    CHECK_THAT(scaled(1000.0, 1.0).failures(), Catch::Contains("mm/s"));
    CHECK_THAT(scaled(1.0 / kG, 1.0).failures(), Catch::Contains("values in g declared"));
  }
  SECTION("the triads swapped") {
    auto r = rest(f, w, kAccelNoise, kGyroNoise);
    for (auto& x : r) std::swap(x.accel, x.gyro);
    const PlausibilityReport report = gate(r, l);
    CHECK_FALSE(named(report, "gravity magnitude").passed);
    CHECK_THAT(report.failures(), Catch::Contains("swapped"));
  }
  SECTION("the triads swapped in counts of other scales: told by the rests' directions") {
    // Five poses: gravity turns in the body, the biases stay; swapped, each triad read with the
    // other's scale (as two files of raw counts given the wrong way round).
    const Eigen::Vector3d ups[] = {{0, 0, 1}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}, {0.6, 0, 0.8}};
    std::vector<RestStatistics> rests;
    for (const auto& u : ups) {
      auto r = rest(kG * u, w, kAccelNoise, kGyroNoise);
      for (auto& x : r) {
        const Eigen::Vector3d a = x.accel;
        x.accel = 12.0 * x.gyro;
        x.gyro = a / 12.0;
      }
      rests.push_back(rest_statistics(r, 0, r.size() - 1, "pose"));
    }
    const PlausibilityReport report = check_rests(rests, kG, l, "acc.txt");
    CHECK_FALSE(named(report, "gravity magnitude").passed);
    CHECK_THAT(report.failures(), Catch::Contains("swapped: the gyros' mean turns"));
    // The same poses the right way round pass.
    std::vector<RestStatistics> right;
    for (const auto& u : ups) {
      const auto r = rest(kG * u, w, kAccelNoise, kGyroNoise);
      right.push_back(rest_statistics(r, 0, r.size() - 1, "pose"));
    }
    CHECK(check_rests(right, kG, l, "acc.txt").passed());
  }
  SECTION("one signal in both triads; a strong but imperfect correlation is not") {
    auto r = rest(f, w, kAccelNoise, kGyroNoise);
    auto same = r;
    for (auto& x : same) x.gyro = x.accel / 12.0;
    const PlausibilityCheck c = check_same_signal(same, l, "acc.txt");
    CHECK_FALSE(c.passed);
    CHECK_THAT(c.detail, Catch::Contains("same file given for both triads"));
    // Correlation about 0.995: the gyro half the accelerometer's signal, a tenth its own noise.
    std::mt19937 rng(5);
    std::normal_distribution<double> n(0.0, 1.0);
    for (auto& x : r) {
      const double k = kAccelNoise / std::sqrt(kDt);
      x.gyro = 0.5 * x.accel + 0.05 * k * Eigen::Vector3d(n(rng), n(rng), n(rng));
    }
    CHECK(check_same_signal(r, l, "acc.txt").passed);
  }
}

TEST_CASE("Rest gate: bounds from a sensor profile", "[plausibility]") {
  const SensorProfile p = SensorProfile::load(test::source_path("config/sensors/mems.ini"));
  const RestLimits l = RestLimits::from_profile(&p);
  const PlausibilityLimits t = PlausibilityLimits::from_profile(&p);
  CHECK(l.gyro_bias == Approx(t.rate));
  CHECK(l.specific_force == Approx(t.specific_force));
  CHECK(l.gyro_noise_lo == Approx(p.noise.gyro.white / 2.0));
  CHECK(l.gyro_noise_hi == Approx(p.noise.gyro.white * 10.0));
  CHECK(l.accel_noise_lo == Approx(p.noise.accel.white / 2.0));
  CHECK(l.accel_noise_hi == Approx(p.noise.accel.white * 10.0));
  CHECK_THAT(l.source, Catch::Contains("mems"));
  // The generic bounds admit the MEMS profile's largest errors.
  const RestLimits g = RestLimits::from_profile(nullptr);
  CHECK(g.gyro_bias > std::sqrt(3.0) * 0.5 * units::deg_per_s);
  CHECK(g.specific_force > std::sqrt(3.0) * 0.040 * units::g0 + 0.01 * units::g0);
}
