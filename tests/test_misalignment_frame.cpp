// The misalignment frame (filter/kalman/misalignment_frame.hpp, issue 36.3): an estimate relative
// to the table converted into the accelerometer-triad frame with its full covariance. The
// conversion's Jacobian is its derivative; the converted misalignment sigmas do not carry the
// table's attitude accuracy; design predicts the frame the calibration reports.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>

#include "catalog.hpp"
#include "filter/design/prediction.hpp"
#include "filter/kalman/misalignment_frame.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"

using namespace sinscal;

namespace {

// A navigation-grade unit mounted 0.3 deg off the platform, as the table frame sees it: every
// linear term, the g-sensitivity and the lever arms non-zero, so every block of the Jacobian is.
ImuErrorModel table_frame_unit() {
  ImuErrorModel m;
  const char* names[] = {"gyro.scale.x",          "gyro.scale.y",          "gyro.scale.z",
                         "accel.scale.x",         "accel.scale.y",         "accel.scale.z",
                         "gyro.misalignment.xy",  "gyro.misalignment.xz",  "gyro.misalignment.yx",
                         "gyro.misalignment.yz",  "gyro.misalignment.zx",  "gyro.misalignment.zy",
                         "accel.misalignment.xy", "accel.misalignment.xz", "accel.misalignment.yx",
                         "accel.misalignment.yz", "accel.misalignment.zx", "accel.misalignment.zy"};
  const double values[] = {120, -80, 40,   300,  -150, 90,   1100, -700, -1050,
                           400, 760, -380, 1000, -750, -980, 350,  720,  -420};  // ppm, arcsec
  for (std::size_t k = 0; k < std::size(names); ++k) m.set(names[k], values[k]);
  m.gyro_g_sensitivity << 1e-7, 2e-8, -3e-8, 4e-8, -1e-7, 5e-8, -2e-8, 3e-8, 8e-8;  // rad/s/(m/s^2)
  m.accel_lever_arm_b << 0.0, 0.012, -0.008, 0.010, 0.0, 0.011, -0.009, 0.013, 0.0;  // m
  m.gyro.bias = Eigen::Vector3d(1e-8, -2e-8, 3e-8);
  return m;
}

ImuErrorModel model_of(const Eigen::VectorXd& v) {
  ImuErrorModel m;
  auto refs = m.coefficient_refs();
  for (std::size_t c = 0; c < refs.size(); ++c) *refs[c].second = v(static_cast<Eigen::Index>(c));
  return m;
}

}  // namespace

TEST_CASE("Misalignment frame: the conversion's Jacobian is its derivative", "[frame]") {
  const ImuErrorModel m = table_frame_unit();
  const Eigen::VectorXd x = m.vector();
  const Eigen::MatrixXd J = accel_triad_frame_jacobian(m);
  // Central differences of the conversion itself. Step 1e-6 in SI: the truncation error is of
  // order h^2 (1e-12) times the second-order terms (O(1)), the rounding of the linear parts
  // (about 1: 1e-16) over 2h about 1e-10. The tolerance, 1e-7, is a thousand times that and a
  // million times below the O(1) entries a wrong sign of the rotation's change would alter.
  const double h = 1e-6;
  double worst = 0.0;
  for (Eigen::Index k = 0; k < x.size(); ++k) {
    Eigen::VectorXd up = x, down = x;
    up(k) += h;
    down(k) -= h;
    const Eigen::VectorXd d = (in_accel_triad_frame(model_of(up)).vector() -
                               in_accel_triad_frame(model_of(down)).vector()) /
                              (2.0 * h);
    worst = std::max(worst, (d - J.col(k)).cwiseAbs().maxCoeff());
  }
  CHECK(worst < 1e-7);
  // The common rotation moves the gyro misalignments with the accelerometers' upper ones: the
  // part a table frame carries and the triad frame drops (first order: -1 for the antisymmetric
  // pair of gyro.misalignment.xy / accel.misalignment.xy).
  const int gxy = test::coefficient_index("gyro.misalignment.xy"),
            gyx = test::coefficient_index("gyro.misalignment.yx");
  const int axy = test::coefficient_index("accel.misalignment.xy");
  CHECK(J(gxy, axy) == Approx(-1.0).margin(0.01));
  CHECK(J(gyx, axy) == Approx(1.0).margin(0.01));
  // Coefficients of the sensor axes only (a bias) pass unchanged.
  const int gbx = test::coefficient_index("gyro.bias.x");
  CHECK(J(gbx, gbx) == 1.0);
  CHECK(J.col(gbx).cwiseAbs().sum() == 1.0);
}

TEST_CASE("Misalignment frame: names, the mode's default, the table frame needs attitude updates",
          "[frame]") {
  CHECK(parse_misalignment_frame("triad") == MisalignmentFrame::Triad);
  CHECK(misalignment_frame_name(MisalignmentFrame::Table) == "table");
  CHECK_THROWS_WITH(parse_misalignment_frame("case"),
                    Catch::Contains("unknown misalignment frame"));
  CHECK(resolve_misalignment_frame(MisalignmentFrame::ByMode, true) == MisalignmentFrame::Table);
  CHECK(resolve_misalignment_frame(MisalignmentFrame::ByMode, false) == MisalignmentFrame::Triad);
  CHECK_THROWS_WITH(resolve_misalignment_frame(MisalignmentFrame::Table, false),
                    Catch::Contains("not observable without table-attitude updates"));
}

namespace {

// The predicted worst sigma of a family (design, the calibration's covariance pass).
struct FrameSigmas {
  double gyro = 0.0, accel = 0.0;  // rad: gyro.misalignment, accel.misalignment
  MisalignmentFrame frame = MisalignmentFrame::ByMode;
};

FrameSigmas predicted(MisalignmentFrame frame, double table_sigma_arcsec) {
  const Plan plan = test::load_plan("rot19.ini");
  const SensorProfile prof =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-extended.ini"));
  CalibratorOptions ko = calibrator_options_from_profile(prof);
  ko.attitude_sigma = table_sigma_arcsec * units::arcsec;
  ko.misalignment_frame = frame;
  DesignOptions d;
  d.rate_hz = 10.0;
  const PlanPrediction p = predict_plan(plan, ko, {}, d);
  FrameSigmas s;
  s.frame = p.run.misalignment_frame;
  for (const auto& f : p.families) {
    if (f.family == "gyro.misalignment") s.gyro = f.worst_sigma;
    if (f.family == "accel.misalignment") s.accel = f.worst_sigma;
  }
  return s;
}

}  // namespace

TEST_CASE(
    "Misalignment frame: in the triad frame the misalignment sigmas do not depend on the "
    "table's attitude accuracy",
    "[frame][design]") {
  // rot19, nav-fog-extended, the table at 2.5, 25 and 250 arcsec per dwell.
  const FrameSigmas table_2 = predicted(MisalignmentFrame::ByMode, 2.5),
                    table_25 = predicted(MisalignmentFrame::ByMode, 25.0),
                    table_250 = predicted(MisalignmentFrame::ByMode, 250.0),
                    triad_2 = predicted(MisalignmentFrame::Triad, 2.5),
                    triad_25 = predicted(MisalignmentFrame::Triad, 25.0),
                    triad_250 = predicted(MisalignmentFrame::Triad, 250.0);
  CHECK(table_2.frame == MisalignmentFrame::Table);
  CHECK(triad_2.frame == MisalignmentFrame::Triad);
  const double as = units::arcsec;
  WARN("worst misalignment sigma [arcsec] at a table of 2.5 / 25 / 250 arcsec: table frame gyro "
       << table_2.gyro / as << " / " << table_25.gyro / as << " / " << table_250.gyro / as
       << ", accel " << table_2.accel / as << " / " << table_25.accel / as << " / "
       << table_250.accel / as << "; triad frame gyro " << triad_2.gyro / as << " / "
       << triad_25.gyro / as << " / " << triad_250.gyro / as << ", accel " << triad_2.accel / as
       << " / " << triad_25.accel / as << " / " << triad_250.accel / as);
  // Relative to the table the common rotation of the triads is known only to the table's
  // accuracy: the sigmas grow with it (to the prior, 28 arcsec).
  CHECK(table_25.gyro > 5.0 * table_2.gyro);
  CHECK(table_25.accel > 5.0 * table_2.accel);
  CHECK(table_250.gyro > 3.0 * table_25.gyro);
  CHECK(table_250.accel > 3.0 * table_25.accel);
  // Within the triads the common rotation drops out. What the attitude updates still give is the
  // dwells' relative orientations, which the gyros measure too (each turn to a fraction of an
  // arcsec): information on the triads' shape that falls as 1 / sigma_table^2 once the table is
  // coarser than that. At 25 and 250 arcsec the table adds nothing the gyros do not measure: the
  // sigmas are equal to 1 % (the 1/sigma^2 law from the 2.5-arcsec step below puts the change at
  // about 0.1 %; a conversion that kept the rotation would grow them 4 times, as above).
  CHECK(triad_250.gyro == Approx(triad_25.gyro).epsilon(0.01));
  CHECK(triad_250.accel == Approx(triad_25.accel).epsilon(0.01));
  // At 2.5 arcsec the table's relative orientations still add information (never remove it), and
  // the excess over the limit, sigma^-2 - sigma_limit^-2, falls at least 50 times from 2.5 to 25
  // arcsec (1/sigma_table^2: 100 times, to first order in the table's share).
  CHECK(triad_2.gyro <= triad_25.gyro);
  CHECK(triad_2.accel <= triad_25.accel);
  auto excess = [](double sigma, double limit) {
    return 1.0 / (sigma * sigma) - 1.0 / (limit * limit);
  };
  CHECK(excess(triad_25.gyro, triad_250.gyro) < excess(triad_2.gyro, triad_250.gyro) / 50.0);
  CHECK(excess(triad_25.accel, triad_250.accel) < excess(triad_2.accel, triad_250.accel) / 50.0);
}

TEST_CASE("Misalignment frame: design predicts the triad-frame sigmas the calibration reports",
          "[frame][design][kalman]") {
  // As tests/test_design.cpp "predicted sigmas are those the calibration of the plan reports",
  // in the triad frame: rot19 simulated from nav-fog-extended (drawn coefficients, noise) and
  // calibrated with attitude updates, converted after the estimation.
  const Plan plan = test::load_plan("rot19.ini");
  const SensorProfile prof =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-extended.ini"));
  CalibratorOptions ko = calibrator_options_from_profile(prof);
  ko.misalignment_frame = MisalignmentFrame::Triad;
  const double rate_hz = 20.0;
  DesignOptions d;
  d.rate_hz = rate_hz;
  const PlanPrediction p = predict_plan(plan, ko, prof.sigma_targets, d);
  const Motion motion = build_motion(plan, plan.site);
  SimulatorOptions so;
  so.rate_hz = rate_hz;
  so.noise_seed = 1007;
  ImuSimulator sim(motion, prof.draw(7), prof.noise, so);
  KalmanRunOptions run;
  run.align = false;
  const KalmanRun c = run_kalman(design_session(plan, rate_hz), ko, &sim, run);
  REQUIRE(c.misalignment_frame == MisalignmentFrame::Triad);
  REQUIRE(c.converted_to_triad_frame);
  const auto& cat = coefficient_catalog();
  int compared = 0;
  for (std::size_t i = 0; i < cat.size(); ++i) {
    const auto& e = p.run.estimates[i];
    REQUIRE(e.status == c.estimates[i].status);
    if (e.status != CoefficientEstimate::Status::Estimated) continue;
    CAPTURE(cat[i].name, e.sigma, c.estimates[i].sigma);
    CHECK(e.sigma == Approx(c.estimates[i].sigma).epsilon(0.05));  // the 5 %
    ++compared;
  }
  CHECK(compared >= 30);
  for (int f : triad_fixed_coefficients())
    CHECK(c.estimates[static_cast<std::size_t>(f)].status ==
          CoefficientEstimate::Status::FixedByConvention);
}

TEST_CASE("Misalignment frame: the unobservable combinations are named in the reported frame",
          "[frame][design]") {
  // rot19 on a table of 3000 arcsec per dwell: relative to the table the triads' common rotation
  // is barely determined (combinations of the misalignments keep most of their prior variance);
  // within the triads it drops out, and what is named is the converted coefficients' (none of
  // the three the triad convention fixes, and every converted misalignment observed).
  const Plan plan = test::load_plan("rot19.ini");
  const SensorProfile prof =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-extended.ini"));
  CalibratorOptions ko = calibrator_options_from_profile(prof);
  ko.attitude_sigma = 3000.0 * units::arcsec;
  DesignOptions d;
  d.rate_hz = 10.0;
  ko.misalignment_frame = MisalignmentFrame::Table;
  const PlanPrediction table = predict_plan(plan, ko, {}, d);
  ko.misalignment_frame = MisalignmentFrame::Triad;
  const PlanPrediction triad = predict_plan(plan, ko, {}, d);
  REQUIRE(triad.run.converted_to_triad_frame);
  CHECK_FALSE(table.run.unobservable_directions.empty());
  const auto& fixed = triad_fixed_coefficients();
  const auto& cat = coefficient_catalog();
  auto is_fixed = [&](const std::string& name) {
    return std::any_of(fixed.begin(), fixed.end(),
                       [&](int c) { return cat[static_cast<std::size_t>(c)].name == name; });
  };
  bool table_names_fixed = false;
  for (const auto& u : table.run.unobservable_directions)
    for (const auto& [name, weight] : u.components) table_names_fixed |= is_fixed(name);
  CHECK(table_names_fixed);  // the table frame's directions hold what the triads' drop
  for (const auto& u : triad.run.unobservable_directions)
    for (const auto& [name, weight] : u.components) {
      CAPTURE(u.text());
      CHECK_FALSE(is_fixed(name));
    }
  CHECK(triad.run.unobservable_directions.size() < table.run.unobservable_directions.size());
  for (std::size_t c = 0; c < cat.size(); ++c)
    if (cat[c].family == "accel.misalignment" &&
        triad.run.estimates[c].status == CoefficientEstimate::Status::Estimated) {
      CAPTURE(cat[c].name, triad.run.estimates[c].sigma, triad.run.estimates[c].prior_sigma);
      CHECK(triad.run.estimates[c].observed());
      CHECK(std::find(triad.run.unobservable.begin(), triad.run.unobservable.end(), cat[c].name) ==
            triad.run.unobservable.end());
    }
}
