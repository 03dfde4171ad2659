// Throughput benchmarks (not tests): simulator, navigator, log writer and reader, calibrations,
// on one core.
// Prints samples/s and ratios. Usage: bench [SOURCE_DIR [design]] (design: plan design's lines
// only)
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "filter/closed_form/closed_form.hpp"
#include "filter/design/bound.hpp"
#include "filter/design/prediction.hpp"
#include "filter/design/search.hpp"
#include "filter/diagnosis/diagnosis_kalman.hpp"
#include "filter/diagnosis/diagnosis_table.hpp"
#include "filter/diagnosis/handheld_diagnosis.hpp"
#include "filter/kalman/error_propagation.hpp"
#include "filter/kalman/kalman_calibrator.hpp"
#include "filter/six_face/six_face.hpp"
#include "filter/strapdown/strapdown.hpp"
#include "filter/table_free/handheld_run.hpp"
#include "models/config.hpp"
#include "models/sensor_profile.hpp"
#include "rig/imu_sim.hpp"
#include "rig/io/log_io.hpp"
#include "rig/plan.hpp"
#include "rig/session.hpp"
#include "rig/table_spec.hpp"

using namespace sinscal;
using Clock = std::chrono::steady_clock;

namespace {
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
}  // namespace

// The design bound and the seeded search in the toolbox's mode (--attitude none) at 491 s
// (aims: the bound within 10 s, the optimization within 60 s of CPU).
// The toolbox's mode (--attitude none, zero velocity in motion as the table gives it), its
// targets and a budget of 491 s, seeded with rot19, seed8 and toolbox19.
SearchOptions toolbox_search_491(const std::string& src, CalibratorOptions& o,
                                 const TableSpec& table, const Plan& rot) {
  o.attitude = CalibratorOptions::AttitudeUpdates::None;
  o.zero_velocity_in_motion = table.reference_on_axes;
  SearchOptions so;
  so.targets = read_sigma_targets(IniFile(src + "/config/targets/reference-toolbox.ini"));
  so.budget_s = 491.0;
  so.seeds = {rot, Plan::load(src + "/config/plans/seed8.ini"),
              Plan::load(src + "/config/plans/toolbox19.ini")};
  return so;
}

double bench_design_bound(const std::string& src, CalibratorOptions o, const TableSpec& table,
                          const Plan& rot) {
  SearchOptions so = toolbox_search_491(src, o, table, rot);
  so.seeds.push_back(Plan::load(src + "/config/plans/diagonal-491.ini"));
  so.seeds.push_back(Plan::load(src + "/config/plans/searched-491.ini"));
  std::clock_t c0 = std::clock();
  const InformationLibrary lib = information_library(o, table, rot.site, so.targets, so.rate_hz);
  const DesignBound b = relaxed_bound(lib, so.budget_s);
  const double bound_cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  c0 = std::clock();
  const double time_for_targets = bound_time_for_targets(lib);
  const double bisection_cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  c0 = std::clock();
  const SearchResult r = search_plan(o, table, rot.site, SearchSpace{}, so);
  std::printf(
      "design bound at 491 s, --attitude none (%zu segments, library %.1f s, %d iterations): "
      "%.1f s CPU, worst sigma/target >= %.3f (relaxed %.3f; aim 10 s); the time for the "
      "targets >= %.0f s, %.1f s more; the seeded search: %.1f s CPU, %.3f (%s; aim 60 s)\n",
      lib.segments.size(), lib.cpu_s, b.iterations, bound_cpu, b.lower, b.upper, time_for_targets,
      bisection_cpu, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC, r.excess.worst_ratio,
      r.origin.c_str());
  return b.lower + r.excess.worst_ratio;
}

// The search with its structure moves at 491 s and 1000 s in the toolbox's mode, from the hand
// plans only (design --optimize's default of 2000 passes, fewer by the cost of one pass at the
// budget: structure_pass_limit; aim: the whole optimization within 60 s of CPU at any budget).
double bench_structure_moves(const std::string& src, CalibratorOptions o, const TableSpec& table,
                             const Plan& rot) {
  SearchOptions so = toolbox_search_491(src, o, table, rot);
  so.structure_evaluations = 2000;
  double sink = 0.0;
  for (const double budget : {491.0, 1000.0}) {
    so.budget_s = budget;
    const std::clock_t c0 = std::clock();
    const SearchResult r = search_plan(o, table, rot.site, SearchSpace{}, so);
    std::printf(
        "design --optimize at %.0f s with structure moves (rot19, seed8, toolbox19 as seeds; %d "
        "of at most %d passes of the moves, %zu kept): %.1f s CPU, worst sigma/target %.4f (%s, "
        "%s; aim 60 s)\n",
        budget, r.structure_evaluations, r.structure_limit, r.structure.size(),
        static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC, r.excess.worst_ratio,
        r.excess.worst_family.c_str(), r.origin.c_str());
    sink += r.excess.worst_ratio;
  }
  return sink;
}

// Plan design: the covariance pass over rot19 (592 s) with nav-fog-extended, CPU time (aim 0.2 s).
double bench_design(const std::string& src) {
  const Plan rot = Plan::load(src + "/config/plans/rot19.ini");
  const SensorProfile profile = SensorProfile::load(src + "/config/sensors/nav-fog-extended.ini");
  const CalibratorOptions o = calibrator_options_from_profile(profile);
  double sink = 0.0;
  for (const double rate : {20.0, 50.0, 100.0}) {
    DesignOptions d;
    d.rate_hz = rate;
    double best = 1e300;
    for (int pass = 0; pass < 3; ++pass) {
      const std::clock_t c0 = std::clock();
      const PlanPrediction p = predict_plan(rot, o, profile.sigma_targets, d);
      best = std::min(best, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
      sink += p.run.estimates[0].sigma;
    }
    std::printf("design of rot19 (covariance pass, ideal IMU at %.0f Hz): %.3f s CPU%s\n", rate,
                best, rate == 50.0 ? " (the default rate; aim 0.2 s)" : "");
  }
  // The search for the targets within half of rot19's time (aim: 60 s CPU on one core).
  const TableSpec table = TableSpec::load(src + "/config/tables/two-axis-20.ini");
  SearchOptions so;
  so.targets = read_sigma_targets(IniFile(src + "/config/targets/reference-toolbox.ini"));
  so.budget_s = 296.0;
  const std::clock_t c0 = std::clock();
  const SearchResult r = search_plan(o, table, rot.site, SearchSpace{}, so);
  std::printf(
      "design --optimize within 296 s (beam 4, 20 Hz): %d covariance passes, %.1f s CPU "
      "(aim 60 s)\n",
      r.evaluations, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
  return sink + r.excess.J + bench_design_bound(src, o, table, rot) +
         bench_structure_moves(src, o, table, rot);
}

// Table-free calibration and diagnosis of the Xsens MTi hand-held session.
void bench_handheld(const std::string& src) {
  Clock::time_point t0;
  // Table-free calibration of the Xsens MTi hand-held session (config/measured, the files of
  // data/ read in place): reading both files, pose detection, calibration (aim: 1 s).
  const std::string xsens = src + "/config/measured/xsens-mti-handheld/session.ini";
  try {
    const Session hs = Session::load(xsens, Session::PlanNeed::Optional);
    double t_tf = 1e300;
    TableFreeRun tf;
    for (int pass = 0; pass < 3; ++pass) {
      t0 = Clock::now();
      tf = run_table_free(hs, TableFreeRunOptions{});
      t_tf = std::min(t_tf, seconds_since(t0));
    }
    std::printf(
        "table-free calibration of the Xsens MTi session (%zu samples, %zu poses, files read "
        "included): %.3f s (aim 1 s)\n",
        tf.samples, tf.poses.size(), t_tf);
    // Its diagnosis (filter/diagnosis/handheld_diagnosis.hpp): every candidate refitted, held-out
    // figures, the Allan deviation of the longest pose (aim: calibration + diagnosis 2 s).
    double t_dg = 1e300;
    HandheldDiagnosis dg;
    for (int pass = 0; pass < 3; ++pass) {
      t0 = Clock::now();
      dg = diagnose_handheld(tf.readings, tf.result, tf.options);
      t_dg = std::min(t_dg, seconds_since(t0));
    }
    std::size_t refits = 0;
    for (const auto& round : dg.report.rounds)
      for (const auto& c : round) refits += c.dof > 0 ? 1 : 0;
    std::printf(
        "diagnosis of the Xsens MTi session (%d residuals, %zu candidate refits, %zu "
        "findings): %.3f s; calibration + diagnosis %.3f s (aim 2 s)\n",
        dg.rows, refits, dg.report.findings.size(), t_dg, t_tf + t_dg);
  } catch (const std::exception& e) {
    std::printf("table-free calibration of the Xsens MTi session: failed: %s\n", e.what());
  }
}

// Model discovery on rot19 (100 Hz) as `sinscal diagnose` runs it: the closed form, then the
// dwells and the turns in one ranking (filter/diagnosis_table), with an accelerometer K2 the
// session's nav-fog profile lacks (the case: an ambiguous set, then a round against the
// extended model, held-out turns for the gain). CPU time (std::clock) and wall time.
double bench_kalman_diagnosis(const std::string& src) {
  double sink = 0.0;
  const std::string dir = (std::filesystem::temp_directory_path() / "sinscal_bench_kdiag").string();
  std::filesystem::create_directories(dir);
  {
    std::ifstream in(src + "/config/sensors/nav-fog.ini");
    std::ofstream out(dir + "/data-sensor.ini");
    out << in.rdbuf() << "\n[accel]\nk2 = 20 30 ug/g^2\n";
  }
  SessionSimulation spec;
  spec.plan_path = src + "/config/plans/rot19.ini";
  spec.data_sensor_path = dir + "/data-sensor.ini";
  spec.filter_sensor_path = src + "/config/sensors/nav-fog.ini";
  spec.seed = 3;
  const SimulatedSession sim = simulate_session(dir + "/session", spec);
  const Session session = Session::load(sim.session_path);
  const SensorProfile profile = SensorProfile::load(session.sensor_file);
  double cpu = 1e300, wall = 1e300;
  std::size_t runs = 0, findings = 0;
  for (int pass = 0; pass < 2; ++pass) {
    const std::clock_t c0 = std::clock();
    const Clock::time_point t0 = Clock::now();
    TurnModel model = turn_model_of(session, profile, kDefaultTableAttitudeSigma);
    const auto about = linearize(model, 0);
    const ClosedFormReport cal = run_closed_form(session, default_stage1(&profile),
                                                 TableAttitudeError{kDefaultTableAttitudeSigma},
                                                 !about, about ? &*about : nullptr);
    const TableDiagnosis d = diagnose_table(cal.stage1, session.site, cal.stage2_options,
                                            TableDiagnosisOptions{}, &model);
    cpu = std::min(cpu, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
    wall = std::min(wall, seconds_since(t0));
    runs = 1;  // the session's model
    for (const auto& round : d.turns->rounds) runs += round.size();
    for (const auto& f : d.findings) runs += 1 + (f.turns_before ? 2 : 0) + 2;  // extend, held out
    findings = d.findings.size();
    sink += d.dwells.initial.chi2;
  }
  std::filesystem::remove_all(dir);
  std::printf(
      "diagnosis of rot19 with the turns' test (%zu samples, K2 hidden: %zu finding(s), about %zu "
      "filter runs): %.2f s CPU, %.2f s wall (aim 5 s CPU)\n",
      sim.samples, findings, runs, cpu, wall);
  return sink;
}

// Six-face calibration (filter/six_face/six_face.hpp): imucal's 46 s recording (204.8 Hz) read
// and calibrated, and a simulated two-minute Ferraris session at 200 Hz from memory (aim: a
// two-minute session under 0.2 s CPU). CPU time (std::clock), best of 5.
double bench_six_face(const std::string& src) {
  double sink = 0.0;
  const Session s = Session::load(src + "/config/measured/imucal-ferraris/session.ini",
                                  Session::PlanNeed::Optional);
  double cpu = 1e300;
  for (int pass = 0; pass < 5; ++pass) {
    const std::clock_t c0 = std::clock();
    sink += six_face_calibrate(read_parts(s), six_face_options(s)).accel_chi2;
    cpu = std::min(cpu, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
  }
  std::printf("six-face: imucal's session (9414 readings, 46 s), read and calibrated: %.4f s CPU\n",
              cpu);
  FerrarisOptions fo;
  fo.rest = 10.0;
  fo.turn = 10.0;
  Site site;
  site.lat_rad = 0.87;
  const FerrarisSession session = ferraris_session(site, fo, 1);
  const SensorProfile prof = SensorProfile::load(src + "/config/sensors/mems.ini");
  SimulatorOptions so;
  so.rate_hz = 200.0;
  std::vector<ImuSample> samples;
  {
    ImuSimulator sim(session.motion, prof.draw(2), prof.noise, so);
    ImuSample x;
    while (sim.next(x)) samples.push_back(x);
  }
  std::vector<std::string> labels;
  labels.reserve(samples.size());
  for (const auto& x : samples) labels.push_back(session.label_at(x.t - 0.5 * x.dt));
  cpu = 1e300;
  for (int pass = 0; pass < 5; ++pass) {
    const std::clock_t c0 = std::clock();
    PartAccumulator parts({"x_rot", "y_rot", "z_rot"});
    for (std::size_t i = 0; i < samples.size(); ++i) parts.push(samples[i], labels[i]);
    SixFaceOptions o;
    o.site = site;
    sink += six_face_calibrate(parts.parts(), o).accel_chi2;
    cpu = std::min(cpu, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
  }
  std::printf(
      "six-face: a simulated %.0f s session at 200 Hz (%zu samples) from memory: %.4f s CPU, "
      "%.2e samples/s (aim: a two-minute session under 0.2 s CPU)\n",
      session.motion.duration(), samples.size(), cpu, static_cast<double>(samples.size()) / cpu);
  return sink;
}

// The thermal filter's cost per sample against the fixed-temperature filter's (issue 19: at
// most 1.5x): rot19 simulated with nav-fog's errors, its samples given a chamber ramp's
// temperature (1 C/min from -40 C), calibrated with nav-fog-thermal (the thermal states) and with
// nav-fog (without), both from memory.
double bench_thermal(const std::string& src) {
  const Plan rot = Plan::load(src + "/config/plans/rot19.ini");
  const Motion motion = build_motion(rot, rot.site);
  const SensorProfile fixed = SensorProfile::load(src + "/config/sensors/nav-fog.ini");
  const SensorProfile thermal = SensorProfile::load(src + "/config/sensors/nav-fog-thermal.ini");
  std::vector<ImuSample> samples;
  {
    ImuSimulator sim(motion, fixed.draw(1), fixed.noise, SimulatorOptions{});
    ImuSample s;
    while (sim.next(s)) {
      s.has_temperature = true;
      s.accel_temperature_c = s.gyro_temperature_c = -40.0 + s.t / 60.0;
      samples.push_back(s);
    }
  }
  double sink = 0.0;
  const auto run = [&](const SensorProfile& profile, int* states) {
    double best = 1e300;
    for (int pass = 0; pass < 3; ++pass) {
      Calibrator kf(PlanTimeline::of(rot, rot.site), rot.site,
                    calibrator_options_from_profile(profile));
      const auto t0 = Clock::now();
      for (const auto& s : samples) kf.push(s);
      kf.finish();
      best = std::min(best, seconds_since(t0));
      *states = kf.layout().size;
      sink += kf.estimate()[0].value;
    }
    return best;
  };
  int n_fixed = 0, n_thermal = 0;
  const double t_fixed = run(fixed, &n_fixed);
  const double t_thermal = run(thermal, &n_thermal);
  const double n = static_cast<double>(samples.size());
  std::printf(
      "thermal Kalman filter on rot19 with a ramp's temperature: %d states %.0f samples/s, "
      "without the thermal states %d states %.0f samples/s: %.2fx per sample (aim 1.5x)\n",
      n_thermal, n / t_thermal, n_fixed, n / t_fixed, t_thermal / t_fixed);
  return sink;
}

// The Kalman filter's cost per sample by stage, from memory on rot19 (each stage alone, the
// best of three passes, in microseconds per sample): navigation, compensation with the filter's
// model, the error model's Jacobian, the propagator's step (the transition and the coefficient
// coupling, the Jacobian inside), and the whole filter (the rest: covariance propagation and
// updates once per second, the supervision).
double bench_kalman_stages(const Plan& rot, const Motion& rot_motion,
                           const std::vector<ImuSample>& samples, const SensorProfile& profile,
                           const ImuErrorModel& errors) {
  double sink = 0.0;
  const double n = static_cast<double>(samples.size());
  auto best = [&](auto&& body) {
    double t = 1e300;
    for (int pass = 0; pass < 3; ++pass) {
      const auto t0 = Clock::now();
      body();
      t = std::min(t, seconds_since(t0));
    }
    return 1e6 * t / n;
  };
  const Eigen::Matrix3d C0 = rot_motion.dwells()[0].C_b_n_known;
  const ImuErrorModel::LinearInverses inverses = errors.linear_inverses();
  const double t_nav = best([&] {
    Strapdown nav;
    nav.reset(NavState::at_rest(C0, rot.site));
    for (const auto& s : samples) nav.step(s.dtheta_b, s.dv_b, s.dt);
    sink += nav.state().v_n.norm();
  });
  const double t_comp = best([&] {
    KinematicSample k;
    for (const auto& s : samples) {
      errors.compensate(s.dtheta_b / s.dt, s.dv_b / s.dt, Eigen::Vector3d::Zero(), k.omega_ib_b,
                        k.f_ib_b, s.t, &k, &inverses);
      sink += k.f_ib_b(0);
    }
  });
  // As run_kalman runs it: the error dynamics along the plan's motion.
  CalibratorOptions options = calibrator_options_from_profile(profile);
  options.reference_motion = std::make_shared<const Motion>(rot_motion);
  const StateLayout layout = StateLayout::make(effective_layout(options));
  std::vector<int> catalog;
  for (const auto& cb : layout.coefficients)
    for (int c : cb.catalog) catalog.push_back(c);
  const double t_jac = best([&] {
    ImuErrorModel::JacobianColumns J;
    KinematicSample k;
    for (const auto& s : samples) {
      k.omega_ib_b = s.dtheta_b / s.dt;
      k.f_ib_b = s.dv_b / s.dt;
      k.t = s.t;
      errors.jacobian(k, Eigen::Vector3d::Zero(), catalog, J);
      sink += J(0, 0);
    }
  });
  const double t_step = best([&] {
    ErrorPropagator propagator(layout, InsSiteTerms::at(rot.site), profile.noise);
    KinematicSample k;
    for (const auto& s : samples) {
      k.omega_ib_b = s.dtheta_b / s.dt;
      k.f_ib_b = s.dv_b / s.dt;
      k.t = s.t;
      propagator.step(C0, k, Eigen::Vector3d::Zero(), errors, inverses, s.dt);
      if (propagator.accumulated() >= 1.0) {
        sink += propagator.Q_nn()(0, 0);
        propagator = ErrorPropagator(layout, InsSiteTerms::at(rot.site), profile.noise);
      }
    }
  });
  const double t_kf = best([&] {
    Calibrator kf(PlanTimeline::of(rot, rot.site), rot.site, options);
    for (const auto& s : samples) kf.push(s);
    kf.finish();
    sink += kf.estimate()[0].value;
  });
  std::printf(
      "Kalman filter by stage on rot19 (%d states, us per sample): navigation %.3f, "
      "compensation %.3f, Jacobian (%zu columns) %.3f, propagator step (Jacobian included) "
      "%.3f, the rest (covariance propagation and updates, supervision) %.3f; whole filter "
      "%.3f\n",
      layout.size, t_nav, t_comp, catalog.size(), t_jac, t_step, t_kf - t_nav - t_comp - t_step,
      t_kf);
  return sink;
}

int main(int argc, char** argv) {
  const std::string src = argc > 1 ? argv[1] : ".";
  if (argc > 2 && std::string(argv[2]) == "design") return bench_design(src) > 0.0 ? 0 : 1;
  if (argc > 2 && std::string(argv[2]) == "diagnosis")  // rot19's diagnosis alone (aim 5 s CPU)
    return bench_kalman_diagnosis(src) > 0.0 ? 0 : 1;
  const Plan plan = Plan::load(src + "/config/plans/seed8.ini");
  const SensorProfile profile = SensorProfile::load(src + "/config/sensors/nav-fog-extended.ini");
  const Motion motion = build_motion(plan, plan.site);
  const ImuErrorModel errors = profile.draw(1);

  // Simulator: full extended error model and noise, 100 Hz.
  SimulatorOptions so;
  std::vector<ImuSample> samples;
  auto t0 = Clock::now();
  {
    ImuSimulator sim(motion, errors, profile.noise, so);
    samples.reserve(sim.total_samples());
    ImuSample s;
    while (sim.next(s)) samples.push_back(s);
  }
  const double t_sim = seconds_since(t0);
  const double n = static_cast<double>(samples.size());

  // Navigator: several passes over the samples, best pass reported.
  double t_nav = 1e300;
  double sink = 0.0;
  for (int pass = 0; pass < 5; ++pass) {
    Strapdown nav;
    nav.reset(NavState::at_rest(motion.dwells()[0].C_b_n_known, plan.site));
    t0 = Clock::now();
    for (const auto& s : samples) nav.step(s.dtheta_b, s.dv_b, s.dt);
    t_nav = std::min(t_nav, seconds_since(t0));
    sink += nav.state().v_n.norm();
  }

  // Log write and read.
  const std::string path =
      (std::filesystem::temp_directory_path() / "sinscal_bench_imu.csv").string();
  t0 = Clock::now();
  {
    LogWriter w(path, so.rate_hz);
    for (const auto& s : samples) w.write(s);
    w.close();
  }
  const double t_write = seconds_since(t0);
  t0 = Clock::now();
  {
    LogReader r(LogFormat::native_format(path, so.rate_hz));
    ImuSample s;
    while (r.next(s)) sink += s.dt;
  }
  const double t_read = seconds_since(t0);
  std::filesystem::remove(path);

  // Closed-form method: navigation through the 8 dwells, stage 1 (fit, coupled, 4 channels) and
  // stage 2, on the in-memory session.
  double t_cf = 1e300;
  for (int pass = 0; pass < 3; ++pass) {
    VectorSource source(samples);
    Stage1Options o;
    o.model = ErrorModelKind::Coupled;
    o.channels.vertical = o.channels.heading = true;
    o.arw = profile.noise.gyro.white;
    o.vrw = profile.noise.accel.white;
    t0 = Clock::now();
    const auto in = run_stage1(source, PlanTimeline::of(plan, plan.site).dwells, plan.site, o);
    const Stage2Result r = solve_stage2(in, plan.site, Stage2Options{});
    t_cf = std::min(t_cf, seconds_since(t0));
    sink += r.theta(0);
  }

  const double real_time = motion.duration();
  std::printf("sinscal bench: plan seed8 (%.0f s at %.0f Hz, %.0f samples), profile %s\n",
              real_time, so.rate_hz, n, profile.name.c_str());
  std::printf("%-34s %14s %14s\n", "stage", "samples/s", "x real time");
  auto row = [&](const char* name, double t) {
    std::printf("%-34s %14.0f %14.0f\n", name, n / t, real_time / t);
  };
  row("simulator (extended model, noise)", t_sim);
  row("strapdown navigator", t_nav);
  row("log write (native CSV)", t_write);
  row("log read (native CSV)", t_read);
  row("closed-form calibration (1+2)", t_cf);
  std::printf("closed-form calibration of the 8-orientation session: %.3f s per session\n", t_cf);
  // Kalman filter, full extended model, on the 19-position rotation plan.
  const Plan rot = Plan::load(src + "/config/plans/rot19.ini");
  const Motion rot_motion = build_motion(rot, rot.site);
  std::vector<ImuSample> rot_samples;
  {
    ImuSimulator sim(rot_motion, errors, profile.noise, so);
    ImuSample s;
    while (sim.next(s)) rot_samples.push_back(s);
  }
  // As run_kalman runs the filter: the error dynamics along the plan's motion.
  CalibratorOptions rot_options = calibrator_options_from_profile(profile);
  if (follows_plan_motion(rot_options))
    rot_options.reference_motion = std::make_shared<const Motion>(rot_motion);
  double t_kf = 1e300;
  int states = 0;
  for (int pass = 0; pass < 3; ++pass) {
    Calibrator kf(PlanTimeline::of(rot, rot.site), rot.site, rot_options);
    t0 = Clock::now();
    for (const auto& s : rot_samples) kf.push(s);
    kf.finish();
    t_kf = std::min(t_kf, seconds_since(t0));
    states = kf.layout().size;
    sink += kf.estimate()[0].value;
  }
  std::printf(
      "Kalman filter (%d states) on rot19 (%.0f s): %.0f samples/s, %.0fx real time "
      "(aim 1000x)\n",
      states, rot_motion.duration(), static_cast<double>(rot_samples.size()) / t_kf,
      rot_motion.duration() / t_kf);
  // Model discovery on the rot19 session's static dwells: stage 1, then every candidate refit.
  {
    Stage1Options o;
    o.model = ErrorModelKind::Coupled;
    o.channels.vertical = o.channels.heading = true;
    o.arw = profile.noise.gyro.white;
    o.vrw = profile.noise.accel.white;
    double t_s1 = 1e300, t_diag = 1e300;
    std::size_t candidates = 0;
    for (int pass = 0; pass < 3; ++pass) {
      VectorSource source(rot_samples);
      t0 = Clock::now();
      const auto in = run_stage1(source, PlanTimeline::of(rot, rot.site).dwells, rot.site, o);
      t_s1 = std::min(t_s1, seconds_since(t0));
      t0 = Clock::now();
      const DiagnosisReport d = diagnose_static(in, rot.site, Stage2Options{});
      t_diag = std::min(t_diag, seconds_since(t0));
      candidates = 0;
      for (const auto& round : d.rounds) candidates += round.size();
      sink += d.initial.chi2;
    }
    std::printf(
        "diagnosis of rot19 (static dwells): stage 1 %.3f s, %zu candidate refits %.3f s "
        "(aim 10 s)\n",
        t_s1, candidates, t_diag);
  }
  // The filter's cost per sample as a ratio to reading and navigating the same log alone (the
  // floor any calibration from a log pays): both from the same native CSV on disk.
  const std::string rot_path =
      (std::filesystem::temp_directory_path() / "sinscal_bench_rot19.csv").string();
  {
    LogWriter w(rot_path, so.rate_hz);
    for (const auto& s : rot_samples) w.write(s);
    w.close();
  }
  const LogFormat rot_log = LogFormat::native_format(rot_path, so.rate_hz);
  double t_read_nav = 1e300, t_kf_log = 1e300;
  for (int pass = 0; pass < 3; ++pass) {
    t0 = Clock::now();
    {
      LogReader r(rot_log);
      Strapdown nav;
      nav.reset(NavState::at_rest(rot_motion.dwells()[0].C_b_n_known, rot.site));
      ImuSample s;
      while (r.next(s)) nav.step(s.dtheta_b, s.dv_b, s.dt);
      sink += nav.state().v_n.norm();
    }
    t_read_nav = std::min(t_read_nav, seconds_since(t0));
    t0 = Clock::now();
    {
      LogReader r(rot_log);
      Calibrator kf(PlanTimeline::of(rot, rot.site), rot.site, rot_options);
      ImuSample s;
      while (r.next(s)) kf.push(s);
      kf.finish();
      sink += kf.estimate()[0].value;
    }
    t_kf_log = std::min(t_kf_log, seconds_since(t0));
  }
  std::filesystem::remove(rot_path);
  std::printf(
      "rot19 from its log: read + navigate %.0f samples/s, Kalman filter %.0f samples/s: the "
      "filter costs %.1fx reading and navigating\n",
      static_cast<double>(rot_samples.size()) / t_read_nav,
      static_cast<double>(rot_samples.size()) / t_kf_log, t_kf_log / t_read_nav);
  sink += bench_kalman_stages(rot, rot_motion, rot_samples, profile, errors);
  sink += bench_kalman_diagnosis(src);
  sink += bench_design(src);
  bench_handheld(src);
  sink += bench_six_face(src);
  sink += bench_thermal(src);
  std::printf("navigator / simulator throughput ratio: %.1f\n", t_sim / t_nav);
  std::printf("navigator aim: 5e6 samples/s -> %s\n", n / t_nav >= 5e6 ? "met" : "NOT met");
  return sink > 0 ? 0 : 1;
}
