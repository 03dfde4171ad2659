#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <set>

#include "helpers.hpp"
#include "models/config.hpp"
#include "models/imu_error_model.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"

using namespace sinscal;
using Eigen::Vector3d;

namespace {
ImuErrorModel random_extended_model(std::uint64_t seed) {
  // Base and extended terms from the profile, plus asymmetry and g-sensitivity by hand.
  ImuErrorModel m =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-extended.ini")).draw(seed);
  std::mt19937_64 rng(seed + 100);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < 3; ++i) {
    m.gyro.scale_asym(i) = 20 * units::ppm * u(rng);
    m.accel.scale_asym(i) = 20 * units::ppm * u(rng);
    for (int j = 0; j < 3; ++j) m.gyro_g_sensitivity(i, j) = 0.05 * units::deg_per_h_per_g * u(rng);
    m.gyro.bias_drift(i) = 0.1 * units::deg_per_h / units::hour * u(rng);
    m.accel.bias_drift(i) = 50 * units::ug / units::hour * u(rng);
    // Thermal terms of a MEMS unit's size.
    for (int d = 0; d < 3; ++d) {
      const double per = std::pow(0.02, d);  // per C^d: a MEMS unit's curvature
      m.gyro.bias_temp(i, d) = 5 * units::deg_per_h * per * u(rng);
      m.accel.bias_temp(i, d) = 50 * units::ug * per * u(rng);
      m.gyro.scale_temp(i, d) = 50 * units::ppm * per * u(rng);
      m.accel.scale_temp(i, d) = 50 * units::ppm * per * u(rng);
    }
    for (int j = 0; j < 3; ++j)
      if (j != i) {
        m.gyro.misalignment_temp(i, j) = 2 * units::arcsec * u(rng);
        m.accel.misalignment_temp(i, j) = 2 * units::arcsec * u(rng);
      }
    m.gyro.bias_temp_rate(i) = 10 * units::deg_per_h * 60.0 * u(rng);
  }
  REQUIRE(m.has_thermal());
  return m;
}
}  // namespace

TEST_CASE("Error model: apply then compensate returns the input to 1e-12 relative",
          "[error_model]") {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const ImuErrorModel m = random_extended_model(seed);
    REQUIRE(m.accel.k2.norm() > 0.0);
    REQUIRE(m.accel_lever_arm_b.norm() > 0.0);
    for (int k = 0; k < 50; ++k) {
      KinematicSample s;
      s.omega_ib_b = Vector3d(n(rng), n(rng), n(rng)) * 0.5;
      s.omega_dot_ib_b = Vector3d(n(rng), n(rng), n(rng)) * 0.3;
      s.f_ib_b = Vector3d(n(rng), n(rng), n(rng)) * 9.8;
      s.t = 3600.0 * std::abs(n(rng));  // time-dependent terms (bias drift)
      s.accel_dtemp = 30.0 * n(rng);    // thermal terms
      s.gyro_dtemp = 30.0 * n(rng);
      s.gyro_dtemp_rate = 0.02 * n(rng);
      const Vector3d yg = m.gyro_output(s), ya = m.accel_output(s);
      Vector3d w, f;
      m.compensate(yg, ya, s.omega_dot_ib_b, w, f, s.t, &s);
      CHECK((w - s.omega_ib_b).norm() <= 1e-12 * s.omega_ib_b.norm());
      CHECK((f - s.f_ib_b).norm() <= 1e-12 * s.f_ib_b.norm());
      // And the errors are really there: output differs from input by far more than that.
      CHECK((ya - s.f_ib_b).norm() > 1e-6 * s.f_ib_b.norm());
    }
  }
}

TEST_CASE("Error model: sign conventions of each term", "[error_model]") {
  ImuErrorModel m;
  m.set("gyro.misalignment.xy", 10.0);  // sensor x towards body y
  m.set("gyro.scale.z", 100.0);
  m.set("gyro.bias.y", 1.0);
  KinematicSample s;
  s.omega_ib_b = Vector3d(0.0, 1.0, 2.0);
  Vector3d y = m.gyro_output(s);
  CHECK(y.x() == Approx(10.0 * units::arcsec));
  CHECK(y.y() == Approx(1.0 + units::deg_per_h));
  CHECK(y.z() == Approx(2.0 * (1.0 + 100e-6)));
  // Asymmetry: +a on positive input, -a on negative input (half the difference).
  ImuErrorModel a;
  a.set("accel.scale_asym.x", 50.0);
  s.f_ib_b = Vector3d(2.0, 0, 0);
  CHECK(a.accel_output(s).x() == Approx(2.0 * (1 + 50e-6)));
  s.f_ib_b = Vector3d(-2.0, 0, 0);
  CHECK(a.accel_output(s).x() == Approx(-2.0 * (1 - 50e-6)));
  // K2 in ug/g^2: 1 g input gives k2 ug extra.
  ImuErrorModel q;
  q.set("accel.k2.z", 20.0);
  s.f_ib_b = Vector3d(0, 0, units::g0);
  CHECK(q.accel_output(s).z() - units::g0 == Approx(20.0 * units::ug).epsilon(1e-9));
  // g-sensitivity: gyro x per acceleration along z.
  ImuErrorModel g;
  g.set("gyro.g_sensitivity.xz", 0.5);
  s.omega_ib_b.setZero();
  CHECK(g.gyro_output(s).x() == Approx(0.5 * units::deg_per_h));
  // Size effect: turning about z at w, an accelerometer x at r = (L, 0, 0) sees -w^2 L.
  ImuErrorModel l;
  l.set("accel.lever_arm.x.x", 50.0);
  s.f_ib_b.setZero();
  s.omega_ib_b = Vector3d(0, 0, 2.0);
  CHECK(l.accel_output(s).x() == Approx(-4.0 * 0.05));
  CHECK(l.accel_output(s).y() == 0.0);
  // Bias drift: linear in the time since the start of the plan.
  ImuErrorModel d;
  d.set("gyro.bias_drift.y", 2.0);    // deg/h per hour
  d.set("accel.bias_drift.z", 30.0);  // ug per hour
  s.omega_ib_b.setZero();
  s.f_ib_b.setZero();
  s.t = 1800.0;
  CHECK(d.gyro_output(s).y() == Approx(1.0 * units::deg_per_h));
  CHECK(d.accel_output(s).z() == Approx(15.0 * units::ug));
  s.t = 0.0;
  CHECK(d.gyro_output(s).y() == 0.0);
}

TEST_CASE("Coefficient catalog: names, units and set/get", "[error_model]") {
  const auto& cat = coefficient_catalog();
  CHECK(cat.size() == 24 + 3 + 6 + 9 + 9 + 1 + 6 + 3 * 12 + 6 + 6 + 3);
  std::set<std::string> names;
  for (const auto& c : cat) names.insert(c.name);
  CHECK(names.size() == cat.size());
  for (const char* n : {"gyro.bias.x", "accel.misalignment.zy", "accel.k2.y", "gyro.scale_asym.z",
                        "gyro.g_sensitivity.yx", "accel.lever_arm.z.x", "time_delay",
                        "gyro.bias_drift.x", "accel.bias_drift.z"})
    CHECK(names.count(n) == 1);
  ImuErrorModel m;
  m.set("time_delay", 5.0);
  CHECK(m.time_delay == Approx(5e-3));
  m.set("accel.lever_arm.y.x", 30.0);  // accelerometer y, body axis x
  CHECK(m.accel_lever_arm_b(0, 1) == Approx(0.03));
  CHECK(m.coefficients().at("accel.lever_arm.y.x") == Approx(30.0));
  CHECK_THROWS_AS(m.set("gyro.bias.w", 1.0), std::invalid_argument);
}

TEST_CASE("Sensor profiles: drawn coefficients lie in their ranges", "[error_model]") {
  const SensorProfile p =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-extended.ini"));
  CHECK(p.has("accel.k2"));
  CHECK_FALSE(p.has("gyro.g_sensitivity"));
  CHECK(p.noise.gyro.white == Approx(0.001 * units::deg_per_sqrt_h));
  CHECK(p.noise.accel.white == Approx(10 * units::ug_per_sqrt_hz));
  for (std::uint64_t seed = 1; seed < 30; ++seed) {
    const auto c = p.draw(seed).coefficients();
    for (const auto& [name, v] : c) {
      const std::string fam = coefficient_family(name);
      if (fam == "gyro.bias") CHECK((std::abs(v) >= 0.1 && std::abs(v) <= 0.3));
      if (fam == "gyro.misalignment") CHECK((std::abs(v) >= 10 && std::abs(v) <= 60));
      if (fam == "accel.lever_arm") CHECK((std::abs(v) >= 10 && std::abs(v) <= 60));
      if (fam == "time_delay") CHECK(v == Approx(5.0));
      if (fam == "gyro.g_sensitivity") CHECK(v == 0.0);
    }
  }
  CHECK(p.draw(1).coefficients() == p.draw(1).coefficients());
  CHECK(p.draw(1).coefficients() != p.draw(2).coefficients());
}

TEST_CASE("Sensor profiles: wrong units and unknown keys are errors with file and line",
          "[error_model]") {
  const std::string dir = test::temp_dir("profile");
  test::write_file(dir + "/bad_unit.ini", "[gyro]\nbias = 0.1 0.3 ug\n");
  try {
    SensorProfile::load(dir + "/bad_unit.ini");
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK_THAT(e.what(), Catch::Contains("bad_unit.ini:2") && Catch::Contains("ug") &&
                             Catch::Contains("deg/h"));
  }
  test::write_file(dir + "/typo.ini", "[accel]\nbias = 100 ug\nbais = 3\n");
  CHECK_THROWS_WITH(SensorProfile::load(dir + "/typo.ini"), Catch::Contains("typo.ini:3"));
}

TEST_CASE("Every bundled sensor profile loads and draws", "[error_model]") {
  int n = 0;
  for (const auto& f : std::filesystem::directory_iterator(test::source_path("config/sensors"))) {
    CAPTURE(f.path().string());
    const SensorProfile p = SensorProfile::load(f.path().string());
    CHECK(p.has("gyro.bias"));
    CHECK(p.noise.gyro.white > 0.0);
    ++n;
  }
  CHECK(n >= 3);
  const SensorProfile mems = SensorProfile::load(test::source_path("config/sensors/mems.ini"));
  CHECK(mems.has("gyro.g_sensitivity"));
  const double g_sens = std::abs(mems.draw(4).gyro_g_sensitivity(0, 0));
  CHECK((g_sens >= 0.01 * units::deg / units::g0 && g_sens <= 0.1 * units::deg / units::g0));
}

TEST_CASE("Error model: the thermal terms' signs and powers", "[error_model][thermal]") {
  // docs/conventions.md: b(T) = b + B1 dT + B2 dT^2 + B3 dT^3 + r dT/dt, k(T) likewise, and
  // M(T) = M + M1 dT, with dT = T - T0.
  ImuErrorModel m;
  m.set("gyro.bias_temp1.x", 0.5);          // deg/h/C
  m.set("gyro.bias_temp2.y", 0.01);         // deg/h/C^2
  m.set("gyro.bias_temp3.z", -0.001);       // deg/h/C^3
  m.set("gyro.bias_temp_rate.x", 3.0);      // deg/h/(C/min)
  m.set("accel.scale_temp1.x", 40.0);       // ppm/C
  m.set("accel.scale_temp2.x", 1.0);        // ppm/C^2
  m.set("accel.misalignment_temp1.yz", 2);  // arcsec/C
  m.set("accel.bias_temp1.z", -20.0);       // ug/C
  KinematicSample s;
  s.f_ib_b = Vector3d(9.8, 1.0, 2.0);
  s.gyro_dtemp = s.accel_dtemp = -10.0;
  s.gyro_dtemp_rate = 0.5 / 60.0;  // C/s: 0.5 C/min
  const Vector3d yg = m.gyro_output(s), ya = m.accel_output(s);
  CHECK(yg(0) / units::deg_per_h == Approx(-5.0 + 1.5).epsilon(1e-12));
  CHECK(yg(1) / units::deg_per_h == Approx(1.0).epsilon(1e-12));
  CHECK(yg(2) / units::deg_per_h == Approx(1.0).epsilon(1e-12));
  CHECK(ya(0) == Approx(9.8 * (1.0 + (-400.0 + 100.0) * units::ppm)).epsilon(1e-14));
  CHECK(ya(1) == Approx(1.0 - 20.0 * units::arcsec * 2.0).epsilon(1e-14));
  CHECK(ya(2) == Approx(2.0 + 200.0 * units::ug).epsilon(1e-14));
  // At T0 nothing is left.
  s.gyro_dtemp = s.accel_dtemp = s.gyro_dtemp_rate = 0.0;
  CHECK(m.gyro_output(s).norm() == 0.0);
  CHECK((m.accel_output(s) - s.f_ib_b).norm() == 0.0);
}

TEST_CASE("Error model Jacobian matches finite differences of the model",
          "[error_model][jacobian]") {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  const ImuErrorModel m = random_extended_model(4);
  const auto& cat = coefficient_catalog();
  for (int trial = 0; trial < 20; ++trial) {
    KinematicSample s;
    s.omega_ib_b = Vector3d(n(rng), n(rng), n(rng)) * 0.5;
    s.omega_dot_ib_b = Vector3d(n(rng), n(rng), n(rng)) * 0.3;
    s.f_ib_b = Vector3d(n(rng), n(rng), n(rng)) * 9.8;
    s.t = 3600.0 * std::abs(n(rng));
    s.accel_dtemp = 30.0 * n(rng);
    s.gyro_dtemp = 30.0 * n(rng);
    s.gyro_dtemp_rate = 0.02 * n(rng);
    const Vector3d f_dot(n(rng), n(rng), n(rng));
    const auto J = m.jacobian(s, f_dot);
    REQUIRE(J.cols() == static_cast<Eigen::Index>(cat.size()));
    for (std::size_t k = 0; k < cat.size(); ++k) {
      CAPTURE(cat[k].name);
      // One unit of the coefficient: the model is linear in its coefficients, so a central
      // difference has no truncation error and a large step keeps rounding small.
      const double h = cat[k].si_per_unit;
      Eigen::Matrix<double, 6, 1> fd;
      if (cat[k].name == "time_delay") {
        // Delay: the accelerometer sees f(t - tau); to first order f - tau f_dot.
        ImuErrorModel p = m;
        KinematicSample shifted = s;
        shifted.f_ib_b = s.f_ib_b - h * f_dot;
        fd << Vector3d::Zero(), (p.accel_output(shifted) - p.accel_output(s)) / h;
        // the model's own linear errors act on the shifted input too (second order): at the
        // sample's temperature
        const double linear_error =
            (m.accel.linear(s.accel_dtemp) - Eigen::Matrix3d::Identity()).norm();
        CHECK((fd - J.col(static_cast<Eigen::Index>(k))).norm() <
              (1e-3 + linear_error) * f_dot.norm());
        continue;
      }
      ImuErrorModel plus = m, minus = m;
      plus.set(cat[k].name, m.coefficients().at(cat[k].name) + 1.0);
      minus.set(cat[k].name, m.coefficients().at(cat[k].name) - 1.0);
      fd << (plus.gyro_output(s) - minus.gyro_output(s)) / (2 * h),
          (plus.accel_output(s) - minus.accel_output(s)) / (2 * h);
      CHECK((fd - J.col(static_cast<Eigen::Index>(k))).norm() <=
            1e-7 * (1.0 + J.col(static_cast<Eigen::Index>(k)).norm()));
    }
  }
}
