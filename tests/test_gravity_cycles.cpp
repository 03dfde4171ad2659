// The readings' intervals of a log without time, measured from gravity's cycles (issue 34, item 4;
// filter/plausibility/gravity_cycles.hpp), on generated logs of the APOPHIS rate tests' structure.
#include <catch2/catch.hpp>
#include <cmath>

#include "apophis_like.hpp"
#include "filter/plausibility/gravity_cycles.hpp"
#include "helpers.hpp"
#include "models/units.hpp"
#include "rig/session.hpp"

using namespace sinscal;

namespace {
// Turns of 2 revolutions at 25 deg/s about body x and then -y (both across gravity: z up), and
// one about z (along it), 10 s rests between; the BMI160's data-sheet noise, no toggling.
test::ApophisLike cycles_session(double min_hz, double max_hz, const Eigen::Matrix3d& error) {
  test::ApophisLike spec;
  const double rate = 25.0 * units::deg_per_s, accel = 25.0 * units::deg_per_s;
  const double hold = 2.0 * 2.0 * M_PI / rate - rate / accel;
  spec.phases = {
      test::rest_phase(10.0), test::turn_phase(Eigen::Vector3d::UnitX(), rate, accel, hold),
      test::rest_phase(10.0), test::turn_phase(-Eigen::Vector3d::UnitY(), rate, accel, hold),
      test::rest_phase(10.0), test::turn_phase(Eigen::Vector3d::UnitZ(), rate, accel, hold),
      test::rest_phase(10.0)};
  spec.toggling = false;
  spec.gyro_white = 0.007 * units::deg_per_s * std::sqrt(15.0);
  spec.accel_white = 180.0 * units::ug * std::sqrt(15.0);
  spec.min_hz = min_hz;
  spec.max_hz = max_hz;
  spec.accel_error = error;
  // No plan: a hand-held session ([site] gravity); the check reads the log only.
  return spec;
}

GravityCycleIntervals measured(const std::string& name, double min_hz, double max_hz,
                               const Eigen::Matrix3d& error = Eigen::Matrix3d::Zero()) {
  const std::string dir = test::temp_dir(name);
  const Session s =
      Session::load(test::write_apophis_like(dir, cycles_session(min_hz, max_hz, error)),
                    Session::PlanNeed::Optional);
  return gravity_cycle_intervals(s.log, turn_timings(s.log, TurnTimingOptions{}));
}
}  // namespace

TEST_CASE("Gravity's cycles measure a no-time log's irregular 12-18 Hz intervals",
          "[plausibility][apophis]") {
  // The readings' true intervals are uniform in 1/18 ... 1/12 s: mean 69.44 ms (14.4 Hz, the
  // session says 15), standard deviation (1/12 - 1/18) / sqrt(12) = 8.02 ms, 11.5 % of the mean.
  const GravityCycleIntervals g = measured("gravity_cycles_irregular", 12.0, 18.0);
  CAPTURE(g.turns, g.intervals, g.mean, g.mean_sigma, g.jitter, g.jitter_sigma, g.noise);
  CHECK(g.turns == 2);  // the turn about z moves no gravity
  const double mean = 0.5 * (1.0 / 12.0 + 1.0 / 18.0);
  const double spread = (1.0 / 12.0 - 1.0 / 18.0) / std::sqrt(12.0) / mean;
  CHECK(std::abs(g.mean - mean) < 4.0 * g.mean_sigma);
  CHECK(std::abs(g.jitter - spread) < 4.0 * g.jitter_sigma);
  CHECK(g.irregular());
  LogFormat log;
  log.file = "log.csv";
  const PlausibilityCheck c = check_gravity_cycle_intervals(g, log, 0.04);
  CHECK_FALSE(c.passed);
  CHECK_THAT(c.detail, Catch::Contains("log.csv: without a time column") &&
                           Catch::Contains("the intervals are irregular"));
}

TEST_CASE("Gravity's cycles find a regular no-time log regular, at its rate",
          "[plausibility][apophis]") {
  // The same turns read at a steady 15 Hz: the steps' spread is the noise's alone. The
  // accelerometers' biases (30-50 mg) move gravity's circle off the origin, and scale factors 2 %
  // apart and a 1 deg misalignment make it an ellipse: measured from the origin, the steps'
  // spread was 3.2 % of the mean on such a log; about the fitted ellipse's centre, on the circle
  // it maps to, the noise's.
  Eigen::Matrix3d error = Eigen::Matrix3d::Zero();
  error.diagonal() << 0.01, -0.01, 0.005;
  error(0, 1) = 1.0 * units::deg;
  const GravityCycleIntervals g = measured("gravity_cycles_regular", 15.0, 15.0, error);
  CAPTURE(g.turns, g.intervals, g.mean, g.mean_sigma, g.jitter, g.jitter_sigma, g.noise);
  CHECK(g.turns == 2);
  CHECK(std::abs(g.mean - 1.0 / 15.0) < 4.0 * g.mean_sigma);
  CHECK(g.jitter < 4.0 * g.jitter_sigma);
  CHECK_FALSE(g.irregular());
  LogFormat log;
  log.file = "log.csv";
  CHECK(check_gravity_cycle_intervals(g, log, 0.04).passed);
}
