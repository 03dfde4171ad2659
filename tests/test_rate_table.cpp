// Rate-table and tumble calibration from segment means (filter/rate_table): simulated sessions of
// the plans in config/plans (rate table, dividing-head tumble, six faces on a three-axis table,
// mixed), a few seeds each, error / sigma of every estimate against the simulation's truth.
// The 30-seed Monte Carlo of the same families: bench/rate_table_mc.sh (docs/accuracy.md).
#include <cmath>
#include <functional>

#include "filter/plausibility/plausibility.hpp"
#include "filter/rate_table/rate_table.hpp"
#include "helpers.hpp"
#include "models/units.hpp"
#include "rig/session.hpp"

using namespace sinscal;
using namespace sinscal::test;

namespace {

double truth_of(ImuErrorModel truth, const RateCoefficient& c) {
  if (c.name.rfind("gyro.k2.", 0) == 0) return truth.gyro.k2(c.name.back() - 'x');
  if (!c.in_catalog) return 0.0;  // accel.k3: not simulated
  for (auto& [info, ptr] : truth.coefficient_refs())
    if (info.name == c.name) return *ptr;
  FAIL("no truth for " << c.name);
  return 0.0;
}

struct FamilyStats {
  double sum2 = 0.0, worst = 0.0;
  int n = 0;
  std::vector<std::string> names;  // of the first seed's estimates
};

// Alters the segments' means before the fit (an effect the simulation's truth does not have).
using AlterMeans = std::function<void(const std::vector<RateSegment>&, std::vector<SegmentMean>&)>;

RateTableResult calibrate_simulated(const std::string& plan, std::uint64_t seed,
                                    ImuErrorModel& truth, double table_sigma = 0.0,
                                    const AlterMeans& alter = nullptr) {
  SessionSimulation spec;
  spec.plan_path = source_path("config/plans/" + plan);
  spec.data_sensor_path = source_path("config/sensors/tactical-rate.ini");
  spec.rate_hz = 50.0;
  spec.seed = seed;
  spec.table.attitude_sigma = table_sigma;
  spec.table.seed = seed + 1000;
  const auto sim = simulate_session(temp_dir("rate_table_" + plan + std::to_string(seed)), spec);
  truth = sim.truth;
  const Session session = Session::load(sim.session_path);
  RateTableOptions o;
  o.nominal_rate_hz = session.rate_hz;
  o.table_sigma = table_sigma;
  const auto segments = rate_segments(session.plan, session.site);
  auto means = find_segments(read_rate_readings(session.log), segments, o);
  if (alter) alter(segments, means);
  return rate_table_calibrate(segments, means, session.site, 0.0, o);
}

FamilyStats run_family(const std::string& plan, int seeds, double table_sigma = 0.0) {
  FamilyStats s;
  for (int k = 1; k <= seeds; ++k) {
    ImuErrorModel truth;
    const auto r = calibrate_simulated(plan, static_cast<std::uint64_t>(k), truth, table_sigma);
    for (const auto& c : r.coefficients) {
      const double z = (c.value - truth_of(truth, c)) / c.sigma;
      s.sum2 += z * z;
      s.worst = std::max(s.worst, std::abs(z));
      ++s.n;
      if (k == 1) s.names.push_back(c.name);
    }
  }
  return s;
}

bool has(const std::vector<std::string>& v, const std::string& name) {
  return std::find(v.begin(), v.end(), name) != v.end();
}

// RMS of error / sigma over n estimates: 1 within the chi-square spread of n values (a few
// seeds: the bounds are wide; the 30-seed Monte Carlo sets 0.8-1.25).
void check_consistent(const FamilyStats& s) {
  const double rms = std::sqrt(s.sum2 / s.n);
  INFO("estimates " << s.n << ", RMS error/sigma " << rms << ", worst " << s.worst);
  CHECK(rms > 1.0 - 4.0 / std::sqrt(2.0 * s.n));
  CHECK(rms < 1.0 + 4.0 / std::sqrt(2.0 * s.n));
  CHECK(s.worst < 5.0);
}

}  // namespace

TEST_CASE("rate table: gyro scale, misalignment, asymmetry and K2 across rates from means",
          "[rate_table]") {
  const FamilyStats s = run_family("rate-table.ini", 3);
  CHECK(has(s.names, "gyro.scale.x"));
  CHECK(has(s.names, "gyro.misalignment.zy"));
  CHECK(has(s.names, "gyro.scale_asym.z"));
  CHECK(has(s.names, "gyro.k2.y"));
  CHECK_FALSE(has(s.names, "accel.scale.x"));  // one attitude: the accelerometers undetermined
  check_consistent(s);
}

TEST_CASE("tumble: accelerometer bias, scale, misalignment, K2, K3 from static means",
          "[rate_table]") {
  const FamilyStats s = run_family("tumble.ini", 3, 2.5 * units::arcsec);
  for (const char* n : {"accel.bias.z", "accel.misalignment.xy", "accel.k2.y", "accel.k3.x",
                        "gyro.g_sensitivity.zx"})
    CHECK(has(s.names, n));
  check_consistent(s);
}

TEST_CASE("three-axis table: six faces at any attitude, simulated and calibrated", "[rate_table]") {
  const Plan plan = load_plan("six-face-3axis.ini");
  CHECK(plan.table.axes == 3);
  const Motion motion = build_motion(plan, plan.site);
  // "+y up, heading 0": the specific force along +y is g.
  const Eigen::Vector3d f =
      motion.at(0.5 * (motion.dwells()[2].t_start + motion.dwells()[2].t_end)).imu.f_ib_b;
  CHECK(f.y() > 9.7);
  // The same plan with a two-axis table is refused (not reachable).
  std::string text = plan.text;
  text.replace(text.find("\naxes = 3"), 9, "\naxes = 2");
  CHECK_THROWS_WITH(Plan::parse("two.ini", text), Catch::Contains("not reachable"));
  const FamilyStats s = run_family("six-face-3axis.ini", 3, 2.5 * units::arcsec);
  CHECK(has(s.names, "accel.scale.y"));
  check_consistent(s);
}

TEST_CASE("mixed session: rate segments and static positions in one least squares",
          "[rate_table]") {
  const FamilyStats s = run_family("rate-mixed.ini", 3, 2.5 * units::arcsec);
  for (const char* n :
       {"gyro.scale.z", "gyro.scale_asym.x", "accel.misalignment.zx", "gyro.g_sensitivity.xy"})
    CHECK(has(s.names, n));
  check_consistent(s);
}

TEST_CASE("rate table: the segments found without the log's time", "[rate_table]") {
  const Plan plan = load_plan("rate-mixed.ini");
  const auto segments = rate_segments(plan, plan.site);
  REQUIRE(segments.size() == 18);
  CHECK(segments[1].kind == RateSegment::Kind::Rate);
  CHECK(segments[1].axis_b.z() == Approx(1.0));
  // A log whose readings come at irregular intervals: the same means (readings, not time).
  const Motion motion = build_motion(plan, plan.site);
  std::vector<RateReading> readings;
  double t = 0.0;
  for (int k = 0; t < motion.duration(); ++k) {
    const auto s = motion.at(t);
    readings.push_back({s.imu.omega_ib_b, s.imu.f_ib_b});
    t += 0.01 * (1.0 + 0.5 * std::sin(0.37 * k));  // 67-200 Hz
  }
  RateTableOptions o;
  o.nominal_rate_hz = 100.0;
  const auto means = find_segments(readings, segments, o);
  const auto r = rate_table_calibrate(segments, means, plan.site, 0.0, o);
  // A perfect IMU: every estimate near zero (the Earth rate modelled: a sign flip of it would
  // show as a gyro bias of 2 x 15 deg/h).
  for (const auto& c : r.coefficients)
    if (c.name.rfind("gyro.bias", 0) == 0) CHECK(std::abs(c.value) < 0.01 * units::deg_per_h);
}

TEST_CASE("rate table: the fit's gate passes a clean session, refuses what the model lacks",
          "[rate_table][plausibility]") {
  const PlausibilityLimits limits = PlausibilityLimits::from_profile(nullptr);
  const double table_sigma = 2.5 * units::arcsec;
  ImuErrorModel truth;
  const auto clean = calibrate_simulated("rate-mixed.ini", 4, truth, table_sigma);
  REQUIRE(clean.triad_fits.size() == 2);
  const PlausibilityCheck ok = check_rate_table_fit(clean, limits, "imu.csv");
  INFO(ok.detail);
  CHECK(ok.passed);
  // A gyro offset present only while the table turns (the model's gyro biases are the same at
  // rest and turning), 30 sigma of a rate segment's mean: the gyros' fit is refused.
  const auto turning_offset = [](const std::vector<RateSegment>& seg, std::vector<SegmentMean>& m) {
    std::size_t first = 0;
    while (seg[first].kind != RateSegment::Kind::Rate) ++first;
    const double sigma = std::sqrt(m[first].var_omega.dot(seg[first].axis_b.cwiseAbs2()) /
                                   static_cast<double>(m[first].count));
    for (std::size_t i = 0; i < seg.size(); ++i)
      if (seg[i].kind == RateSegment::Kind::Rate)
        m[i].omega += 30.0 * sigma * Eigen::Vector3d(1.0, 1.0, 1.0).normalized();
  };
  const auto bad = calibrate_simulated("rate-mixed.ini", 4, truth, table_sigma, turning_offset);
  const PlausibilityCheck refused = check_rate_table_fit(bad, limits, "imu.csv");
  INFO(refused.detail);
  for (const auto& t : bad.triad_fits) INFO(t.triad << " chi2 " << t.chi2 << " dof " << t.dof);
  CHECK_FALSE(refused.passed);
  CHECK_THAT(refused.detail, Catch::Contains("imu.csv: the gyros' chi2 per dof") &&
                                 Catch::Contains("a gyro offset while turning"));
  CHECK_THAT(refused.detail, !Catch::Contains("accelerometers"));
  // Noise densities 3 times too small (the means' variances 9 times): both triads refused.
  const auto quiet = [](const std::vector<RateSegment>&, std::vector<SegmentMean>& m) {
    for (auto& x : m) {
      x.var_omega /= 9.0;
      x.var_f /= 9.0;
    }
  };
  const auto q = calibrate_simulated("rate-mixed.ini", 4, truth, 0.0, quiet);
  const PlausibilityCheck q_check = check_rate_table_fit(q, limits, "imu.csv");
  INFO(q_check.detail);
  CHECK_FALSE(q_check.passed);
  CHECK_THAT(q_check.detail, Catch::Contains("gyros'") && Catch::Contains("accelerometers'"));
}

TEST_CASE("Rate table: a refusal names the largest residual of the triad that failed",
          "[rate_table][plausibility]") {
  // A fit whose gyros fail and whose accelerometers pass may still have its largest whitened
  // residual in an accelerometer row: the gyros' refusal names the gyros' largest.
  RateTableResult r;
  Eigen::Matrix<double, 6, 1> z;
  z << 2.0, -3.0, 1.0, 0.5, 5.0, -0.2;
  r.residual_sigma = {z};
  RateSegment s;
  s.label = "start";
  s.number = 4;
  CHECK(largest_residual(r, {s}) == "segment 4 (start): accelerometer y +5.0 sigma");
  CHECK(largest_residual(r, {s}, "gyro") == "segment 4 (start): gyro y -3.0 sigma");
  CHECK(largest_residual(r, {s}, "accel") == "segment 4 (start): accelerometer y +5.0 sigma");
  // The failed triads by check_rate_table_fit's rule: gyros 30 on 3 dof fail, the
  // accelerometers' 3 on 3 pass.
  r.triad_fits = {{"gyro", 30.0, 3}, {"accel", 3.0, 3}};
  const auto failed = failed_rate_table_triads(r, PlausibilityLimits::from_profile(nullptr));
  REQUIRE(failed.size() == 1);
  CHECK(failed.front() == "gyro");
}
