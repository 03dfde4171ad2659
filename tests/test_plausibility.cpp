// The plausibility gate: a clean simulated seed8 log passes every check; a wrong unit, a flipped
// axis, the wrong plan and clipped data each fail the check that names them.
#include <catch2/catch.hpp>
#include <functional>

#include "filter/plausibility/plausibility.hpp"
#include "helpers.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "rig/motion.hpp"
#include "rig/thermal.hpp"

using namespace sinscal;

namespace {

constexpr double kRate = 10.0;  // Hz: enough for dwell means

// seed8 simulated with the nav-fog profile's drawn errors and noise, altered by `alter`, written
// as a native log and passed through the gate.
PlausibilityReport gate(const std::function<void(ImuSample&)>& alter, const Plan* plan_for_gate,
                        double accel_range = 0.0, bool integrating = false) {
  const Plan plan = test::load_plan("seed8.ini");
  const SensorProfile profile =
      SensorProfile::load(test::source_path("config/sensors/nav-fog.ini"));
  const Motion motion = build_motion(plan, plan.site);
  auto samples = test::simulate(motion, profile.draw(3), kRate, &profile.noise, 3);
  for (auto& s : samples) alter(s);
  const std::string dir = test::temp_dir("plausibility");
  const std::string path = dir + "/imu.csv";
  {
    LogWriter w(path, kRate);
    for (const auto& s : samples) w.write(s);
    w.close();
  }
  PlausibilityLimits limits = PlausibilityLimits::from_profile(&profile);
  if (accel_range > 0.0) limits.accel_range = accel_range;
  if (integrating) limits = integrating_limits(limits, LogFormat::native_format(path, kRate));
  LogReader reader(LogFormat::native_format(path, kRate));
  const Plan& p = plan_for_gate ? *plan_for_gate : plan;
  return check_plausibility(reader, "imu.csv", test::timeline(p), p.site, 0.0, limits);
}

const PlausibilityCheck& check(const PlausibilityReport& r, const std::string& name) {
  for (const auto& c : r.checks)
    if (c.name == name) return c;
  FAIL("no check '" << name << "'");
  throw std::logic_error("unreachable");
}

}  // namespace

TEST_CASE("Plausibility gate: a clean log passes, each bad input fails its check",
          "[plausibility]") {
  SECTION("clean") {
    const auto r = gate([](ImuSample&) {}, nullptr);
    INFO(r.failures());
    CHECK(r.passed());
    CHECK(r.checks.size() == 4);
  }
  SECTION("velocity in mm/s declared as m/s") {
    const auto r = gate([](ImuSample& s) { s.dv_b *= 1000.0; }, nullptr);
    CHECK_FALSE(check(r, "gravity magnitude").passed);
    CHECK_THAT(check(r, "gravity magnitude").detail, Catch::Contains("mm/s"));
    CHECK(check(r, "gravity direction").passed);
  }
  SECTION("gyro increments in rad declared as deg") {
    const auto r = gate([](ImuSample& s) { s.dtheta_b *= units::deg; }, nullptr);
    CHECK_FALSE(check(r, "Earth rate").passed);
    CHECK_THAT(check(r, "Earth rate").detail, Catch::Contains("rad declared as deg"));
    CHECK(check(r, "gravity magnitude").passed);
  }
  SECTION("a flipped accelerometer axis") {
    const auto r = gate([](ImuSample& s) { s.dv_b.y() = -s.dv_b.y(); }, nullptr);
    CHECK(check(r, "gravity magnitude").passed);
    CHECK_FALSE(check(r, "gravity direction").passed);
    CHECK_THAT(check(r, "gravity direction").detail, Catch::Contains("wrong axis map or sign"));
  }
  SECTION("swapped accelerometer axes keep the magnitude: the direction of gravity tells") {
    const auto r = gate([](ImuSample& s) { std::swap(s.dv_b.x(), s.dv_b.z()); }, nullptr);
    CHECK_FALSE(check(r, "gravity direction").passed);
  }
  SECTION("the wrong plan") {
    const Plan rot19 = test::load_plan("rot19.ini");
    const auto r = gate([](ImuSample&) {}, &rot19);
    CHECK_FALSE(r.passed());
  }
  SECTION("clipped data") {
    const double range = 0.6 * units::g0;
    const auto r = gate(
        [&](ImuSample& s) {
          for (int i = 0; i < 3; ++i)
            s.dv_b(i) = std::clamp(s.dv_b(i), -range * s.dt, range * s.dt);
        },
        nullptr, range);
    CHECK_FALSE(check(r, "saturation").passed);
    CHECK_THAT(check(r, "saturation").detail, Catch::Contains("imu.csv:"));
  }
}

TEST_CASE("Plausibility gate: bounds from the sensor profile's error ranges", "[plausibility]") {
  const SensorProfile fog = SensorProfile::load(test::source_path("config/sensors/nav-fog.ini"));
  const SensorProfile mems = SensorProfile::load(test::source_path("config/sensors/mems.ini"));
  const auto lf = PlausibilityLimits::from_profile(&fog);
  const auto lm = PlausibilityLimits::from_profile(&mems);
  // The MEMS unit's larger errors widen every bound; neither is below its floor.
  CHECK(lm.specific_force > lf.specific_force);
  CHECK(lm.rate > lf.rate);
  CHECK(lf.direction >= 5.0 * units::deg);
  CHECK(lf.check_rate);
  // A FOG's Earth-rate bound is a small fraction of the Earth rate: rad-as-deg cannot hide in it.
  CHECK(lf.rate < 0.2 * Earth::wgs84().rate());
  const auto none = PlausibilityLimits::from_profile(nullptr);
  CHECK_FALSE(none.check_rate);
}

// The gate must not cry wolf: every bundled sensor profile on both bundled plans, 20 seeds each
// (the profile's errors drawn and its noise added), passes.
TEST_CASE("Plausibility gate Monte Carlo: no false alarm on simulated sessions",
          "[long][plausibility][monte_carlo]") {
  for (const std::string sensor : {"nav-fog.ini", "nav-fog-extended.ini", "mems.ini"}) {
    const SensorProfile profile =
        SensorProfile::load(test::source_path("config/sensors/" + sensor));
    const PlausibilityLimits limits = PlausibilityLimits::from_profile(&profile);
    for (const std::string plan_file : {"seed8.ini", "rot19.ini"}) {
      const Plan plan = test::load_plan(plan_file);
      const Motion motion = build_motion(plan, plan.site);
      const std::string path = test::temp_dir("plausibility_mc") + "/imu.csv";
      int alarms = 0;
      std::string first;
      for (std::uint64_t seed = 1; seed <= 20; ++seed) {
        const auto samples =
            test::simulate(motion, profile.draw(seed), kRate, &profile.noise, seed);
        {
          LogWriter w(path, kRate);
          for (const auto& s : samples) w.write(s);
          w.close();
        }
        LogReader reader(LogFormat::native_format(path, kRate));
        const auto r =
            check_plausibility(reader, "imu.csv", test::timeline(plan), plan.site, 0.0, limits);
        if (!r.passed()) {
          ++alarms;
          if (first.empty()) first = r.failures();
        }
      }
      INFO(sensor << " on " << plan_file << ": " << first);
      CHECK(alarms == 0);
    }
  }
}

TEST_CASE("Plausibility gate: the integrating methods refuse irregular sample intervals",
          "[plausibility]") {
  const double dt0 = 1.0 / kRate;
  SECTION("a clean clock passes") {
    const auto r = gate([](ImuSample&) {}, nullptr, 0.0, true);
    const auto& c = check(r, "sample intervals");
    INFO(c.detail);
    CHECK(c.passed);
    CHECK_THAT(c.detail, Catch::Contains("spread 0"));
  }
  SECTION("times jittered by up to 20 % of the interval (8-12 Hz irregular)") {
    const auto jitter = [dt0](ImuSample& s) { s.t += 0.2 * dt0 * std::sin(37.0 * s.t); };
    const auto r = gate(jitter, nullptr, 0.0, true);
    const auto& c = check(r, "sample intervals");
    INFO(c.detail);
    CHECK_FALSE(c.passed);
    CHECK_THAT(c.detail, Catch::Contains("imu.csv: sample intervals") &&
                             Catch::Contains("median 100 ms") &&
                             Catch::Contains("use --method rate-table"));
    // The means-only methods do not check the intervals.
    const auto means_only = gate(jitter, nullptr);
    for (const auto& m : means_only.checks) CHECK(m.name != "sample intervals");
  }
  SECTION("a jitter just above the tolerance is refused, one below passes") {
    const double tol = PlausibilityLimits::kIntegratingIntervalSpread;
    // Intervals dt0 (1 +- a): a spread of 2a.
    const auto alternate = [dt0](double a) {
      return [dt0, a](ImuSample& s) {
        const auto k = static_cast<long>(std::lround(s.t / dt0));
        s.t += (k % 2 == 0 ? 0.5 : -0.5) * a * dt0;
      };
    };
    CHECK_FALSE(check(gate(alternate(0.8 * tol), nullptr, 0.0, true), "sample intervals").passed);
    CHECK(check(gate(alternate(0.3 * tol), nullptr, 0.0, true), "sample intervals").passed);
  }
  SECTION("a steady clock stamped in coarse steps passes; jitter stamped so is still refused") {
    // Times rounded to 7 ms: intervals of 98 and 105 ms (a spread of 7 %), the rounding of a
    // steady clock, whose integrated errors telescope.
    const auto stamp = [](double step) {
      return [step](ImuSample& s) { s.t = step * std::round(s.t / step); };
    };
    const auto coarse = check(gate(stamp(0.007), nullptr, 0.0, true), "sample intervals");
    INFO(coarse.detail);
    CHECK(coarse.passed);
    CHECK_THAT(coarse.detail, Catch::Contains("timestamps in steps of 7 ms") &&
                                  Catch::Contains("jitter beyond them 0 %"));
    // The 20 % jitter above, stamped in whole ms: the grid is the stamps', the jitter is not.
    const auto jittered_stamped = [dt0](ImuSample& s) {
      s.t += 0.2 * dt0 * std::sin(37.0 * s.t);
      s.t = 0.001 * std::round(s.t / 0.001);
    };
    const auto j = check(gate(jittered_stamped, nullptr, 0.0, true), "sample intervals");
    INFO(j.detail);
    CHECK_FALSE(j.passed);
  }
  SECTION("no time column: the session's rate is an assumption the check names") {
    LogFormat f = LogFormat::native_format("imu.txt", 200.0);
    f.columns = {"gx", "gy", "gz", "ax", "ay", "az"};
    const PlausibilityLimits l = integrating_limits(PlausibilityLimits{}, f);
    CHECK(l.assumed_rate_hz == 200.0);
    const PlausibilityCheck c = check_interval_spread(IntervalSpread{}, l, "imu.txt");
    CHECK(c.passed);
    CHECK_THAT(c.detail, Catch::Contains("imu.txt: no time column") && Catch::Contains("200 Hz"));
  }
}

TEST_CASE("Plausibility gate: the profile's thermal terms at each dwell's temperature",
          "[plausibility][thermal]") {
  // seed8 at -40 C (60 C below the profile's T0) of a nav-fog-thermal unit whose gyro bias moves
  // by the profile's largest linear and quadratic terms, both away from T0's bias (1.68 deg/h per
  // axis there, above the base terms' bound of about 1.7 deg/h on |omega| on some dwells): the
  // gate takes each dwell's temperature and the thermal terms into its bounds (a ramp's cold
  // dwells failed it before, issue 33). Without them the same log fails; a unit error still
  // fails with them.
  const Plan plan = test::load_plan("seed8.ini");
  const SensorProfile profile =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-thermal.ini"));
  ImuErrorModel truth = profile.draw(3);
  const double T0 = profile.reference_temperature_c, cold = T0 - 60.0;
  truth.gyro.bias_temp.col(0).setConstant(-profile.ranges.at("gyro.bias_temp1").hi);
  truth.gyro.bias_temp.col(1).setConstant(profile.ranges.at("gyro.bias_temp2").hi);
  const SensorTemperature temperature(ChamberAir{{0.0}, {cold}}, 600.0);
  const Motion motion = build_motion(plan, plan.site);
  const auto samples = test::simulate(motion, truth, kRate, &profile.noise, 3, &temperature);
  REQUIRE(samples.front().has_temperature);
  const std::string path = test::temp_dir("plausibility_thermal") + "/imu.csv";
  const auto gate_with = [&](const PlausibilityLimits& limits, double scale) {
    {
      LogWriter w(path, kRate, false, true);
      for (auto s : samples) {
        s.dtheta_b *= scale;
        w.write(s);
      }
      w.close();
    }
    LogReader reader(LogFormat::native_format(path, kRate));
    return check_plausibility(reader, "imu.csv", test::timeline(plan), plan.site, 0.0, limits);
  };
  const PlausibilityLimits limits = PlausibilityLimits::from_profile(&profile);
  CHECK(limits.rate_thermal[1] > 0.0);
  const auto r = gate_with(limits, 1.0);
  INFO(r.failures());
  CHECK(r.passed());
  PlausibilityLimits base = limits;
  base.rate_thermal = {};
  base.specific_force_thermal = {};
  base.rate_per_temperature_rate = 0.0;
  const auto without = gate_with(base, 1.0);
  CHECK_FALSE(check(without, "Earth rate").passed);
  const auto unit = gate_with(limits, units::deg);  // rad declared as deg
  CHECK_FALSE(check(unit, "Earth rate").passed);
  CHECK_THAT(check(unit, "Earth rate").detail, Catch::Contains("at -40 C"));
}
