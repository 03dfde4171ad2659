// A table's dynamics in the simulator (rig/motion.hpp TableDynamics) and the Kalman filter's
// motion from the data (filter/kalman/motion_from_data.hpp): logs whose turns do not follow the
// plan's commanded trapezoids.
#include <catch2/catch.hpp>
#include <cmath>

#include "filter/kalman/kalman_run.hpp"
#include "filter/plausibility/plausibility.hpp"
#include "helpers.hpp"
#include "models/attitude.hpp"
#include "models/units.hpp"
#include "report/result.hpp"
#include "rig/plan.hpp"
#include "rig/session.hpp"

using namespace sinscal;

namespace {

std::vector<std::pair<std::string, TableDynamics>> dynamics_kinds() {
  std::vector<std::pair<std::string, TableDynamics>> out;
  TableDynamics d;
  d.smoothing = 0.3;
  out.emplace_back("smoothing", d);
  d = {};
  d.max_rate = 8.0 * units::deg;
  d.max_acceleration = 6.0 * units::deg;
  out.emplace_back("limits", d);
  d = {};
  d.jerk_time = 0.5;
  out.emplace_back("jerk", d);
  d = {};
  d.servo_frequency = 2.0;
  d.servo_damping = 0.5;
  out.emplace_back("servo", d);
  d = {};
  d.servo_frequency = 3.0;
  d.ripple_frequency = 10.0;
  d.ripple_damping = 0.1;
  out.emplace_back("servo and structural mode", d);
  d = {};
  d.jerk_time = 0.2;
  d.smoothing = 0.1;
  d.rate_ripple = 2.0 * units::arcsec;
  d.rate_ripple_period = 1.0 * units::deg;
  out.emplace_back("jerk, smoothing and rate ripple", d);
  return out;
}

}  // namespace

TEST_CASE(
    "Table dynamics: the realized profile's rate and acceleration are its derivatives, "
    "and it ends at the commanded angle",
    "[motion][table_dynamics]") {
  const TrapezoidProfile cmd =
      TrapezoidProfile::by_duration(-90.0 * units::deg, 9.0, 10.0 * units::deg);
  for (const auto& [name, d] : dynamics_kinds()) {
    CAPTURE(name);
    const AngleProfile p = d.realize(cmd);
    REQUIRE(p.realized());
    CHECK(p.begin() <= 0.0);
    CHECK(p.end() >= cmd.duration());
    double a, r, c;
    p.eval(p.end() + 1.0, a, r, c);
    CHECK(a == cmd.angle());
    p.eval(p.end() - 1e-6, a, r, c);
    CHECK(std::abs(a - cmd.angle()) < 1e-9);  // settled at the end of its support
    CHECK(std::abs(r) < 1e-5);                // the acceleration times 1e-6 s
    p.eval(p.begin() + 1e-6, a, r, c);
    CHECK(std::abs(a) < 1e-9);
    // Central differences of angle and rate against rate and acceleration along the profile
    // (away from the jerk limit's kinks).
    const double h = 1e-4;
    double worst_rate = 0.0, worst_accel = 0.0, peak = 0.0;
    for (double t = p.begin() + 0.013; t < p.end(); t += 0.0371) {
      double a0, r0, c0, a1, r1, c1, a2, r2, c2;
      p.eval(t - h, a0, r0, c0);
      p.eval(t, a1, r1, c1);
      p.eval(t + h, a2, r2, c2);
      peak = std::max(peak, std::abs(r1));
      worst_rate = std::max(worst_rate, std::abs((a2 - a0) / (2 * h) - r1));
      if (std::abs(c2 - c0) < 1e-3)  // not across an acceleration kink
        worst_accel = std::max(worst_accel, std::abs((r2 - r0) / (2 * h) - c1));
    }
    CHECK(worst_rate < 1e-6 * peak);
    CHECK(worst_accel < 1e-3 * peak);
  }
}

TEST_CASE(
    "Table dynamics: the simulated table departs from the plan as described, and the "
    "dwells still end at the plan's attitudes",
    "[motion][table_dynamics]") {
  const Plan plan = test::load_plan("rot19.ini");
  const Motion commanded = build_motion(plan, plan.site);
  TableErrors e;
  e.dynamics.smoothing = 0.3;
  const Motion smoothed = build_motion(plan, plan.site, e);
  // At the plan's end of the start dwell the smoothed table already turns (zero phase: it
  // begins before the command), at the plan's start of the next dwell it still turns.
  const double t_turn = commanded.dwells()[0].t_end;
  CHECK(commanded.at(t_turn).omega_nb_b.norm() < 1e-12);
  CHECK(smoothed.at(t_turn).omega_nb_b.norm() > 0.3 * units::deg);
  CHECK(smoothed.at(commanded.dwells()[1].t_start).omega_nb_b.norm() > 0.3 * units::deg);
  CHECK_FALSE(smoothed.static_between(t_turn - 0.5, t_turn));
  // Mid-dwell both rest in the same attitude.
  for (const auto& d : commanded.dwells()) {
    const double t = 0.5 * (d.t_start + d.t_end);
    CHECK(rotvec_from_dcm(smoothed.at(t).C_b_n * commanded.at(t).C_b_n.transpose()).norm() < 1e-12);
  }
  // A settling that reaches into the next turn is refused with the times.
  TableErrors slow;
  slow.dynamics.servo_frequency = 0.2;  // settles over 37 / (0.9 2 pi 0.2) = 33 s > 20 s
  slow.dynamics.servo_damping = 0.9;
  CHECK_THROWS_WITH(build_motion(plan, plan.site, slow),
                    Catch::Contains("after the next move begins"));
}

namespace {

Session simulate(const std::string& name, const TableDynamics& d, std::uint64_t seed,
                 const std::string& sensor = "config/sensors/nav-fog-extended.ini") {
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/rot19.ini");
  spec.data_sensor_path = test::source_path(sensor);
  spec.name = name;
  spec.seed = seed;
  spec.table.attitude_sigma = 2.5 * units::arcsec;
  spec.table.seed = seed + 100;
  spec.table.dynamics = d;
  const std::string dir = test::temp_dir(name);
  simulate_session(dir, spec);
  return Session::load(dir + "/session.ini");
}

// The largest |error| / sigma over the observable estimates.
double worst(const KalmanRun& r, const Session& s) {
  const ResultCoefficients truth = load_truth(s, r.accel_triad_frame);
  double out = 0.0;
  for (const auto& [name, c] : result_coefficients(r)) {
    if (!c.observable || c.fixed_by_convention || !c.sigma) continue;
    out = std::max(out, std::abs(c.value - truth.at(name).value) / *c.sigma);
  }
  return out;
}

}  // namespace

TEST_CASE(
    "Kalman filter along the data's motion: a start-time offset the session does not "
    "state is found, and the calibration stays within its sigmas",
    "[kalman][table_dynamics]") {
  TableDynamics d;
  d.start_offset = 1.37;
  const Session s = simulate("dyn_offset", d, 3);
  const CalibratorOptions o = calibrator_options_from_profile(SensorProfile::load(s.sensor_file));
  const KalmanRun r = run_kalman(s, o);
  REQUIRE(r.motion);
  CHECK(r.motion->offset_found());
  CHECK(std::abs(r.motion->time_offset - 1.37) < 0.005);
  CHECK(r.diverged.empty());
  CHECK(r.stopped.empty());
  CHECK(worst(r, s) < 4.0);
  // Along the plan's commanded motion, 1.37 s late, the lever arms (whose column is the
  // angular acceleration) land tens of sigmas off.
  KalmanRunOptions plan_motion;
  plan_motion.motion_from_data = false;
  const KalmanRun p = run_kalman(s, o, nullptr, plan_motion);
  CHECK((!p.diverged.empty() || worst(p, s) > 6.0));
}

TEST_CASE(
    "Kalman filter along the data's motion: smoothed turns (another tool's profile) are "
    "reported as departing, and calibrated within their sigmas",
    "[kalman][table_dynamics]") {
  TableDynamics d;
  d.smoothing = 0.3;
  const Session s = simulate("dyn_smooth", d, 5);
  const CalibratorOptions o = calibrator_options_from_profile(SensorProfile::load(s.sensor_file));
  const KalmanRun r = run_kalman(s, o);
  REQUIRE(r.motion);
  CHECK_FALSE(r.motion->offset_found());
  CHECK(r.motion->departing() == 18);
  for (const auto& m : r.motion->moves) {
    CHECK(m.largest > 0.1 * units::deg);    // the smoothing's lead and lag
    CHECK(std::abs(m.start_shift) < 0.02);  // zero phase: on time at mid-turn
    CHECK(m.begins < m.plan_begins - 0.3);  // it turns before the command
  }
  CHECK(r.diverged.empty());
  CHECK(worst(r, s) < 4.0);
  // The plan's own motion, simulated without dynamics, follows the plan: nothing departs.
  const Session plain = simulate("dyn_plain", TableDynamics{}, 5);
  const KalmanRun q = run_kalman(plain, o);
  REQUIRE(q.motion);
  CHECK(q.motion->departing() == 0);
  CHECK_FALSE(q.motion->offset_found());
}

TEST_CASE(
    "Kalman filter along the data's motion: a MEMS unit's smoothed turns, its gyro biases "
    "(up to 0.5 deg/s) taken off each turn by the dwells around it",
    "[kalman][table_dynamics]") {
  TableDynamics d;
  d.smoothing = 0.3;
  const Session s = simulate("dyn_mems", d, 4, "config/sensors/mems.ini");
  const CalibratorOptions o = calibrator_options_from_profile(SensorProfile::load(s.sensor_file));
  const KalmanRun r = run_kalman(s, o);
  REQUIRE(r.motion);
  CHECK_FALSE(r.motion->offset_found());
  CHECK(r.motion->departing() == 18);
  for (const auto& m : r.motion->moves) {
    CHECK(std::abs(m.start_shift) < 0.035);  // the 50 % crossing, to a few 10 ms samples
    // The smoothing's lead and lag: 0.3 s of a 10 deg/s^2 ramp reach about 0.45 deg.
    CHECK(m.largest < 0.7 * units::deg);
  }
  CHECK(r.diverged.empty());
  CHECK(worst(r, s) < 4.0);
}

TEST_CASE(
    "Plausibility gate on a log that starts 3 s late: refused with the plan's timing, "
    "passed with the offset and the dwells the data show",
    "[plausibility][table_dynamics]") {
  TableDynamics d;
  d.start_offset = 3.0;
  const Session s = simulate("dyn_gate", d, 6);
  const SensorProfile profile = SensorProfile::load(s.sensor_file);
  const PlausibilityLimits limits = PlausibilityLimits::from_profile(&profile);
  CHECK_FALSE(check_plausibility(s, limits).passed());
  const DataMotion m = motion_from_data(s, calibrator_options_from_profile(profile));
  CHECK(std::abs(m.time_offset - 3.0) < 0.005);
  LogReader reader(s.log);
  const PlausibilityReport r =
      check_plausibility(reader, s.log.file, *m.timeline, s.site, m.time_offset, limits);
  CAPTURE(r.failures());
  CHECK(r.passed());
}
