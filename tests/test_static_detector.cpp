// Static intervals detected from the data, and the Kalman filter run on them when the log's
// timing does not follow the plan.
#include <catch2/catch.hpp>
#include <cmath>

#include "filter/kalman/kalman_calibrator.hpp"
#include "filter/noise/static_detector.hpp"
#include "helpers.hpp"
#include "models/units.hpp"
#include "rig/imu_sim.hpp"

using namespace sinscal;

namespace {
// Largest |estimate - truth| / sigma over the estimated coefficients.
double max_error_over_sigma(const std::vector<CoefficientEstimate>& est,
                            const ImuErrorModel& truth) {
  double worst = 0.0;
  const auto t = truth.coefficients();
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (est[i].status != CoefficientEstimate::Status::Estimated) continue;
    const double e = est[i].value / cat[i].si_per_unit - t.at(cat[i].name);
    worst = std::max(worst, std::abs(e) / (est[i].sigma / cat[i].si_per_unit));
  }
  return worst;
}

Plan rot19_with(const std::string& from, const std::string& to) {
  const Plan base = test::load_plan("rot19.ini");
  std::string text = base.text;
  const auto at = text.find(from);
  REQUIRE(at != std::string::npos);
  text.replace(at, from.size(), to);
  return Plan::parse("rot19-variant", text);
}
}  // namespace

TEST_CASE("Static detector finds rot19's dwells where the motion has them", "[long][static]") {
  const Plan p = test::load_plan("rot19.ini");
  const Motion m = build_motion(p, p.site);
  // A FOG unit, a consumer MEMS unit (biases up to 0.5 deg/s, noise 50x the FOG's), and the FOG's
  // errors without noise (the bounds' floors).
  for (const char* profile :
       {"config/sensors/nav-fog-extended.ini", "config/sensors/mems.ini", "noise-free"}) {
    const bool noise_free = std::string(profile) == "noise-free";
    const SensorProfile prof = SensorProfile::load(
        test::source_path(noise_free ? "config/sensors/nav-fog-extended.ini" : profile));
    const NoiseModel noise = noise_free ? NoiseModel{} : prof.noise;
    const auto samples = test::simulate(m, prof.draw(5), 100.0, noise_free ? nullptr : &noise, 6);
    StaticDetector det(noise);
    for (const auto& s : samples) det.push(s);
    CAPTURE(profile, det.gyro_bound() / units::deg_per_s, det.accel_bound() / units::ug);
    REQUIRE(det.dwells().size() == m.dwells().size());
    for (std::size_t k = 0; k < m.dwells().size(); ++k) {
      const Dwell& truth = m.dwells()[k];
      const DetectedDwell& found = det.dwells()[k];
      CAPTURE(k, truth.t_start, truth.t_end, found.t_start, found.t_end);
      CHECK(found.index == static_cast<int>(k) + 1);
      // The table accelerates at 10 deg/s^2: within a few samples of the start and end of rest
      // the rate leaves the noise bound (FOG: 0.001 deg/s, 1 sample; MEMS: 0.3 deg/s, 3-4).
      CHECK(std::abs(found.t_start - truth.t_start) < 0.1);
      if (k + 1 < m.dwells().size()) CHECK(std::abs(found.t_end - truth.t_end) < 0.1);
    }
  }
}

TEST_CASE("Kalman filter with dwells from the data: a log whose timing is off the plan",
          "[long][kalman][static]") {
  // The data rest 12.3 s longer at the start than the plan says, so every later dwell is 12.3 s
  // late against the plan: with the plan's timing the attitude updates come mid-turn.
  const Plan data_plan = rot19_with("dwell = 70 s", "dwell = 82.3 s");
  const Plan plan = test::load_plan("rot19.ini");
  const SensorProfile prof =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-extended.ini"));
  const ImuErrorModel truth = prof.draw(derive_seed(11, 1));
  const auto samples = test::simulate(build_motion(data_plan, data_plan.site), truth, 100.0,
                                      &prof.noise, derive_seed(11, 2));
  const Motion m = build_motion(plan, plan.site);
  auto worst_z = [&](CalibratorOptions::StaticFrom from) {
    CalibratorOptions o = calibrator_options_from_profile(prof);
    o.static_from = from;
    Calibrator kf(test::timeline(plan), plan.site, o);
    for (const auto& s : samples) kf.push(s);
    kf.finish();
    const double worst = max_error_over_sigma(kf.estimate(), truth);
    if (from == CalibratorOptions::StaticFrom::Data) {
      REQUIRE(kf.detector() != nullptr);
      CHECK(kf.detector()->dwells().size() == m.dwells().size());
      CHECK(kf.detector()->dwells()[1].t_start - m.dwells()[1].t_start == Approx(12.3).margin(0.1));
    }
    return worst;
  };
  // From the data: every coefficient within 4 sigma of the truth (the consistency bound of the
  // Monte Carlo tests). From the plan's timing: far off.
  CHECK(worst_z(CalibratorOptions::StaticFrom::Data) < 4.0);
  double plan_z = 0.0;
  try {
    plan_z = worst_z(CalibratorOptions::StaticFrom::Plan);
  } catch (const std::runtime_error&) {
    plan_z = HUGE_VAL;  // the estimates run away until the error model cannot be inverted
  }
  CHECK(plan_z > 10.0);
}

TEST_CASE("Kalman filter with dwells from the data: more static intervals than the plan's dwells",
          "[long][kalman][static]") {
  // The data follow rot19; the plan stops three turns earlier.
  const Plan full = test::load_plan("rot19.ini");
  const Plan shorter = rot19_with("-x -x -x +z +z -z -z -z\n", "-x -x -x +z +z\n");
  const SensorProfile prof =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-extended.ini"));
  const auto samples =
      test::simulate(build_motion(full, full.site), prof.draw(3), 100.0, &prof.noise, 4);
  CalibratorOptions o = calibrator_options_from_profile(prof);
  o.static_from = CalibratorOptions::StaticFrom::Data;
  Calibrator kf(test::timeline(shorter), shorter.site, o);
  CHECK_THROWS_AS(
      [&] {
        for (const auto& s : samples) kf.push(s);
      }(),
      PlanDataMismatch);
  CHECK_THROWS_WITH(
      [&] {
        Calibrator again(test::timeline(shorter), shorter.site, o);
        for (const auto& s : samples) again.push(s);
      }(),
      Catch::Contains("static interval 17 found in the data") &&
          Catch::Contains("the plan has 16 dwells"));
  // What was estimated before stays available.
  CHECK(kf.estimate()[0].status == CoefficientEstimate::Status::Estimated);
}

TEST_CASE("Kalman filter with a table-angle column: the attitude the table really reached",
          "[long][kalman][table]") {
  // The table misses each commanded orientation by 30 arcsec per axis (1-sigma); its encoders
  // read where it went. With the plan's orientations (taken as known to 2.5 arcsec) the attitude
  // updates are wrong by far more than their sigma; with the logged angles they are right.
  const Plan plan = test::load_plan("seed8.ini");
  const SensorProfile prof = SensorProfile::load(test::source_path("config/sensors/nav-fog.ini"));
  TableErrors table;
  table.angle_sigma = 30.0 * units::arcsec;
  table.seed = 21;
  const Motion truth_motion = build_motion(plan, plan.site, table);
  const ImuErrorModel truth = prof.draw(derive_seed(22, 1));
  SimulatorOptions so;
  so.noise_seed = derive_seed(22, 2);
  so.table_angles = true;
  ImuSimulator sim(truth_motion, truth, prof.noise, so);
  std::vector<ImuSample> samples;
  for (ImuSample s; sim.next(s);) samples.push_back(s);
  REQUIRE(samples.front().has_table);

  auto worst_z = [&](bool use_angles) {
    CalibratorOptions o = calibrator_options_from_profile(prof);
    o.use_table_angles = use_angles;
    Calibrator kf(test::timeline(plan), plan.site, o);
    for (const auto& s : samples) kf.push(s);
    kf.finish();
    // Every update of the 8 dwells takes the angles (the attitude held through each dwell).
    if (use_angles)
      CHECK(kf.table_attitude_updates() > 8 * 10);
    else
      CHECK(kf.table_attitude_updates() == 0);
    const double worst = max_error_over_sigma(kf.estimate(), truth);
    return worst;
  };
  CHECK(worst_z(true) < 4.0);
  CHECK(worst_z(false) > 6.0);
}

TEST_CASE("Table-angle column far from the plan's orientation: a plan mismatch",
          "[kalman][table]") {
  // The log's angles belong to seed8's orientations in another order (2 and 3 swapped).
  const Plan plan = test::load_plan("seed8.ini");
  std::string text = plan.text;
  const auto a = text.find("[orientation.2]"), b = text.find("[orientation.3]");
  REQUIRE((a != std::string::npos && b != std::string::npos));
  text.replace(b, 15, "[orientation.X]");
  text.replace(a, 15, "[orientation.3]");
  text.replace(text.find("[orientation.X]"), 15, "[orientation.2]");
  const Plan swapped = Plan::parse("seed8-swapped", text);
  const SensorProfile prof = SensorProfile::load(test::source_path("config/sensors/nav-fog.ini"));
  const Motion data_motion = build_motion(swapped, swapped.site);
  SimulatorOptions so;
  so.noise = false;
  so.table_angles = true;
  ImuSimulator sim(data_motion, prof.draw(1), prof.noise, so);
  CalibratorOptions o = calibrator_options_from_profile(prof);
  Calibrator kf(test::timeline(plan), plan.site, o);
  CHECK_THROWS_WITH(
      [&] {
        for (ImuSample s; sim.next(s);) kf.push(s);
      }(),
      Catch::Contains("dwell 2 (2)") && Catch::Contains("from the plan's orientation"));
}
