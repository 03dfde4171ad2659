// Plan design (filter/design/prediction.hpp): the covariance pass over a plan's truth motion
// predicts the sigmas a calibration of that plan reports and the spread of its errors; table
// descriptions and the plan's limits against them.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <map>

#include "filter/design/advice.hpp"
#include "filter/design/bound.hpp"
#include "filter/design/hand_plans.hpp"
#include "filter/design/prediction.hpp"
#include "filter/design/robustness.hpp"
#include "filter/design/rounding.hpp"
#include "filter/design/search.hpp"
#include "filter/kalman/kalman_run.hpp"
#include "filter/kalman/misalignment_frame.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/config.hpp"
#include "models/units.hpp"
#include "rig/table_spec.hpp"

using namespace sinscal;

namespace {

const char* kFog = "config/sensors/nav-fog-extended.ini";

struct Calibration {
  KalmanRun run;
  Eigen::VectorXd truth;  // SI, catalog order
};

// What `calibrate --method kf` does with a session of `plan` simulated at `rate_hz` from the
// profile (coefficients drawn and noise, seed `seed`), the samples streamed to the filter.
Calibration calibrate_simulated(const Plan& plan, const SensorProfile& prof,
                                const CalibratorOptions& ko, double rate_hz, std::uint64_t seed,
                                const TableErrors& table = {}) {
  const Motion motion = build_motion(plan, plan.site, table);
  Calibration c;
  const ImuErrorModel truth = prof.draw(seed);
  c.truth = truth.vector();
  SimulatorOptions so;
  so.rate_hz = rate_hz;
  so.noise_seed = seed + 1000;
  ImuSimulator sim(motion, truth, prof.noise, so);
  KalmanRunOptions run;
  run.align = false;
  c.run = run_kalman(design_session(plan, rate_hz), ko, &sim, run);
  return c;
}

void check_equal_sigmas(const std::string& plan_file, double rate_hz) {
  const Plan plan = test::load_plan(plan_file);
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  DesignOptions d;
  d.rate_hz = rate_hz;
  const PlanPrediction p = predict_plan(plan, ko, prof.sigma_targets, d);
  const Calibration c = calibrate_simulated(plan, prof, ko, rate_hz, 7);
  const auto& cat = coefficient_catalog();
  int compared = 0;
  double worst = 0.0;
  for (std::size_t i = 0; i < cat.size(); ++i) {
    const auto& e = p.run.estimates[i];
    REQUIRE(e.status == c.run.estimates[i].status);
    if (e.status != CoefficientEstimate::Status::Estimated) continue;
    CAPTURE(plan_file, cat[i].name, e.sigma, c.run.estimates[i].sigma);
    // The acceptance: within 5 % (the pass differs from the calibration only by its
    // linearization point, the truth instead of the estimate).
    CHECK(e.sigma == Approx(c.run.estimates[i].sigma).epsilon(0.05));
    worst = std::max(worst, std::abs(e.sigma / c.run.estimates[i].sigma - 1.0));
    ++compared;
  }
  WARN(plan_file << ": " << compared << " sigmas, worst relative difference " << worst);
  CHECK(compared >= 30);
}

}  // namespace

TEST_CASE("Design: predicted sigmas are those the calibration of the plan reports (rot19)",
          "[design][kalman]") {
  check_equal_sigmas("rot19.ini", 50.0);
}

TEST_CASE("Design: predicted sigmas are those the calibration of the plan reports (seed8)",
          "[design][kalman][long]") {
  check_equal_sigmas("seed8.ini", 50.0);
}

TEST_CASE("Design: the error spread over simulated sessions matches the predicted sigmas",
          "[design][kalman][long]") {
  // Per family, the RMS over seeds and components of error / predicted sigma within 0.8-1.25
  // (the band; with 30 seeds and 3 or more components the RMS of a consistent filter
  // has a relative spread of at most 1/sqrt(2 * 30 * 3) = 7.5 %, so the band is 3 of them).
  // The calibration's default filter (an attitude update at every dwell, the base estimated)
  // on sessions whose table sets every dwell to its 2.5 arcsec (TableErrors::attitude_sigma).
  const char* env = std::getenv("SINSCAL_DESIGN_MC_SEEDS");
  const int seeds = env ? std::atoi(env) : 30;
  // SINSCAL_DESIGN_MC_PLAN: another plan of config/plans (the documented command runs the
  // searched plan too).
  const char* plan_env = std::getenv("SINSCAL_DESIGN_MC_PLAN");
  const Plan plan = test::load_plan(plan_env ? plan_env : "rot19.ini");
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  DesignOptions d;
  const char* rate_env = std::getenv("SINSCAL_DESIGN_MC_RATE");  // Hz, of sessions and design
  d.rate_hz = rate_env ? std::atof(rate_env) : 20.0;
  const PlanPrediction p = predict_plan(plan, ko, prof.sigma_targets, d);
  const auto& cat = coefficient_catalog();
  std::map<std::string, std::pair<double, int>> sum;  // family: sum of squares, count
  for (int k = 0; k < seeds; ++k) {
    TableErrors table;
    table.attitude_sigma = ko.attitude_sigma;
    table.seed = 500 + static_cast<std::uint64_t>(k);
    const Calibration c = calibrate_simulated(plan, prof, ko, d.rate_hz, 100 + k, table);
    for (std::size_t i = 0; i < cat.size(); ++i) {
      // Coefficients the plan observes: an unobserved one keeps its prior, and the profile draws
      // its truth from its range, not from the prior, so its ratio says nothing of the filter.
      if (!p.run.estimates[i].observed()) continue;
      const double z = (c.run.estimates[i].value - c.truth(static_cast<Eigen::Index>(i))) /
                       p.run.estimates[i].sigma;
      sum[cat[i].family].first += z * z;
      ++sum[cat[i].family].second;
    }
  }
  for (const auto& [family, s] : sum) {
    const double rms = std::sqrt(s.first / s.second);
    CAPTURE(family, s.second, rms);
    WARN(family << ": RMS error / predicted sigma " << rms << " over " << s.second);
    CHECK(rms > 0.8);
    CHECK(rms < 1.25);
  }
}

TEST_CASE("Design: a family's target and the time it is reached", "[design]") {
  const Plan plan = test::load_plan("rot19.ini");
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  DesignOptions d;
  d.rate_hz = 20.0;
  std::map<std::string, double> targets = {{"accel.lever_arm", 2e-3}, {"gyro.bias", 1e-9}};
  const PlanPrediction p = predict_plan(plan, calibrator_options_from_profile(prof), targets, d);
  REQUIRE(!p.history.empty());
  for (const auto& f : p.families) {
    if (f.family == "accel.lever_arm") {
      REQUIRE(f.reached_at);
      CHECK(f.meets_target());
      // Before the time reached some lever arm is above 2 mm, from it on none is.
      CHECK(*f.reached_at > 70.0);
      CHECK(*f.reached_at < p.duration);
    }
    if (f.family == "gyro.bias") {
      CHECK_FALSE(f.reached_at);
      CHECK_FALSE(f.meets_target());
    }
  }
  CHECK_FALSE(p.meets_targets());
  CHECK_FALSE(p.last_to_reach());
}

TEST_CASE("Design: table descriptions are read and checked", "[design][input]") {
  const TableSpec t = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  CHECK(t.max_rate == Approx(20.0 * units::deg_per_s));
  CHECK(t.max_acceleration == Approx(20.0 * units::deg_per_s));
  CHECK(t.attitude_sigma == Approx(2.5 * units::arcsec));
  CHECK(t.reference_on_axes);
  const std::string ok =
      "[table]\nmax_rate = 20 deg/s\nmax_acceleration = 20 deg/s^2\nattitude_accuracy = 2 "
      "arcsec\n";
  CHECK_NOTHROW(TableSpec::parse("t.ini", ok));
  CHECK_THROWS_WITH(TableSpec::parse("t.ini", ok + "max_speed = 3 deg/s\n"),
                    Catch::Contains("t.ini") && Catch::Contains("max_speed"));
  CHECK_THROWS_WITH(TableSpec::parse("t.ini", "[table]\nmax_rate = -1 deg/s\n"),
                    Catch::Contains("t.ini:2") && Catch::Contains("positive"));
  CHECK_THROWS_WITH(TableSpec::parse("t.ini", "[table]\nmax_rate = 20 m/s\n"),
                    Catch::Contains("t.ini:2"));
  CHECK_THROWS(TableSpec::parse("t.ini", "[table]\nmax_acceleration = 20 deg/s^2\n"));
}

TEST_CASE("Design: a plan beyond the table's rate, acceleration or settling is named",
          "[design][input]") {
  const Plan plan = test::load_plan("rot19.ini");  // 90 deg in 9 s at 10 deg/s^2: peak 11.3 deg/s
  const Motion m = build_motion(plan, plan.site);
  TableSpec t = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  CHECK(check_against_table(m, t, 0.5).empty());
  t.max_rate = 10.0 * units::deg_per_s;
  auto v = check_against_table(m, t, 0.5);
  REQUIRE(v.size() == 18);  // every turn
  CHECK(v[0].segment == 2);
  CHECK(v[0].what.find("peak rate 11.") != std::string::npos);
  t.max_rate = 20.0 * units::deg_per_s;
  t.max_acceleration = 5.0 * units::deg_per_s;
  v = check_against_table(m, t, 0.5);
  REQUIRE(v.size() == 18);
  CHECK(v[0].what.find("angular acceleration 10.000") != std::string::npos);
  t.max_acceleration = 20.0 * units::deg_per_s;
  t.settling_time = 19.8;  // the 20 s pauses keep 0.5 s from each end
  v = check_against_table(m, t, 0.5);
  REQUIRE(v.size() == 18);
  CHECK(v[0].what.find("settling") != std::string::npos);
}

namespace {

SearchOptions lab_targets() {
  // The reference toolbox's errors on its 19-position log (issue 17), SI.
  SearchOptions so;
  so.targets = {{"gyro.bias", 0.0054 * units::deg_per_h},
                {"gyro.scale", 1.4e-6},
                {"gyro.misalignment", 0.48 * units::arcsec},
                {"accel.bias", 2.1e-6 * 9.80665},
                {"accel.scale", 1.2e-6},
                {"accel.misalignment", 0.30 * units::arcsec},
                {"accel.k2", 2.2e-6 / 9.80665},
                {"accel.lever_arm", 2.1e-3},
                {"time_delay", 0.05e-3}};
  return so;
}

}  // namespace

TEST_CASE("Plan search: a searched plan is a plan file, and its incremental passes are exact",
          "[design][search]") {
  const TableSpec table = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  const Plan rot19 = test::load_plan("rot19.ini");
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  PlanGenome g;
  g.start = 0;
  g.start_dwell = 10.0;
  g.turns = {
      {2, 90.0 * units::deg, 2.5}, {0, 180.0 * units::deg, 10.0}, {5, 90.0 * units::deg, 2.5}};
  const Plan p = plan_of(g, table, rot19.site, "searched");
  REQUIRE(p.steps.size() == 3);
  CHECK(p.steps[1].angle == Approx(180.0 * units::deg));
  CHECK(p.steps[1].duration == Approx(10.0));  // 180 deg at 20 deg/s and 20 deg/s^2, on 0.1 s
  CHECK(p.steps[2].pause == Approx(2.5));
  // Within the table's limits, and the same plan read back from its text.
  CHECK(check_against_table(build_motion(p, p.site), table, 0.5).empty());
  const Plan again = Plan::parse("again.ini", plan_text(g, table, rot19.site, "searched"));
  CHECK(again.text == p.text);
  // The search's pass (one filter grown turn by turn) against the design's own pass over the
  // whole plan at the same rate: the same excess.
  SearchOptions so = lab_targets();
  so.rate_hz = 20.0;
  const Excess e = evaluate_genome(g, ko, table, rot19.site, so);
  DesignOptions d;
  d.rate_hz = 20.0;
  const PlanPrediction full = predict_plan(p, ko, so.targets, d);
  const Excess f = excess(full.run.estimates, so.targets);
  CHECK(e.J == Approx(f.J).epsilon(1e-6));
  CHECK(e.worst_family == f.worst_family);
}

TEST_CASE("Plan search: the beam against every plan of four turns", "[design][search][long]") {
  // Turns of 90 deg about the 6 axes after a 10 s start with body x up, 2.5 s dwells: 6^4 =
  // 1296 plans of four turns, all of one duration (so the beam's gain per second ranks as J).
  const TableSpec table = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  const Plan rot19 = test::load_plan("rot19.ini");
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  SearchOptions so = lab_targets();
  so.rate_hz = 10.0;
  SearchSpace space;
  space.starts = {0};
  space.start_dwells = {10.0};
  space.pauses = {2.5};
  space.angles = {90.0 * units::deg};
  int scored = 0;
  const auto best = enumerate_plans(ko, table, rot19.site, space, so, 4, &scored);
  CHECK(scored == 1296);
  for (const int beam : {1, 4}) {
    so.beam = beam;
    const auto found = beam_plans(ko, table, rot19.site, space, so, 4);
    REQUIRE(found.first.turns.size() == 4);
    CAPTURE(beam, best.second.J, found.second.J);
    // The enumeration is the optimum: the beam cannot beat it.
    CHECK(found.second.J >= best.second.J - 1e-9);
    WARN("beam " << beam << ": J " << found.second.J << " against the best of " << scored
                 << " plans " << best.second.J << " (gap "
                 << 100.0 * (found.second.J - best.second.J) / best.second.J << " %)");
  }
}

TEST_CASE("Plan search: the shortest plan meeting reachable targets", "[design][search][long]") {
  // Targets a few minutes reach: the search meets them, and the refined plan still does.
  const TableSpec table = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  const Plan rot19 = test::load_plan("rot19.ini");
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  SearchOptions so;
  so.rate_hz = 10.0;
  so.beam = 2;
  so.targets = {{"gyro.scale", 3e-6}, {"accel.scale", 3e-6}, {"accel.lever_arm", 2e-3}};
  const SearchResult r = search_plan(ko, table, rot19.site, SearchSpace{}, so);
  CHECK(r.meets);
  CHECK(r.excess.J == 0.0);
  CHECK(r.plan.steps.size() >= 2);
  const double duration = build_motion(r.plan, r.plan.site).duration();
  CHECK(duration <= r.duration_before_refinement + 1e-9);
  CHECK(duration < 300.0);
  // One turn fewer (the last) no longer meets them: the refinement left none to spare.
  PlanGenome shorter = r.best;
  shorter.turns.pop_back();
  if (!shorter.turns.empty()) CHECK(evaluate_genome(shorter, ko, table, rot19.site, so).J > 0.0);
  // A budget below the time they need: the best within it, not meeting.
  so.budget_s = 40.0;
  const SearchResult b = search_plan(ko, table, rot19.site, SearchSpace{}, so);
  CHECK_FALSE(b.meets);
  CHECK(build_motion(b.plan, b.plan.site).duration() <= 40.0 + 1e-9);
}

TEST_CASE("Plan search: --require, the shortest plan that determines a family",
          "[design][search]") {
  // The lever arms and the time delay show only in turns: the search for a plan that determines
  // them finds one of a few turns, and the full pass confirms they are observed (below prior /
  // sqrt(2) and in no unobservable combination); one turn fewer does not determine them.
  const TableSpec table = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  const Plan rot19 = test::load_plan("rot19.ini");
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  DesignOptions d;
  d.rate_hz = 10.0;
  const PlanPrediction ref = predict_plan(rot19, ko, {}, d);
  SearchOptions so;
  so.rate_hz = 10.0;
  so.beam = 2;
  so.targets = required_targets({}, {"accel.lever_arm", "time_delay"}, ref.run.estimates);
  REQUIRE(so.targets.size() == 2);
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i)
    if (cat[i].family == "accel.lever_arm")
      CHECK(so.targets.at("accel.lever_arm") ==
            Approx(kRequiredFraction * ref.run.estimates[i].prior_sigma));
  // A given target smaller than half the prior stays; a larger one is lowered.
  CHECK(required_targets({{"time_delay", 1e-6}}, {"time_delay"}, ref.run.estimates)
            .at("time_delay") == 1e-6);
  CHECK(
      required_targets({{"time_delay", 1.0}}, {"time_delay"}, ref.run.estimates).at("time_delay") ==
      Approx(so.targets.at("time_delay")));
  const SearchResult r = search_plan(ko, table, rot19.site, SearchSpace{}, so);
  REQUIRE(r.meets);
  const PlanPrediction p = predict_plan(r.plan, ko, so.targets, d);
  for (const auto& f : p.families)
    if (f.family == "accel.lever_arm" || f.family == "time_delay") {
      CAPTURE(f.family, f.worst_sigma);
      CHECK(f.observed);
    }
  CHECK(p.duration < 120.0);
  PlanGenome shorter = r.best;
  shorter.turns.pop_back();
  if (!shorter.turns.empty()) CHECK(evaluate_genome(shorter, ko, table, rot19.site, so).J > 0.0);
  // A family the profile does not estimate is refused by name.
  CHECK_THROWS_WITH(required_targets({}, {"gyro.g_sensitivity"}, ref.run.estimates),
                    Catch::Matchers::Contains("gyro.g_sensitivity"));
}

TEST_CASE("Design robustness: the nominal world as predicted, twice the noise twice the errors",
          "[design][robustness][long]") {
  // rot19 at 20 Hz, 8 sessions per perturbation. Nominal: the RMS of error / predicted sigma of
  // a family of n errors has a relative spread of 1/sqrt(2 n) (n >= 24: 14 %), so 0.6-1.45 is
  // beyond 2.5 of them. Twice the white noise: the families the noise limits (scale factors,
  // K2) come out near 2 (their sigma is noise-limited on this plan), the misalignments, which
  // the table's attitude accuracy limits, stay near 1; a table twice worse does the opposite.
  const Plan plan = test::load_plan("rot19.ini");
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  const auto rows = robustness(plan, prof, ko, standard_perturbations(), 8, 20.0);
  REQUIRE(rows.size() == 4);
  for (const auto& [family, r] : rows[0].rms_ratio) {
    CAPTURE(family, r);
    CHECK(r > 0.6);
    CHECK(r < 1.45);
  }
  const auto& table2 = rows[1].rms_ratio;
  const auto& noise2 = rows[3].rms_ratio;
  CHECK(noise2.at("accel.scale") > 1.5);
  CHECK(noise2.at("accel.k2") > 1.5);
  CHECK(noise2.at("accel.misalignment") < 1.45);
  CHECK(table2.at("accel.misalignment") > 1.4);
  CHECK(table2.at("gyro.misalignment") > 1.4);
  CHECK(table2.at("accel.scale") < 1.45);
  CHECK_THROWS_AS(robustness(plan, prof, ko, standard_perturbations(), 1, 20.0),
                  std::invalid_argument);
}

TEST_CASE("Design advice: the turn that separates a family the plan does not observe",
          "[design][advice][long]") {
  // Turns about y only: the accelerometer misalignments and bias, with x and z never turned,
  // are not observed; a turn about z is what separates them. rot19 observes every family.
  const Plan rot19 = test::load_plan("rot19.ini");
  std::string text = rot19.text;
  const auto at = text.find("axes = ");
  REQUIRE(at != std::string::npos);
  text.replace(at, text.find('\n', at) - at, "axes = +y +y +y -y -y -y");
  const Plan yonly = Plan::parse("y-only.ini", text);
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  DesignOptions d;
  d.rate_hz = 20.0;
  const PlanPrediction p = predict_plan(yonly, ko, {}, d);
  const auto advice = separation_advice(yonly, ko, p, 20.0);
  bool misalignment = false;
  for (const auto& a : advice) {
    CAPTURE(a.family, a.turn, a.sigma_before, a.sigma_after);
    CHECK(a.sigma_after <= a.sigma_before);
    if (a.family == "accel.misalignment") {
      misalignment = true;
      CHECK(a.turn.find('z') != std::string::npos);
      CHECK(a.observed_after);
      CHECK(a.sigma_after < 0.1 * a.sigma_before);
    }
  }
  CHECK(misalignment);
  const PlanPrediction full = predict_plan(rot19, ko, {}, d);
  CHECK(separation_advice(rot19, ko, full, 20.0).empty());
}

TEST_CASE("Design advice: the orientation that separates a family an orientation plan misses",
          "[design][advice][long]") {
  // Four orientations with body z up or down: gravity never along x or y in a dwell, so the
  // accelerometers' x and y scale factors are not observed; the advice appends an orientation
  // of the table's reach that determines them. seed8 observes every family of nav-fog.
  const std::string text =
      "[plan]\nname = z-only\ntype = orientations\nconvention = ned-frd\nmove_rate = 15 deg/s\n"
      "move_acceleration = 15 deg/s^2\n[site]\nlatitude = 55.75 deg\n"
      "[orientation.1]\nheading = 0 deg\npitch = 0 deg\nroll = 0 deg\ndwell = 120 s\n"
      "[orientation.2]\nheading = 90 deg\npitch = 0 deg\nroll = 0 deg\ndwell = 120 s\n"
      "[orientation.3]\nheading = 180 deg\npitch = 0 deg\nroll = 180 deg\ndwell = 120 s\n"
      "[orientation.4]\nheading = 270 deg\npitch = 0 deg\nroll = 180 deg\ndwell = 120 s\n";
  const Plan zonly = Plan::parse("z-only.ini", text);
  const SensorProfile prof = SensorProfile::load(test::source_path("config/sensors/nav-fog.ini"));
  const CalibratorOptions ko = calibrator_options_from_profile(prof);
  DesignOptions d;
  d.rate_hz = 20.0;
  const PlanPrediction p = predict_plan(zonly, ko, {}, d);
  const auto advice = separation_advice(zonly, ko, p, 20.0);
  bool scale = false;
  for (const auto& a : advice) {
    CAPTURE(a.family, a.turn, a.sigma_before, a.sigma_after);
    CHECK(a.kind == "orientation");
    CHECK(a.sigma_after <= a.sigma_before);
    if (a.family == "accel.scale") {
      scale = true;
      CHECK(a.turn.find(" 120 s") != std::string::npos);
      CHECK(a.observed_after);
      CHECK(a.sigma_after < 0.3 * a.sigma_before);
      // The advice's orientation, appended, gives the sigma it states.
      const auto open = a.turn.find("(heading ");
      REQUIRE(open != std::string::npos);
      double h = 0, pt = 0, r = 0;
      REQUIRE(std::sscanf(a.turn.c_str() + open, "(heading %lf, pitch %lf, roll %lf", &h, &pt,
                          &r) == 3);
      const Plan longer = Plan::parse(
          "z-only-plus.ini", text + "[orientation.5]\nheading = " + std::to_string(h) +
                                 " deg\npitch = " + std::to_string(pt) +
                                 " deg\nroll = " + std::to_string(r) + " deg\ndwell = 120 s\n");
      const PlanPrediction q = predict_plan(longer, ko, {}, d);
      double worst = 0.0;
      for (const auto& f : q.families)
        if (f.family == "accel.scale") worst = f.worst_sigma;
      CHECK(worst == Approx(a.sigma_after).epsilon(1e-6));
    }
  }
  CHECK(scale);
  const Plan seed8 = test::load_plan("seed8.ini");
  CHECK(separation_advice(seed8, ko, predict_plan(seed8, ko, {}, d), 20.0).empty());
}

namespace {

// Turns of 90 deg about the 6 axes after a 10 s start with body x up, 2.5 s dwells: 6^3 = 216
// plans of one duration. The relaxation's certified lower bound at that duration lies below the
// best of them on the worst sigma / target, and the beam's plan above. Returns bound / best.
double check_bound_against_enumeration(const CalibratorOptions& ko, const std::string& mode) {
  const TableSpec table = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  const Plan rot19 = test::load_plan("rot19.ini");
  SearchOptions so = lab_targets();
  so.rate_hz = 10.0;
  so.minimax = true;
  SearchSpace space;
  space.starts = {0};
  space.start_dwells = {10.0};
  space.pauses = {2.5};
  space.angles = {90.0 * units::deg};
  int scored = 0;
  const auto best = enumerate_plans(ko, table, rot19.site, space, so, 3, &scored);
  REQUIRE(scored == 216);
  const auto found = beam_plans(ko, table, rot19.site, space, so, 3);
  const double duration =
      build_motion(plan_of(best.first, table, rot19.site, "best"), rot19.site).duration();
  const InformationLibrary lib = information_library(ko, table, rot19.site, so.targets, 10.0);
  CHECK(lib.orientations == 24);
  CHECK(lib.segments.size() == 24 * 12 + 24);
  // The bound's coefficients are those of the frame the calibration reports: in the triad frame
  // the three misalignments its convention fixes are not among them, in the table frame they are.
  const auto& fixed = triad_fixed_coefficients();
  const bool has_fixed = std::any_of(lib.catalog.begin(), lib.catalog.end(), [&](int c) {
    return std::find(fixed.begin(), fixed.end(), c) != fixed.end();
  });
  CHECK(has_fixed == (reported_frame(ko) == MisalignmentFrame::Table));
  const DesignBound b = relaxed_bound(lib, duration);
  CAPTURE(mode, duration, b.lower, b.upper, b.family, b.iterations, best.second.worst_ratio,
          found.second.worst_ratio, lib.cpu_s);
  CHECK(b.lower > 0.0);
  CHECK(b.lower <= b.upper);
  CHECK(b.lower <= best.second.worst_ratio);
  CHECK(best.second.worst_ratio <= found.second.worst_ratio + 1e-12);
  // The relaxed design rounded into a plan: the budget filled to within one segment (at most a
  // 180 deg turn and a dwell), the table's limits kept.
  const Plan rounded = rounded_design(lib, b, table, rot19.site);
  const double rounded_s = build_motion(rounded, rounded.site).duration();
  CHECK(rounded_s <= duration + 1e-6);
  CHECK(rounded_s > duration - 13.0);
  CHECK(check_against_table(build_motion(rounded, rounded.site), table, 0.5).empty());
  CHECK_FALSE(rounded.steps.empty());
  WARN(mode << ": bound " << b.lower << " (relaxed " << b.upper << ", " << b.iterations
            << " iterations) <= enumerated " << best.second.worst_ratio << " <= beam "
            << found.second.worst_ratio << "; library " << lib.cpu_s << " s CPU");
  return b.lower / best.second.worst_ratio;
}

}  // namespace

TEST_CASE("Design bound: below the best of every plan of three turns, and the beam above it",
          "[design][bound]") {
  // In the toolbox's mode (--attitude none) and with the table's attitude at every dwell (the
  // default). The oracle knows the attitude: with the calibration's own attitude updates the
  // bound is far closer to the enumerated best than without them.
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  CalibratorOptions ko = calibrator_options_from_profile(prof);
  const double every = check_bound_against_enumeration(ko, "attitude every dwell");
  ko.attitude = CalibratorOptions::AttitudeUpdates::None;
  // Converted to the triad frame after attitude updates: the bound's oracle has the triad-frame
  // coefficients (the triad's attitude told), and is below the enumerated plans in that frame.
  ko.misalignment_frame = MisalignmentFrame::Triad;
  check_bound_against_enumeration(ko, "attitude every dwell, triad frame");
  ko.misalignment_frame = MisalignmentFrame::ByMode;
  ko.attitude = CalibratorOptions::AttitudeUpdates::None;
  const double none = check_bound_against_enumeration(ko, "attitude none");
  CHECK(none < every);
}

TEST_CASE("Design bound: below the exact value of the found plans, in the toolbox's mode",
          "[design][bound]") {
  // The relaxation's certified bound at a plan's duration never exceeds that plan's predicted
  // worst sigma / target (the covariance pass of the calibration itself): the plans found for the
  // goal of 491 s and the toolbox's own 982 s plan, --attitude none, the toolbox's targets. The two
  // searched 491 s plans also keep what docs/methods/design.md states of them: at most 491 s, every
  // family's sigma below its target.
  const TableSpec table = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  CalibratorOptions ko = calibrator_options_from_profile(prof);
  ko.attitude = CalibratorOptions::AttitudeUpdates::None;
  ko.zero_velocity_in_motion = table.reference_on_axes;
  const SearchOptions so = lab_targets();
  const Plan rot19 = test::load_plan("rot19.ini");
  const InformationLibrary lib = information_library(ko, table, rot19.site, so.targets, 10.0);
  DesignOptions d;
  d.rate_hz = 10.0;
  d.history_interval = 1e9;
  for (const char* name :
       {"searched-491.ini", "searched-491m.ini", "diagonal-491.ini", "toolbox19.ini"}) {
    const Plan plan = test::load_plan(name);
    const PlanPrediction p = predict_plan(plan, ko, so.targets, d);
    const Excess e = excess(p.run.estimates, so.targets);
    const DesignBound b = relaxed_bound(lib, p.duration);
    CAPTURE(name, p.duration, b.lower, b.upper, b.family, e.worst_ratio, e.worst_family);
    CHECK(b.lower > 0.0);
    CHECK(b.lower <= e.worst_ratio);
    if (std::string(name).rfind("searched-491", 0) == 0) {
      CHECK(p.duration <= 491.0);
      CHECK(e.worst_ratio < 1.0);
    }
  }
}

TEST_CASE("Plan search: at least as good as every dwell-scaled hand plan, budgets 200-1000 s",
          "[design][search][long]") {
  // The toolbox's mode and targets. At each budget the search's worst sigma / target is at most
  // that of rot19, seed8 and the toolbox's own 19-position plan (toolbox19, 982 s), as they are
  // and with their dwells scaled, at every budget of the sweep up to it: every 100 s from 200 s
  // to 1000 s; and at most the search's own at every shorter budget (monotone: each budget's plan
  // and that plan with its dwells scaled up is carried as a seed of the next). About 50 s of CPU
  // with the structure moves.
  const TableSpec table = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  const SensorProfile prof = SensorProfile::load(test::source_path(kFog));
  CalibratorOptions ko = calibrator_options_from_profile(prof);
  ko.attitude = CalibratorOptions::AttitudeUpdates::None;
  ko.zero_velocity_in_motion = table.reference_on_axes;
  SearchOptions so = lab_targets();
  so.rate_hz = 10.0;
  so.beam = 1;
  // The structure moves at a small effort (the default of design --optimize is 2000 passes):
  // they run at every budget and their plan must stay within it and as good as the hand plans.
  so.structure_evaluations = 30;
  so.seeds = {test::load_plan("rot19.ini"), test::load_plan("seed8.ini"),
              test::load_plan("toolbox19.ini")};
  const std::vector<double> budgets = {200.0, 300.0, 400.0, 500.0, 600.0,
                                       700.0, 800.0, 900.0, 1000.0};
  DesignOptions d;
  d.rate_hz = so.rate_hz;
  d.history_interval = 1e9;
  auto worst = [&](const Plan& p) {
    return excess(predict_plan(p, ko, so.targets, d).run.estimates, so.targets).worst_ratio;
  };
  // Every hand plan's worst ratio at each budget it fits (as it is, or scaled).
  std::vector<std::pair<double, double>> hand;  // duration, worst ratio
  for (const Plan& seed : so.seeds) {
    hand.emplace_back(build_motion(seed, seed.site).duration(), worst(seed));
    for (double b : budgets)
      if (const auto s = dwell_scaled(seed, b, shortest_pause(table)))
        hand.emplace_back(build_motion(*s, s->site).duration(), worst(*s));
  }
  const std::vector<SearchResult> found =
      search_budgets(ko, table, so.seeds.front().site, SearchSpace{}, so, budgets);
  REQUIRE(found.size() == budgets.size());
  for (std::size_t k = 0; k < budgets.size(); ++k) {
    const double b = budgets[k];
    const SearchResult& r = found[k];
    const double duration = build_motion(r.plan, r.plan.site).duration();
    CAPTURE(b, duration, r.origin, r.excess.worst_ratio, r.excess.worst_family);
    CHECK(duration <= b + 1e-6);
    CHECK(worst(r.plan) == Approx(r.excess.worst_ratio).epsilon(1e-6));
    for (const auto& [t, ratio] : hand)
      if (t <= b + 1e-6) {
        CAPTURE(t, ratio);
        CHECK(r.excess.worst_ratio <= ratio * (1.0 + 1e-9));
      }
    for (std::size_t j = 0; j < k; ++j) {
      CAPTURE(budgets[j], found[j].excess.worst_ratio);
      CHECK(r.excess.worst_ratio <= found[j].excess.worst_ratio * (1.0 + 1e-6));
    }
    // And at most the shorter budget's plan with its dwells scaled up to this one (the time
    // added only adds information; without the carry-up the search may miss it).
    if (k > 0)
      if (const auto up = dwell_scaled(found[k - 1].plan, b, shortest_pause(table))) {
        const double ratio = worst(*up);
        CAPTURE(budgets[k - 1], ratio);
        CHECK(r.excess.worst_ratio <= ratio * (1.0 + 1e-6));
      }
    WARN("budget " << b << " s: " << r.origin << ", " << duration << " s, worst "
                   << r.excess.worst_ratio << " (" << r.excess.worst_family << ")");
  }
}

TEST_CASE("Design: the toolbox's 19-position plan is rot19's turns with both dwells of each turn",
          "[design][search]") {
  // The toolbox states each turn with a dwell before it and after it (70 s and 70 s for the
  // first, 20 s and 20 s for the others): 982 s, rot19's start and turns.
  const Plan toolbox = test::load_plan("toolbox19.ini");
  const Plan rot19 = test::load_plan("rot19.ini");
  CHECK(build_motion(toolbox, toolbox.site).duration() == Approx(982.0).margin(1e-6));
  std::vector<double> dwells = {70.0, 90.0};
  dwells.insert(dwells.end(), 16, 40.0);
  dwells.push_back(20.0);
  const std::vector<double> d = plan_dwells(toolbox);
  REQUIRE(d.size() == dwells.size());
  for (std::size_t i = 0; i < d.size(); ++i) CHECK(d[i] == Approx(dwells[i]));
  REQUIRE(toolbox.steps.size() == rot19.steps.size());
  for (std::size_t i = 0; i < toolbox.steps.size(); ++i) {
    CHECK(toolbox.steps[i].axis_name == rot19.steps[i].axis_name);
    CHECK(toolbox.steps[i].angle == Approx(rot19.steps[i].angle));
    CHECK(toolbox.steps[i].duration == Approx(rot19.steps[i].duration));
  }
  CHECK(toolbox.start.heading == rot19.start.heading);
  CHECK(toolbox.start.pitch == rot19.start.pitch);
  CHECK(toolbox.start.roll == rot19.start.roll);
  CHECK(toolbox.convention == rot19.convention);
}

TEST_CASE("Plan search: the bundled searched plans are seeds, renamed plans keep their content",
          "[design][search]") {
  // config/plans/searched-*.ini, in the order of their names; a directory without any: none.
  const std::vector<Plan> found = searched_plans_in(test::source_path("config/plans"));
  REQUIRE(found.size() >= 2);
  for (std::size_t i = 0; i < found.size(); ++i) {
    CAPTURE(found[i].path);
    CHECK(found[i].name.rfind("searched-", 0) == 0);
    if (i > 0) CHECK(found[i - 1].path < found[i].path);
  }
  CHECK(searched_plans_in(test::source_path("config/tables")).empty());
  // A plan renamed (as the search carries a budget's plan up): the same motion, the new name.
  const Plan rot19 = test::load_plan("rot19.ini");
  const Plan r = renamed(rot19, "searched-592s");
  CHECK(r.name == "searched-592s");
  CHECK(Plan::parse("again.ini", r.text).name == "searched-592s");
  CHECK(build_motion(r, r.site).duration() == Approx(build_motion(rot19, rot19.site).duration()));
  CHECK(plan_dwells(r) == plan_dwells(rot19));
}

TEST_CASE("Plan search: a hand plan with its dwells scaled to a table time", "[design][search]") {
  // rot19: 18 turns of 9 s, a 70 s start and 20 s pauses (592 s). Scaled to 479.5 s the turns
  // stay and the 317.5 s of dwells keep their proportions: 70 f + 18 * 20 f = 317.5 s.
  const Plan rot19 = test::load_plan("rot19.ini");
  const auto s = dwell_scaled(rot19, 479.5, 2.5);
  REQUIRE(s);
  CHECK(build_motion(*s, s->site).duration() == Approx(479.5).margin(0.05));
  const double f = 317.5 / 430.0;
  CHECK(s->start_dwell == Approx(70.0 * f).epsilon(1e-4));
  REQUIRE(s->steps.size() == rot19.steps.size());
  for (std::size_t i = 0; i < s->steps.size(); ++i) {
    CHECK(s->steps[i].pause == Approx(20.0 * f).epsilon(1e-4));
    CHECK(s->steps[i].duration == rot19.steps[i].duration);
    CHECK(s->steps[i].axis_name == rot19.steps[i].axis_name);
  }
  CHECK(s->name == "rot19-480s");
  // The same plan read back from its text; dwells set one by one.
  const Plan again = Plan::parse("again.ini", s->text);
  CHECK(again.start_dwell == Approx(s->start_dwell));
  std::vector<double> d = plan_dwells(*s);
  d[0] += 10.0;
  CHECK(with_dwells(*s, d).start_dwell == Approx(s->start_dwell + 10.0).epsilon(1e-6));
  // Below the turns and the shortest dwells: none. seed8 (orientations) scales too.
  CHECK_FALSE(dwell_scaled(rot19, 162.0 + 19 * 2.5 - 1.0, 2.5));
  const Plan seed8 = test::load_plan("seed8.ini");
  const auto s8 = dwell_scaled(seed8, 600.0, 2.5);
  REQUIRE(s8);
  CHECK(build_motion(*s8, s8->site).duration() == Approx(600.0).margin(0.05));
}
