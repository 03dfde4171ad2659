// Thermal calibration: the chamber's sensor temperature (first-order lag, exact), the soak fit
// (weighted least squares with the soaks' covariance, degree by test) on synthetic soaks and on
// simulated chamber sessions calibrated by the Kalman filter, and the ramp filter against it.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>

#include "catalog.hpp"
#include "filter/thermal/soak_fit.hpp"
#include "filter/thermal/soak_run.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "rig/thermal.hpp"

using namespace sinscal;

TEST_CASE("Thermal: the sensor lags the chamber's air as tau dT/dt = T_air - T", "[thermal]") {
  const ChamberAir air{{0.0, 100.0, 400.0}, {20.0, 20.0, 50.0}};  // hold, then 0.1 C/s
  const double tau = 60.0;
  const SensorTemperature T(air, tau);
  // The ODE, integrated by small Euler steps, against the closed form; and its rate.
  double t = 0.0, y = 20.0;
  const double h = 1e-3;
  double worst = 0.0, worst_rate = 0.0;
  while (t < 900.0) {
    const double dydt = (air.at(t) - y) / tau;
    worst_rate = std::max(worst_rate, std::abs(T.rate(t) - dydt));
    y += h * dydt;
    t += h;
    worst = std::max(worst, std::abs(T.at(t) - y));
  }
  CHECK(worst < 1e-3);       // C: Euler's own error at h = 1 ms
  CHECK(worst_rate < 1e-5);  // C/s
  // A ramp's steady lag is rate x tau: 0.1 C/s x 60 s = 6 C behind the air at 400 s.
  CHECK(T.at(400.0) == Approx(50.0 - 6.0 * (1.0 - std::exp(-300.0 / 60.0))).margin(1e-9));
  // And it settles on the air after the ramp.
  CHECK(T.at(400.0 + 20 * tau) == Approx(50.0).margin(1e-6));
}

TEST_CASE("Thermal: the temperature rate from readings, quantized", "[thermal]") {
  TemperatureRate r(60.0);
  double rate = 0.0;
  for (int k = 0; k <= 20000; ++k) {
    const double t = 0.01 * k;                                         // 100 Hz, 200 s
    const double c = std::round((20.0 + 0.02 * t) / 0.0625) * 0.0625;  // 1/16 C steps
    rate = r.add(t, c);
  }
  CHECK(rate == Approx(0.02).margin(0.0625 / 60.0));
}

TEST_CASE("Thermal: the soak fit recovers polynomials, their degree chosen by test", "[thermal]") {
  // Synthetic soaks: gyro.bias.x quadratic, accel.scale.y linear, gyro.scale.z constant, each
  // soak's estimates with a correlated covariance; 200 draws.
  const double T0 = 20.0;
  const std::vector<double> temps = {-40, -20, 0, 20, 40, 60};
  const std::vector<int> idx = {test::coefficient_index("gyro.bias.x"),
                                test::coefficient_index("gyro.scale.z"),
                                test::coefficient_index("accel.scale.y")};
  const double sb = 0.01 * units::deg_per_h, ss = 2 * units::ppm;
  Eigen::Matrix3d C;
  C << sb * sb, 0.5 * sb * ss, 0.0, 0.5 * sb * ss, ss * ss, 0.3 * ss * ss, 0.0, 0.3 * ss * ss,
      ss * ss;
  const Eigen::Matrix3d L = C.llt().matrixL();
  auto truth = [&](int k, double T) {
    const double d = T - T0;
    if (k == 0)
      return 0.2 * units::deg_per_h + 0.01 * units::deg_per_h * d + 2e-4 * units::deg_per_h * d * d;
    if (k == 1) return 30 * units::ppm;
    return -10 * units::ppm + 1.0 * units::ppm * d;
  };
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  int right_degrees = 0, draws = 200;
  double z2 = 0.0;
  int zs = 0;
  for (int draw = 0; draw < draws; ++draw) {
    std::vector<SoakEstimate> soaks;
    for (double T : temps) {
      SoakEstimate e;
      e.accel_temperature_c = e.gyro_temperature_c = T;
      e.catalog = idx;
      e.value = Eigen::Vector3d(truth(0, T), truth(1, T), truth(2, T)) +
                L * Eigen::Vector3d(n(rng), n(rng), n(rng));
      e.covariance = C;
      soaks.push_back(e);
    }
    ThermalFitOptions o;
    o.reference_temperature_c = T0;
    const ThermalFit fit = fit_soaks(soaks, o);
    if (fit.degree("gyro.bias") == 2 && fit.degree("gyro.scale") == 0 &&
        fit.degree("accel.scale") == 1)
      ++right_degrees;
    // Each fitted coefficient against its truth at three temperatures.
    for (int k = 0; k < 3; ++k)
      for (double T : {-30.0, 20.0, 55.0}) {
        const auto [v, sigma] = fit.at(idx[static_cast<std::size_t>(k)], T);
        const double z = (v - truth(k, T)) / sigma;
        z2 += z * z;
        ++zs;
      }
  }
  // 99 % tests on three families: about 3 % of draws take a degree too many (never too few at
  // these sizes: the quadratic is 36 sigma at the ends).
  CHECK(right_degrees >= 0.93 * draws);
  const double rms = std::sqrt(z2 / zs);
  CAPTURE(rms);
  CHECK(rms > 0.85);
  CHECK(rms < 1.15);
}

TEST_CASE("Thermal: a simulated chamber's soaks and its ramp give the thermal coefficients",
          "[thermal][long]") {
  // nav-fog-thermal in six soaks (-40 ... 60 C) and in a ramp over the same range: the soak fit
  // (Kalman filter per soak, then the fit) and the ramp's Kalman filter with the thermal states
  // each within their sigmas of the truth, and of each other.
  const std::string dir = test::temp_dir("thermal_chamber");
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/rot19.ini");
  spec.data_sensor_path = test::source_path("config/sensors/nav-fog-thermal.ini");
  spec.seed = 3;
  const ChamberSimulation soaks = simulate_chamber(
      dir + "/soaks", spec, ChamberProgram::load(test::source_path("config/chambers/soaks6.ini")));
  REQUIRE(soaks.sessions.size() == 6);
  const ImuErrorModel& truth = soaks.sessions.front().truth;
  const Eigen::VectorXd theta = truth.vector();
  const ChamberSoaks chamber = ChamberSoaks::load(soaks.path);
  std::vector<SoakEstimate> estimates;
  for (const auto& s : chamber.sessions) estimates.push_back(calibrate_soak(s, chamber).estimate);
  ThermalFitOptions o;
  o.reference_temperature_c = truth.reference_temperature_c;
  const ThermalFit fit = fit_soaks(estimates, o);
  CHECK(fit.degree("gyro.bias") >= 2);
  CHECK(fit.degree("accel.bias") >= 2);
  CHECK(fit.degree("gyro.scale") >= 1);
  CHECK(fit.degree("accel.misalignment") == 1);
  double z2 = 0.0, worst = 0.0;
  for (std::size_t k = 0; k < fit.catalog.size(); ++k) {
    const int c = fit.catalog[k];
    const double sigma =
        std::sqrt(fit.covariance(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k)));
    const double z = (fit.value(static_cast<Eigen::Index>(k)) - theta(c)) / sigma;
    CAPTURE(coefficient_catalog()[static_cast<std::size_t>(c)].name, z);
    CHECK(std::abs(z) < 4.0);
    z2 += z * z;
    worst = std::max(worst, std::abs(z));
  }
  const double rms = std::sqrt(z2 / static_cast<double>(fit.catalog.size()));
  CAPTURE(rms, worst, fit.chi2, fit.dof);
  CHECK(rms < 1.5);
  CHECK(fit.p_value > 1e-4);

  // The ramp: the Kalman filter with the thermal states.
  const ChamberSimulation ramp = simulate_chamber(
      dir + "/ramp", spec, ChamberProgram::load(test::source_path("config/chambers/ramp.ini")));
  const Session session = Session::load(ramp.path);
  const SensorProfile profile = SensorProfile::load(session.sensor_file);
  const KalmanRun run = run_kalman(session, calibrator_options_from_profile(profile));
  REQUIRE(run.stopped.empty());
  REQUIRE(run.diverged.empty());
  int compared = 0;
  for (std::size_t k = 0; k < fit.catalog.size(); ++k) {
    const int c = fit.catalog[k];
    const auto& info = coefficient_catalog()[static_cast<std::size_t>(c)];
    const CoefficientEstimate& e = run.estimates[static_cast<std::size_t>(c)];
    if (!coefficient_family_info(info.family).thermal() || !e.observed()) continue;
    const double s_fit =
        std::sqrt(fit.covariance(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(k)));
    const double z_ramp = (e.value - theta(c)) / e.sigma;
    const double z_both =
        (e.value - fit.value(static_cast<Eigen::Index>(k))) / std::hypot(e.sigma, s_fit);
    CAPTURE(info.name, e.value, e.sigma, fit.value(static_cast<Eigen::Index>(k)), s_fit, z_ramp,
            z_both);
    CHECK(std::abs(z_ramp) < 4.0);
    CHECK(std::abs(z_both) < 4.0);
    ++compared;
  }
  CHECK(compared >= 12);
}

TEST_CASE("Thermal: Monte Carlo of the chamber, soaks and ramp against the truth",
          "[thermal][montecarlo][.]") {
  // SINSCAL_THERMAL_SEEDS seeds (default 30) of nav-fog-thermal in six soaks and a ramp
  // (SINSCAL_THERMAL_PROFILE: another profile, e.g. config/sensors/mems-thermal.ini). Issue 19's
  // acceptance: every thermal coefficient within 3 sigma in >= 95 % of the seeds, err/sigma RMS
  // 0.8 ... 1.25, from the soaks and from the ramp, soaks and ramp agreeing.
  const char* seeds_env = std::getenv("SINSCAL_THERMAL_SEEDS");
  const char* profile_env = std::getenv("SINSCAL_THERMAL_PROFILE");
  const int seeds = seeds_env ? std::atoi(seeds_env) : 30;
  const std::string profile_path =
      profile_env ? profile_env : test::source_path("config/sensors/nav-fog-thermal.ini");
  const std::string dir = test::temp_dir("thermal_mc");
  const char* table_env = std::getenv("SINSCAL_THERMAL_TABLE_SIGMA");  // arcsec
  const double kTableSigma = (table_env ? std::atof(table_env) : 0.05) * units::arcsec;
  std::map<std::string, std::pair<double, int>> soak_z2, ramp_z2, both_z2;  // by family
  std::map<std::string, int> soak_beyond, ramp_beyond;
  int degree_right = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    SessionSimulation spec;
    spec.plan_path = test::source_path("config/plans/rot19.ini");
    spec.data_sensor_path = profile_path;
    spec.seed = static_cast<std::uint64_t>(seed);
    const std::string at = dir + "/" + std::to_string(seed);
    const ChamberSimulation soaks = simulate_chamber(
        at + "/soaks", spec, ChamberProgram::load(test::source_path("config/chambers/soaks6.ini")));
    const Eigen::VectorXd theta = soaks.sessions.front().truth.vector();
    // The simulated table is perfect: the filters take a table error of 0.05 arcsec
    // (SINSCAL_THERMAL_TABLE_SIGMA), the model of that table. With the default 2.5 the
    // misalignments' sigmas are three times their errors (RMS 0.35), with 0.25 the gyros' are
    // 1.5 times (RMS 0.67).
    ChamberSoaks chamber = ChamberSoaks::load(soaks.path);
    chamber.table_sigma = kTableSigma;
    std::vector<SoakEstimate> estimates;
    for (const auto& s : chamber.sessions) estimates.push_back(calibrate_soak(s, chamber).estimate);
    ThermalFitOptions o;
    o.reference_temperature_c = soaks.sessions.front().truth.reference_temperature_c;
    const ThermalFit fit = fit_soaks(estimates, o);
    const SensorProfile prof = SensorProfile::load(profile_path);
    bool right = true;
    for (const auto& t : fit.degrees) {
      int truth_degree = 0;
      for (int dg = 1; dg <= 3; ++dg)
        if (prof.has(t.family + "_temp" + std::to_string(dg))) truth_degree = dg;
      right = right && t.degree == truth_degree;
    }
    if (right) ++degree_right;
    const ChamberSimulation ramp = simulate_chamber(
        at + "/ramp", spec, ChamberProgram::load(test::source_path("config/chambers/ramp.ini")));
    const Session session = Session::load(ramp.path);
    CalibratorOptions ko = calibrator_options_from_profile(prof);
    ko.attitude_sigma = kTableSigma;
    const KalmanRun run = run_kalman(session, ko);
    REQUIRE(run.diverged.empty());
    for (std::size_t k = 0; k < fit.catalog.size(); ++k) {
      const int c = fit.catalog[k];
      const auto& info = coefficient_catalog()[static_cast<std::size_t>(c)];
      const auto i = static_cast<Eigen::Index>(k);
      const double s_fit = std::sqrt(fit.covariance(i, i));
      const double z = (fit.value(i) - theta(c)) / s_fit;
      auto& a = soak_z2[info.family];
      a.first += z * z;
      ++a.second;
      if (std::abs(z) > 3.0) ++soak_beyond[info.family];
      const CoefficientEstimate& e = run.estimates[static_cast<std::size_t>(c)];
      if (!e.observed()) continue;
      const double zr = (e.value - theta(c)) / e.sigma;
      auto& b = ramp_z2[info.family];
      b.first += zr * zr;
      ++b.second;
      if (std::abs(zr) > 3.0) ++ramp_beyond[info.family];
      const double zb = (e.value - fit.value(i)) / std::hypot(e.sigma, s_fit);
      auto& ab = both_z2[info.family];
      ab.first += zb * zb;
      ++ab.second;
    }
  }
  for (const auto& [family, a] : soak_z2) {
    const double rms = std::sqrt(a.first / a.second);
    const auto r = ramp_z2[family];
    const auto b = both_z2[family];
    std::printf(
        "%-26s soaks: RMS err/sigma %.3f, beyond 3 sigma %d/%d;  ramp: %.3f, %d/%d;  "
        "soaks - ramp: RMS %.3f\n",
        family.c_str(), rms, soak_beyond[family], a.second,
        r.second ? std::sqrt(r.first / r.second) : 0.0, ramp_beyond[family], r.second,
        b.second ? std::sqrt(b.first / b.second) : 0.0);
    if (coefficient_family_info(family).thermal()) {
      CAPTURE(family);
      CHECK(rms > 0.8);
      CHECK(rms < 1.25);
      CHECK(soak_beyond[family] <= 0.05 * a.second);
      // The ramp's filter alike, and the two agreeing (the rate term is the ramp's alone).
      if (r.second > 0) {
        const double ramp_rms = std::sqrt(r.first / r.second);
        CHECK(ramp_rms > 0.8);
        CHECK(ramp_rms < 1.25);
        CHECK(ramp_beyond[family] <= 0.05 * r.second);
        CHECK(std::sqrt(b.first / b.second) < 1.25);
      }
    }
  }
  std::printf("degrees as in the truth: %d of %d seeds\n", degree_right, seeds);
  CHECK(degree_right >= 0.95 * seeds);
}
