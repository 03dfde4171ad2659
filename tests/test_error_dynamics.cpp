// Proofs of the Kalman filter's physics against the code it linearizes:
//  - every column of the accumulated transition (navigation errors and every coefficient family,
//    extended ones included) against the navigator run from a perturbed start or with a
//    perturbed coefficient, over an interval that includes a table turn;
//  - every measurement's H against numerical differences of its measurement function;
//  - the feedback: a known error injected and fed back returns the truth.
// The error-state convention (filter/kalman/measurements.hpp) is the link between them: errors are
// injected with inject_error and read back as navigation errors (computed minus true).
#include <catch2/catch.hpp>
#include <random>

#include "filter/kalman/kalman_calibrator.hpp"
#include "filter/kalman/measurements.hpp"
#include "helpers.hpp"
#include "models/attitude.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"

using namespace sinscal;

namespace {

// A model with every family non-zero, at sizes a navigation-grade unit may have.
ImuErrorModel every_family_model() {
  ImuErrorModel m;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (auto& [info, value] : m.coefficient_refs()) {
    const CoefficientFamily& f = coefficient_family_info(info.family);
    *value = u(rng) * f.default_prior * 0.3;
  }
  m.time_delay = 2e-3;
  // The filter linearizes each triad's compensation on its own: the second-order cross-coupling
  // through the compensation (g-sensitivity G df into the gyro rates, the size effect's rate
  // dependence into the specific force) is not in its transition. It is of relative size |G|
  // (1e-7) or |w r| against the direct effect, which shows only where the direct effect is itself
  // tiny (the attitude rows of accelerometer terms: 3 % measured with G = 0.03 deg/h/g). The
  // window's model leaves those two families out; their own columns are still checked (they do
  // not depend on the model's values).
  m.gyro_g_sensitivity.setZero();
  m.accel_lever_arm_b.setZero();
  return m;
}

// Navigation errors of `computed` against `reference` in the filter's convention, as a state
// vector of the layout (coefficient entries zero).
Eigen::VectorXd nav_difference(const StateLayout& l, const NavState& computed,
                               const NavState& reference) {
  Eigen::VectorXd e = Eigen::VectorXd::Zero(l.size);
  const InsSiteTerms t =
      InsSiteTerms::at(Site{reference.lat_rad, reference.lon_rad, reference.h_m});
  e.segment<3>(l.attitude.index) = attitude_error_n(computed.C_b_n(), reference.C_b_n());
  for (int i = 0; i < l.velocity.size; ++i)
    e(l.velocity.index + i) = computed.v_n(i) - reference.v_n(i);
  e(l.position.index + 0) = (computed.lat_rad - reference.lat_rad) * t.R_N;
  e(l.position.index + 1) = (computed.lon_rad - reference.lon_rad) * t.R_E * std::cos(t.lat_rad);
  e(l.position.index + 2) = -(computed.h_m - reference.h_m);
  return e;
}

struct Window {
  Plan plan;
  Motion motion;
  std::vector<ImuSample> samples;  // the log over the window
  ImuErrorModel truth;
};

// rot19 from 68 s to 74 s: 2 s at rest, then the start of the first turn (10 deg/s^2, 40 deg/s
// reached at 74 s): specific force, rate and angular acceleration all excite the coefficients.
const Window& window() {
  static const Window w = [] {
    Window x{test::load_plan("rot19.ini"),
             build_motion(test::load_plan("rot19.ini"), test::load_plan("rot19.ini").site),
             {},
             every_family_model()};
    // In a chamber warming by 0.1 C/s (the thermal columns act: 12 C from T0 and more).
    const SensorTemperature chamber(ChamberAir{{0.0, 200.0}, {30.0, 50.0}}, 0.0);
    for (const auto& s : test::simulate(x.motion, x.truth, 100.0, nullptr, 1, &chamber))
      if (s.t > 68.0 && s.t <= 74.0 + 1e-9) x.samples.push_back(s);
    return x;
  }();
  return w;
}

CalibratorOptions all_on() {
  CalibratorOptions o;
  for (const auto& f : coefficient_families())
    if (!f.base) o.layout.set(f.name, true);
  o.layout.base_attitude = true;  // the table base too (the calibrator turns it on likewise)
  // And the bias instability's wander as states (a MEMS unit's sizes; a correlation time long
  // against the window: the coupling's geometry is checked here, the decay is applied to the
  // covariance in propagate()).
  o.noise.gyro.bias_instability = 10.0 * units::deg_per_h;
  o.noise.gyro.correlation_time = 1e4;
  o.noise.accel.bias_instability = 0.05 * units::mg;
  o.noise.accel.correlation_time = 1e4;
  o.update_interval = 1e9;  // no update: the transition accumulates over the whole window
  o.time_offset = 0.0;
  return o;
}

// Runs the filter's navigation over the window from the model `estimate` with the error `dx`
// injected at the start.
Calibrator run_window(const CalibratorOptions& o, const Eigen::VectorXd* dx) {
  const Window& w = window();
  Calibrator kf(test::timeline(w.plan), w.plan.site, o);
  if (dx) kf.inject_error(*dx);
  for (const auto& s : w.samples) kf.push(s);
  kf.finish();
  return kf;
}

}  // namespace

TEST_CASE("Error dynamics: every column of the transition matches the perturbed navigator",
          "[kalman][dynamics]") {
  CalibratorOptions o = all_on();
  o.initial_model = window().truth;
  const Calibrator ref = run_window(o, nullptr);
  const StateLayout& l = ref.layout();
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Identity(l.size, l.size);
  Phi.topLeftCorner(l.nav_size, l.nav_size) = ref.propagator().Phi_nn();
  Phi.topRightCorner(l.nav_size, l.size - l.nav_size) = ref.propagator().Phi_nc();
  // Perturbation of each state: small against its effect's nonlinearity (relative 1e-4 or
  // less), large against the rounding of the navigator's latitude and attitude.
  auto step = [&](int j) {
    if (j < l.nav_size) {
      if (j >= l.position.index) return 100.0;  // m
      if (j >= l.velocity.index) return 0.1;    // m/s
      return 100.0 * units::arcsec;             // rad
    }
    for (const auto& cb : l.coefficients)
      if (j >= cb.block.index && j < cb.block.index + cb.block.size)
        return coefficient_family_info(cb.family).default_prior;                         // SI
    if (j >= l.wander.index && j < l.wander.index + 3) return 100.0 * units::deg_per_h;  // rad/s
    if (j >= l.wander.index) return 100.0 * units::ug;                                   // m/s^2
    return 100.0 * units::arcsec;  // the table base (rad): no effect on the navigation
  };
  const double T = window().samples.back().t - window().samples.front().t + 0.01;  // s
  const double g = InsSiteTerms::at(window().plan.site).g;
  // Each block in velocity-equivalent units over the window: a tilt phi makes g phi T of
  // velocity, a position error dp is dp / T of it.
  const std::vector<std::pair<Block, double>> blocks = {
      {l.attitude, g * T}, {l.velocity, 1.0}, {l.position, 1.0 / T}};
  int checked = 0;
  for (int j = 0; j < l.size; ++j) {
    Eigen::VectorXd dx = Eigen::VectorXd::Zero(l.size);
    dx(j) = step(j);
    const Calibrator run = run_window(o, &dx);
    // The navigation error the perturbation caused, per unit of it, against the column.
    const Eigen::VectorXd numeric =
        nav_difference(l, run.navigation(), ref.navigation()).head(l.nav_size) / dx(j);
    const Eigen::VectorXd column = Phi.col(j).head(l.nav_size);
    double scale = 0.0;  // the column's largest block, velocity-equivalent
    for (const auto& [b, w] : blocks)
      scale = std::max(scale, w * column.segment(b.index, b.size).norm());
    std::string state = j < l.nav_size ? "navigation state " + std::to_string(j) : "";
    for (const auto& cb : l.coefficients)
      for (int k = 0; k < cb.block.size; ++k)
        if (cb.block.index + k == j)
          state = coefficient_catalog()[static_cast<std::size_t>(
                                            cb.catalog[static_cast<std::size_t>(k)])]
                      .name;
    for (const auto& [b, w] : blocks) {
      const Eigen::VectorXd a = column.segment(b.index, b.size),
                            n = numeric.segment(b.index, b.size);
      CAPTURE(state, b.index, a.transpose(), n.transpose());
      // What the filter's transition leaves out, and so the tolerance:
      //  - first-order accumulation per 10 ms step: relative error about (integrations from the
      //    state to the row) / (steps over which the effect grows), first order in dt (measured:
      //    halves at 200 Hz, again at 400 Hz); 4 / 400 for position from the turn's rate
      //    (gyro misalignment, 1.05 % measured): 2 % of the block;
      //  - Earth-model terms the INS error matrix neglects (gravity's change with latitude, its
      //    north component's change with height, the free-air gradient against 2 g / R): below
      //    1e-6 of the column's scale, in the velocity and position rows (gravity does not enter
      //    the attitude rows);
      //  - the rounding of the numerical difference: 1e-8 m of position (latitude ulps over 600
      //    steps) is 2e-9 m/s velocity-equivalent, per unit of the perturbation.
      const double gravity_terms = b.index == l.attitude.index ? 0.0 : 1e-6 * scale;
      CHECK(w * (a - n).norm() <=
            2e-2 * w * std::max(a.norm(), n.norm()) + gravity_terms + 2e-9 / std::abs(dx(j)));
    }
    ++checked;
  }
  CHECK(checked == l.size);
  // + the base, the dwell's orientation error and the bias wander
  CHECK(l.size == 9 + static_cast<int>(coefficient_catalog().size()) + 3 + 3 + 6);
}

TEST_CASE(
    "Measurements: H of zero velocity, position and attitude match the measurement "
    "functions",
    "[kalman][dynamics]") {
  CalibratorOptions o = all_on();
  o.initial_model = window().truth;
  const Calibrator ref = run_window(o, nullptr);
  const StateLayout& l = ref.layout();
  const Site site = window().plan.site;
  const InsSiteTerms terms = InsSiteTerms::at(site);
  const NavState& x0 = ref.navigation();
  const Eigen::Matrix3d C_known = window().motion.at(74.0).C_b_n;
  // The table's base: an estimate off the identity, its error a state (the attitude update
  // measures the attitude relative to it).
  REQUIRE(StateLayout::on(l.base));
  const Eigen::Matrix3d C_base0 = dcm_from_rotvec(Eigen::Vector3d(2e-5, -3e-5, 5e-5));
  // And the dwell's orientation error (the table's at this dwell), a state as well.
  REQUIRE(StateLayout::on(l.dwell_orientation));
  const Eigen::Matrix3d C_dwell0 = dcm_from_rotvec(Eigen::Vector3d(-4e-6, 1e-5, 7e-6));
  Eigen::Matrix3d C_dwell = C_dwell0;
  using Function = std::function<Measurement(const NavState&, const Eigen::Matrix3d&)>;
  const std::vector<std::pair<std::string, Function>> ms = {
      {"zero velocity",
       [&](const NavState& x, const Eigen::Matrix3d&) { return zero_velocity(l, x, 1e-3); }},
      {"position",
       [&](const NavState& x, const Eigen::Matrix3d&) { return known_position(l, x, site, 1e-2); }},
      {"attitude", [&](const NavState& x, const Eigen::Matrix3d& C_base) {
         return known_attitude(l, x, C_known, 1e-5, C_base, C_dwell);
       }}};
  for (const auto& [name, h] : ms) {
    CAPTURE(name);
    C_dwell = C_dwell0;
    const Measurement m0 = h(x0, C_base0);
    const Eigen::MatrixXd H = m0.H(l.size);
    for (int j = 0; j < l.size; ++j) {
      const bool base =
          j >= l.base.index && j < l.base.index + l.base.size + l.dwell_orientation.size;
      const double eps = j < l.velocity.index || base ? 1e-6 : j < l.position.index ? 1e-4 : 1e-2;
      Eigen::VectorXd dx = Eigen::VectorXd::Zero(l.size);
      dx(j) = eps;
      NavState x = x0;
      ImuErrorModel model = window().truth;
      inject_error(l, terms, dx, x, model);
      Eigen::Matrix3d C_base = C_base0;
      inject_base_error(l, dx, C_base);
      C_dwell = C_dwell0;
      inject_dwell_orientation_error(l, dx, C_dwell);
      const Measurement m1 = h(x, C_base);
      for (int i = 0; i < m0.rows(); ++i) {
        const double numeric =
            (m1.z[static_cast<std::size_t>(i)] - m0.z[static_cast<std::size_t>(i)]) / eps;
        CAPTURE(j, i, numeric, H(i, j));
        CHECK(std::abs(numeric - H(i, j)) < 1e-4);
      }
    }
  }
}

TEST_CASE("Feedback: a known error injected and fed back returns the truth", "[kalman][dynamics]") {
  CalibratorOptions o = all_on();
  const StateLayout l = StateLayout::make(o.layout);
  const Site site = window().plan.site;
  const InsSiteTerms terms = InsSiteTerms::at(site);
  NavState truth = NavState::at_rest(window().motion.at(74.0).C_b_n, site);
  truth.v_n = Eigen::Vector3d(0.1, -0.2, 0.05);
  const ImuErrorModel model_truth = window().truth;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::VectorXd dx(l.size);
  for (int j = 0; j < l.size; ++j) dx(j) = n(rng) * (j < l.nav_size ? 1e-3 : 1e-7);
  NavState x = truth;
  ImuErrorModel model = model_truth;
  inject_error(l, terms, dx, x, model);
  // The injected error is what the measurement functions see.
  // (Position to the rounding of latitude and longitude: 1 ulp of a latitude is ~1e-9 m.)
  CHECK((nav_difference(l, x, truth).head(l.nav_size) - dx.head(l.nav_size)).norm() <
        1e-9 * dx.head(l.nav_size).norm() + 1e-8);
  const Eigen::VectorXd theta_truth = model_truth.vector(), theta = model.vector();
  for (std::size_t c = 0; c < l.state_of.size(); ++c)
    CHECK(theta_truth(static_cast<Eigen::Index>(c)) - theta(static_cast<Eigen::Index>(c)) ==
          Approx(dx(l.state_of[c])).epsilon(1e-9));
  feed_back(l, terms, dx, x, model);
  CHECK(nav_difference(l, x, truth).norm() < 1e-8);
  CHECK((model.vector() - theta_truth).norm() < 1e-15);
  // The table base: the error injected is the rotation from the estimate to the truth, and the
  // feedback of it returns the truth.
  REQUIRE(StateLayout::on(l.base));
  const Eigen::Matrix3d C_base_truth = dcm_from_rotvec(Eigen::Vector3d(0.01, -0.02, 0.08));
  Eigen::Matrix3d C_base = C_base_truth;
  inject_base_error(l, dx, C_base);
  CHECK((rotvec_from_dcm(C_base_truth * C_base.transpose()) - dx.segment<3>(l.base.index)).norm() <
        1e-12);
  feed_back_base(l, dx, C_base);
  CHECK((C_base - C_base_truth).norm() < 1e-14);
}

TEST_CASE(
    "Error dynamics along the plan's motion: the start's mounting turns the reference into the "
    "IMU's axes",
    "[kalman][dynamics]") {
  // The IMU mounted on the platform 2-3 deg off the plan's axes, noise-free data and the filter
  // at the truth: the transition the table's known motion gives (its rates, specific force and
  // attitude turned by the start's mounting, CalibratorOptions::reference_motion) is the one the
  // navigator's own outputs give. Without the mounting's transpose on the reference rates (stop
  // 29's merge, not caught then) the rates are turned by twice the mounting: the gyros' scale,
  // misalignment and asymmetry columns go red here; a mounting of 1-2 deg in the installation
  // tests stayed inside their sigmas.
  const Plan plan = test::load_plan("rot19.ini");
  TableErrors table;
  table.mounting_b = Eigen::Vector3d(1.5, -2.0, 2.5) * units::deg;
  const Motion mounted = build_motion(plan, plan.site, table);
  const ImuErrorModel truth = every_family_model();
  std::vector<ImuSample> samples;
  for (const auto& s : test::simulate(mounted, truth, 100.0))
    if (s.t <= 76.0 + 1e-9) samples.push_back(s);
  CalibratorOptions o;
  for (const auto& f : coefficient_families())
    if (!f.base && !f.thermal()) o.layout.set(f.name, true);
  o.update_interval = 1e9;  // no update: the transition accumulates over the whole window
  o.initial_model = truth;
  o.start_mounting_b = table.mounting_b;
  StateLayout layout;
  auto transition = [&](std::shared_ptr<const Motion> reference) {
    CalibratorOptions with = o;
    with.reference_motion = std::move(reference);
    Calibrator kf(test::timeline(plan), plan.site, with);
    for (const auto& s : samples) kf.push(s);
    kf.finish();
    layout = kf.layout();
    return kf.propagator().Phi_nc();
  };
  const Eigen::MatrixXd along_plan =
      transition(std::make_shared<const Motion>(build_motion(plan, plan.site)));
  const Eigen::MatrixXd along_navigator = transition(nullptr);
  // Per column, relative to the column (76 s: the dwell and the first turn, 90 deg about East).
  int checked = 0;
  for (Eigen::Index j = 0; j < along_plan.cols(); ++j) {
    const double scale = along_navigator.col(j).norm();
    if (!(scale > 0.0)) continue;
    std::string name;
    for (const auto& cb : layout.coefficients)
      for (int k = 0; k < cb.block.size; ++k)
        if (cb.block.index + k == layout.nav_size + j)
          name = coefficient_catalog()[static_cast<std::size_t>(
                                           cb.catalog[static_cast<std::size_t>(k)])]
                     .name;
    CAPTURE(name, along_plan.col(j).transpose(), along_navigator.col(j).transpose());
    // The inner lever arms act through the angular acceleration, which the navigator's side takes
    // as central differences of the sample rates: at the turn's steps of 10 deg/s^2 they differ
    // from the motion's by up to 2 % of the column (measured), as they would without a mounting.
    const bool arm = name.rfind("accel.lever_arm", 0) == 0;
    CHECK((along_plan.col(j) - along_navigator.col(j)).norm() < (arm ? 5e-2 : 2e-3) * scale);
    ++checked;
  }
  CHECK(checked > 30);
}
