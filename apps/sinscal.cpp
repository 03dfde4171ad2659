// sinscal command-line tool: parses options, calls the library, prints. No algorithms here.
#include <signal.h>  // sigaction: Ctrl-C ends a streaming run with its results written
#include <unistd.h>  // isatty: the live table only on a terminal

#include <algorithm>
#include <atomic>
#include <boost/program_options.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>

#include "filter/closed_form.hpp"
#include "filter/dwell_navigation.hpp"
#include "filter/kalman_calibrator.hpp"
#include "filter/monitor.hpp"
#include "models/config.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "rig/imu_sim.hpp"
#include "rig/log_io.hpp"
#include "rig/plan.hpp"
#include "rig/session.hpp"

namespace po = boost::program_options;
using namespace sinscal;

namespace {

constexpr int kUsageError = 1;
constexpr int kDataError = 2;
constexpr int kDisagree = 3;       // compare: the results differ beyond the given tolerance
constexpr int kInterrupted = 130;  // SIGINT / SIGTERM: stopped, what was computed written

// Set by SIGINT / SIGTERM: a calibration stops reading, finishes and writes its results.
std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop.store(true); }
void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a read blocked on standard input returns
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

po::variables_map parse(const std::vector<std::string>& args, const po::options_description& desc,
                        const std::string& usage) {
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(desc).run(), vm);
  if (vm.count("help")) {
    std::cout << usage << "\n" << desc << "\n";
    throw 0;
  }
  po::notify(vm);
  return vm;
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

int cmd_simulate(const std::vector<std::string>& args) {
  po::options_description d("sinscal simulate options");
  std::string plan_path, sensor_path, out_dir;
  double rate = 100.0, angle_sigma_arcsec = 0.0, non_orth_arcsec = 0.0;
  unsigned long long seed = 1;
  d.add_options()("help,h", "this help")("plan", po::value(&plan_path)->required(),
                                         "plan INI file (config/plans/*.ini)")(
      "sensor", po::value(&sensor_path)->required(), "sensor profile INI (config/sensors/*.ini)")(
      "out", po::value(&out_dir)->required(), "output session directory")(
      "rate", po::value(&rate)->default_value(100.0), "IMU output rate [Hz]")(
      "seed", po::value(&seed)->default_value(1), "seed of all random draws")(
      "no-noise", "no sensor noise (coefficients still drawn)")(
      "table-angles", "log the table's outer and inner axis angles (plans of table moves)")(
      "perfect", "no sensor errors at all (zero coefficients, no noise)")(
      "table-angle-sigma", po::value(&angle_sigma_arcsec)->default_value(0.0),
      "table angle error per commanded angle, 1-sigma [arcsec]")(
      "table-non-orthogonality", po::value(&non_orth_arcsec)->default_value(0.0),
      "lean of the inner axis [arcsec]");
  const auto vm = parse(args, d,
                        "Usage: sinscal simulate --plan P --sensor S --out DIR [--rate HZ] "
                        "[--seed N] [--no-noise]\nSimulates a calibration session: DIR/imu.csv, "
                        "session.ini, plan.ini, sensor.ini, truth.json.");
  if (!(rate > 0.0)) throw UsageError("--rate must be positive");
  SessionSimulation spec;
  spec.plan_path = plan_path;
  spec.data_sensor_path = sensor_path;
  spec.rate_hz = rate;
  spec.seed = seed;
  spec.perfect = vm.count("perfect") > 0;
  spec.noise = !vm.count("no-noise");
  spec.table_angles = vm.count("table-angles") > 0;
  spec.table.angle_sigma = angle_sigma_arcsec * units::arcsec;
  spec.table.non_orthogonality = non_orth_arcsec * units::arcsec;
  spec.table.seed = derive_seed(seed, 3);
  const auto t0 = std::chrono::steady_clock::now();
  const SimulatedSession sim = simulate_session(out_dir, spec);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const bool noise = spec.noise && !spec.perfect;
  const Plan& plan = sim.plan;
  const SensorProfile& profile = sim.profile;
  const ImuErrorModel& truth = sim.truth;
  std::cout << "Simulated plan '" << plan.name << "' (" << plan.path << "), sensor '"
            << profile.name << "'\n  " << sim.samples << " samples at " << rate << " Hz, "
            << fmt("%.1f", sim.duration) << " s, " << sim.dwells << " dwells, "
            << (noise ? "noise on" : "noise off") << ", "
            << fmt("%.0f", static_cast<double>(sim.samples) / seconds) << " samples/s written\n";
  if (sim.saturated > 0)
    std::cout << "  WARNING: " << sim.saturated << " samples clipped at the sensor range\n";
  std::cout << "  session: " << out_dir << "/session.ini\n  injected coefficients (truth.json):\n";
  for (const auto& info : coefficient_catalog()) {
    const double v = truth.coefficients().at(info.name);
    if (v != 0.0) std::printf("    %-28s %12.4f %s\n", info.name.c_str(), v, info.unit.c_str());
  }
  return 0;
}

int cmd_navigate(const std::vector<std::string>& args) {
  po::options_description d("sinscal navigate options");
  std::string session_path, out_path, vertical;
  double interval = 1.0;
  d.add_options()("help,h", "this help")("session", po::value(&session_path)->required(),
                                         "session.ini of the recording")(
      "out", po::value(&out_path)->required(), "navigation error CSV to write")(
      "interval", po::value(&interval)->default_value(1.0),
      "output interval [s] (0: every sample)")(
      "vertical", po::value(&vertical)->default_value("free"), "vertical channel: free | held");
  parse(args, d,
        "Usage: sinscal navigate --session DIR/session.ini --out nav.csv\nNavigates through each "
        "static dwell of the plan from its known attitude, zero velocity and known position, and "
        "writes the navigation errors against them.");
  if (vertical != "free" && vertical != "held") throw UsageError("--vertical must be free or held");
  if (interval < 0.0) throw UsageError("--interval must not be negative");
  const Session session = Session::load(session_path);
  const PlanTimeline timeline = PlanTimeline::of(session.plan, session.site);
  DwellNavOptions opt;
  opt.output_interval = interval;
  opt.time_offset = session.time_offset;
  opt.strapdown.vertical_held = vertical == "held";
  DwellNavigation run(timeline.dwells, session.site, opt);
  LogReader reader(session.log);

  std::ofstream out(out_path);
  if (!out) throw std::runtime_error(out_path + ": cannot create");
  out << "dwell,t_log [s],t [s],dv_n [m/s],dv_e [m/s],dv_d [m/s],phi_n [arcsec],phi_e [arcsec],"
         "phi_d [arcsec],dp_n [m],dp_e [m],dp_d [m]\n";
  auto sink = [&](const DwellNavRow& r) {
    char b[400];
    const NavError& e = r.error;
    std::snprintf(b, sizeof b, "%d,%.6f,%.6f,%.9e,%.9e,%.9e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e\n",
                  r.dwell, r.t_log, e.t, e.dv_n.x(), e.dv_n.y(), e.dv_n.z(),
                  e.phi_n.x() / units::arcsec, e.phi_n.y() / units::arcsec,
                  e.phi_n.z() / units::arcsec, e.dp_n.x(), e.dp_n.y(), e.dp_n.z());
    out << b;
  };
  auto print_summary = [&] {
    std::printf("Navigation through the dwells of '%s' (%s convention), vertical channel %s\n",
                session.plan.name.c_str(), to_string(session.plan.convention).c_str(),
                vertical.c_str());
    std::printf("%5s %-14s %8s %8s %8s %7s %10s %10s %10s %10s %10s\n", "dwell", "label", "heading",
                "pitch", "roll", "T", "dv_n", "dv_e", "phi_n", "phi_e", "phi_d");
    std::printf("%5s %-14s %8s %8s %8s %7s %10s %10s %10s %10s %10s\n", "", "", "[deg]", "[deg]",
                "[deg]", "[s]", "[mm/s]", "[mm/s]", "[arcsec]", "[arcsec]", "[arcsec]");
    for (const auto& s : run.summaries()) {
      const EulerAngles a = euler_from_C_b_n(session.plan.convention, s.dwell.C_b_n_known);
      const NavError& e = s.final_error;
      std::printf("%5d %-14s %8.2f %8.2f %8.2f %7.1f %10.4f %10.4f %10.4f %10.4f %10.4f\n",
                  s.dwell.index, s.dwell.label.c_str(), a.heading / units::deg,
                  a.pitch / units::deg, a.roll / units::deg, e.t, e.dv_n.x() * 1e3,
                  e.dv_n.y() * 1e3, e.phi_n.x() / units::arcsec, e.phi_n.y() / units::arcsec,
                  e.phi_n.z() / units::arcsec);
    }
    std::printf("Navigation errors written to %s\n", out_path.c_str());
  };
  try {
    run.run(reader, sink);
  } catch (...) {
    out.close();
    print_summary();  // what was computed is kept and shown
    throw;
  }
  out.close();
  if (!out) throw std::runtime_error(out_path + ": write failed");
  print_summary();
  return 0;
}

// Coefficient, estimate, sigma, unit; truth, error and error/sigma when the session has truth.
void print_coefficient_table(const ResultCoefficients& coefficients, const Session& session,
                             bool accel_triad_frame = false) {
  const ResultCoefficients truth = load_truth(session, accel_triad_frame);
  std::printf("\n%-24s %12s %10s %-7s", "coefficient", "estimate", "sigma", "unit");
  if (!truth.empty()) std::printf(" %12s %10s %7s", "truth", "error", "err/sig");
  std::printf("\n");
  for (const auto& info : coefficient_catalog()) {
    const auto it = coefficients.find(info.name);
    if (it == coefficients.end()) continue;
    const ResultCoefficient& c = it->second;
    const bool estimated = c.observable && !c.fixed_by_convention;
    if (c.fixed_by_convention) {
      std::printf("%-24s %23s %-7s", info.name.c_str(), "0 (convention)", c.unit.c_str());
    } else if (!c.observable) {
      std::printf("%-24s %23s %-7s", info.name.c_str(), "unobservable", c.unit.c_str());
    } else {
      std::printf("%-24s %12.4f %10.4f %-7s", info.name.c_str(), c.value, *c.sigma, c.unit.c_str());
    }
    const auto t = truth.find(info.name);
    if (t != truth.end()) {
      if (estimated)
        std::printf(" %12.4f %10.4f %7.2f", t->second.value, c.value - t->second.value,
                    (c.value - t->second.value) / *c.sigma);
      else
        std::printf(" %12.4f", t->second.value);
    }
    std::printf("\n");
  }
}

// Live convergence table on a terminal (standard error), redrawn at every monitor record: per
// coefficient family, the largest sigma against its target.
void print_live_table(const nlohmann::ordered_json& rec,
                      const std::map<std::string, double>& targets) {
  std::map<std::string, std::pair<double, std::string>> worst;  // family -> max sigma, unit
  for (const auto& info : coefficient_catalog()) {
    if (!rec["coefficients"].contains(info.name)) continue;
    const double sigma = rec["coefficients"][info.name][1].get<double>();
    auto& w = worst[coefficient_family(info.name)];
    if (sigma >= w.first) w = {sigma, info.unit};
  }
  std::fprintf(stderr, "\033[H\033[J");  // home, clear
  std::fprintf(stderr, "sinscal calibrate --method kf   t = %.1f s   NIS/dof %.3f   %s\n",
               rec["t"].get<double>(), rec["nis_per_dof"].get<double>(),
               rec["converged"].get<bool>() ? "CONVERGED" : "converging");
  std::fprintf(stderr, "%-22s %12s %12s %-8s\n", "family", "max sigma", "target", "unit");
  for (const auto& [family, w] : worst) {
    const auto t = targets.find(family);
    double target_in_unit = 0.0;
    if (t != targets.end())
      for (const auto& info : coefficient_catalog())
        if (coefficient_family(info.name) == family) {
          target_in_unit = t->second / info.si_per_unit;
          break;
        }
    std::fprintf(stderr, "%-22s %12.4g %12s %-8s %s\n", family.c_str(), w.first,
                 t == targets.end() ? "-" : std::to_string(target_in_unit).c_str(),
                 w.second.c_str(),
                 t == targets.end() ? "" : (w.first <= target_in_unit ? "ok" : ""));
  }
}

void print_kalman_verdicts(const KalmanReport& kr, const SensorProfile& profile) {
  std::vector<std::string> fixed;
  for (const auto& [name, c] : kr.coefficients)
    if (c.fixed_by_convention) fixed.push_back(name);
  if (!fixed.empty()) {
    std::printf("\nBody frame = accelerometer triad (no table attitude): zero by convention:");
    for (const auto& n : fixed) std::printf(" %s", n.c_str());
    std::printf("\n");
  }
  if (!kr.unobservable.empty()) {
    std::fprintf(stderr,
                 "sinscal calibrate: warning: the plan does not observe these coefficients (the "
                 "data determine them worse than the prior did; reported as not observable):");
    for (const auto& n : kr.unobservable) std::fprintf(stderr, " %s", n.c_str());
    std::fprintf(stderr, "\n");
  }
  if (profile.sigma_targets.empty())
    std::printf("Convergence: the sensor profile sets no sigma targets ([targets])\n");
  else if (kr.converged_at)
    std::printf("Convergence: every sigma below its target from t = %.1f s\n", *kr.converged_at);
  else {
    std::printf("Convergence: NOT converged: sigma above its target at the end:");
    for (const auto& name : kr.above_target) {
      const CoefficientInfo& info = coefficient_info(name);
      std::printf(
          " %s (%.3g > %.3g %s)", name.c_str(), kr.coefficients.at(name).sigma.value_or(0.0),
          profile.sigma_targets.at(coefficient_family(name)) / info.si_per_unit, info.unit.c_str());
    }
    std::printf("\n");
  }
  if (kr.skipped > 0) {
    std::fprintf(stderr, "sinscal calibrate: warning: %zu bad samples skipped, the first:\n",
                 kr.skipped);
    for (const auto& m : kr.skipped_examples) std::fprintf(stderr, "  %s\n", m.c_str());
  }
}

// --channels: stage-1 channels of the closed form, comma separated; north and east required.
ChannelSet parse_channels(const std::string& list) {
  ChannelSet c{false, false, false, false};
  std::stringstream cs(list);
  for (std::string name; std::getline(cs, name, ',');) {
    if (name == "north")
      c.north = true;
    else if (name == "east")
      c.east = true;
    else if (name == "vertical")
      c.vertical = true;
    else if (name == "heading")
      c.heading = true;
    else
      throw UsageError("--channels: unknown channel '" + name +
                       "' (north, east, vertical, heading)");
  }
  if (!c.north || !c.east) throw UsageError("--channels needs at least north,east");
  return c;
}

// Options of `calibrate`, shared by every session of a run.
struct CalibrateOptions {
  std::string method, stage1, model, channels, attitude, on_bad_sample, static_from;
  double table_sigma = 2.5, arw = 0.0, vrw = 0.0, min_dwell = 20.0, monitor_interval = 10.0;
  double static_window = 1.0, static_min = 3.0, static_rate = 3.0;
  bool no_table_angles = false, no_zero_velocity = false;
  int passes = 1;
  std::string terms;
  bool stream = false, no_position = false, no_motion_zero_velocity = false;
};

// The Kalman filter on one session. `verbose`: the tables and verdicts on standard output (a
// single session); `live`: the live table on the terminal.
SessionSummary calibrate_kf(const CalibrateOptions& o, const std::string& session_path,
                            const std::string& out_path, const std::string& monitor_path,
                            bool verbose, bool live) {
  const Session session = Session::load(session_path);
  if (session.sensor_file.empty())
    throw UsageError(session_path +
                     ": --method kf needs the session's sensor profile ([session] sensor =)");
  const SensorProfile profile = SensorProfile::load(session.sensor_file);
  CalibratorOptions ko = calibrator_options_from_profile(profile);
  ko.attitude_sigma = o.table_sigma * units::arcsec;
  // The table sets every orientation of either kind of plan to its stated accuracy.
  ko.attitude = CalibratorOptions::AttitudeUpdates::Every;
  if (o.attitude == "every")
    ko.attitude = CalibratorOptions::AttitudeUpdates::Every;
  else if (o.attitude == "first")
    ko.attitude = CalibratorOptions::AttitudeUpdates::First;
  else if (o.attitude == "none")
    ko.attitude = CalibratorOptions::AttitudeUpdates::None;
  ko.position = !o.no_position;
  ko.zero_velocity_in_motion = !o.no_motion_zero_velocity;
  ko.time_offset = session.time_offset;
  ko.use_table_angles = !o.no_table_angles;
  ko.zero_velocity = !o.no_zero_velocity;
  try {
    apply_terms(ko.layout, o.terms);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--terms: ") + e.what());
  }
  if (o.static_from == "data") {
    ko.static_from = CalibratorOptions::StaticFrom::Data;
    ko.detector.window = o.static_window;
    ko.detector.min_duration = o.static_min;
    ko.detector.rate_threshold = o.static_rate * units::deg_per_s;
  }
  KalmanRunOptions run;
  run.skip_bad_samples = o.on_bad_sample == "skip";
  run.passes = o.passes;
  run.stop = &g_stop;
  run.sigma_targets = profile.sigma_targets;
  std::ofstream monitor;
  if (!monitor_path.empty()) {
    monitor.open(monitor_path);
    if (!monitor) throw std::runtime_error(monitor_path + ": cannot create");
  }
  if (monitor || live) {
    run.monitor_interval = o.monitor_interval;
    run.monitor = [&](const nlohmann::ordered_json& rec) {
      if (monitor) monitor << rec.dump() << "\n" << std::flush;
      if (live) print_live_table(rec, profile.sigma_targets);
    };
  }
  std::unique_ptr<LogReader> stdin_reader;
  if (o.stream) {
    LogFormat f = session.log;
    f.file = "<stdin>";
    stdin_reader = std::make_unique<LogReader>(std::cin, f);
  }
  const auto t0 = std::chrono::steady_clock::now();
  const KalmanReport kr = run_kalman(session, ko, stdin_reader.get(), run);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_result_json(out_path, kr.coefficients, kr.details);
  const bool accel_frame = kr.details["method"]["body_frame"] == "accelerometer triad";

  SessionSummary row;
  row.session = session_path;
  row.name = session.name;
  row.result = out_path;
  row.samples = kr.samples;
  row.duration = kr.duration;
  row.nis_per_dof = kr.nis_per_dof;
  row.converged_at = kr.converged_at;
  row.coefficients = kr.coefficients;
  row.max_error_over_sigma =
      max_error_over_sigma(kr.coefficients, load_truth(session, accel_frame));
  row.status = "ok";
  if (kr.interrupted) {
    row.status = "interrupted";
    row.message = kr.stopped;
  } else if (!kr.stopped.empty()) {
    row.status = "stopped";
    row.message = "input stopped: " + kr.stopped;
  } else if (!kr.diverged.empty()) {
    row.status = "diverged";
    row.message = kr.diverged;
  }
  if (!verbose) return row;
  std::printf("Kalman-filter calibration of '%s': %d states, %zu samples, NIS per dof %.3f\n",
              session.name.c_str(), kr.states, kr.samples, kr.nis_per_dof);
  print_coefficient_table(kr.coefficients, session, accel_frame);
  std::printf("\nResult written to %s (%.2f s, %.0fx real time)\n", out_path.c_str(), seconds,
              kr.duration / seconds);
  print_kalman_verdicts(kr, profile);
  return row;
}

// The closed-form method on one session; `verbose` as calibrate_kf.
SessionSummary calibrate_closed_form(const CalibrateOptions& co, const std::string& session_path,
                                     const std::string& out_path, bool verbose) {
  Stage1Options o;
  o.method = co.stage1 == "point" ? Stage1Method::Point : Stage1Method::Fit;
  o.model = co.model == "uncoupled" ? ErrorModelKind::Uncoupled : ErrorModelKind::Coupled;
  o.channels = parse_channels(co.channels);
  o.min_dwell = co.min_dwell;
  const Session session = Session::load(session_path);
  if (!session.sensor_file.empty()) {
    const SensorProfile p = SensorProfile::load(session.sensor_file);
    o.arw = p.noise.gyro.white;
    o.vrw = p.noise.accel.white;
  }
  if (co.arw > 0.0) o.arw = co.arw * units::deg_per_sqrt_h;
  if (co.vrw > 0.0) o.vrw = co.vrw * units::ug_per_sqrt_hz;
  const auto t0 = std::chrono::steady_clock::now();
  const ClosedFormReport r = run_closed_form(session, o, co.table_sigma * units::arcsec);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  write_result_json(out_path, r.coefficients, r.details);

  SessionSummary row;
  row.session = session_path;
  row.name = session.name;
  row.result = out_path;
  row.status = "ok";
  row.coefficients = r.coefficients;
  row.max_error_over_sigma = max_error_over_sigma(r.coefficients, load_truth(session));
  for (const auto& e : r.stage1) row.duration += e.duration;
  if (!verbose) return row;

  std::printf(
      "Closed-form calibration of '%s': stage 1 %s, %s model, channels %s, table %.2f arcsec\n",
      session.name.c_str(), co.stage1.c_str(), co.model.c_str(), co.channels.c_str(),
      co.table_sigma);
  std::printf("\nStage 1: equivalent inputs per dwell (value +- sigma)\n");
  std::printf("%5s %-10s %6s %20s %20s %20s %20s %20s %20s %8s\n", "dwell", "label", "T [s]",
              "df_n [ug]", "df_e [ug]", "df_d [ug]", "dw_n [deg/h]", "dw_e [deg/h]", "dw_d [deg/h]",
              "chi2/dof");
  for (const auto& e : r.stage1) {
    std::printf("%5d %-10s %6.1f", e.dwell.index, e.dwell.label.c_str(), e.duration);
    for (int i = 0; i < 6; ++i) {
      const double f = i < 3 ? units::ug : units::deg_per_h;
      if (e.estimated[i])
        std::printf(" %10.4f +- %6.4f", e.u(i) / f, std::sqrt(e.cov(i, i)) / f);
      else
        std::printf(" %20s", "-");
    }
    std::printf(" %8.3f\n", e.chi2_per_dof);
  }
  std::printf("\nIdentifiability: rank %d of %d\n", r.stage2.rank, base_coeffs::kSize);
  for (const auto& u : r.stage2.unobservable_directions)
    std::printf("  unobservable direction: %s\n", u.c_str());
  print_coefficient_table(r.coefficients, session);
  // The limits of a static plan, shown rather than hidden.
  auto sigma_range = [&](const Block& block, double unit) {
    std::pair<double, double> range{1e300, 0.0};
    for (int k = block.index; k < block.index + block.size; ++k) {
      if (!r.stage2.observable[k]) continue;
      const double sigma = std::sqrt(r.stage2.cov(k, k)) / unit;
      range = {std::min(range.first, sigma), std::max(range.second, sigma)};
    }
    return range;
  };
  const auto [smin, smax] = sigma_range(base_coeffs::kGyroScale, units::ppm);
  const auto [mmin, mmax] = sigma_range(base_coeffs::kGyroMis, units::arcsec);
  std::printf(
      "\nLimit of static orientations: gyro scale factors and misalignments come from Earth "
      "rate alone:\n  sigma %.0f-%.0f ppm and %.0f-%.0f arcsec. Rotations are needed for them "
      "(Kalman filter, rot19).\n",
      smin, smax, mmin, mmax);
  if (r.has_paper_forms) {
    const PaperClosedForms& p = r.paper;
    std::printf(
        "\nThe paper's literal closed forms (X and Z sensors) beside the general solution:\n");
    const std::pair<const char*, double> rows[] = {{"gyro.bias.x", p.w0x},
                                                   {"gyro.scale.x", p.dkgx},
                                                   {"gyro.misalignment.xy", p.nu_xy},
                                                   {"gyro.misalignment.xz", p.nu_xz},
                                                   {"gyro.bias.z", p.w0z},
                                                   {"gyro.scale.z", p.dkgz},
                                                   {"gyro.misalignment.zx", p.nu_zx},
                                                   {"gyro.misalignment.zy", p.nu_zy},
                                                   {"accel.bias.x", p.f0x},
                                                   {"accel.misalignment.xy", p.mu_xy},
                                                   {"accel.misalignment.xz", p.mu_xz},
                                                   {"accel.bias.z", p.f0z},
                                                   {"accel.misalignment.zx", p.mu_zx},
                                                   {"accel.misalignment.zy", p.mu_zy}};
    for (const auto& [name, v] : rows) {
      const CoefficientInfo& info = coefficient_info(name);
      const auto& c = r.coefficients.at(name);
      std::printf("  %-24s paper %12.4f   general %12.4f %s\n", name, v / info.si_per_unit,
                  c.observable ? c.value : std::nan(""), info.unit.c_str());
    }
  }
  std::printf("\nResult written to %s (%.2f s)\n", out_path.c_str(), seconds);
  return row;
}

// Result file stems for a batch: the session directory's name, made unique with -2, -3, ...
std::vector<std::string> result_stems(const std::vector<std::string>& sessions) {
  std::vector<std::string> stems;
  std::map<std::string, int> seen;
  for (const auto& s : sessions) {
    const std::filesystem::path p(s);
    std::string stem = p.filename() == "session.ini" && p.has_parent_path()
                           ? p.parent_path().filename().string()
                           : p.stem().string();
    if (stem.empty() || stem == ".") stem = "session";
    const int n = ++seen[stem];
    stems.push_back(n == 1 ? stem : stem + "-" + std::to_string(n));
  }
  return stems;
}

// Every session of a batch, on `jobs` threads; one result (and for kf one monitor file) per
// session in `out_dir`, the summary table in out_dir/summary.csv. A session that fails does not
// stop the others.
int calibrate_batch(const CalibrateOptions& o, const std::vector<std::string>& sessions,
                    const std::string& out_dir, unsigned jobs) {
  std::filesystem::create_directories(out_dir);
  const auto stems = result_stems(sessions);
  std::vector<SessionSummary> rows(sessions.size());
  std::atomic<std::size_t> next{0};
  std::mutex print_mutex;
  const auto t0 = std::chrono::steady_clock::now();
  auto worker = [&] {
    for (std::size_t i; (i = next++) < sessions.size();) {
      const std::string result = out_dir + "/" + stems[i] + ".json";
      SessionSummary& row = rows[i];
      if (g_stop) {
        row.session = sessions[i];
        row.status = "interrupted";
        row.message = "not started: interrupted";
        continue;
      }
      try {
        row = o.method == "kf"
                  ? calibrate_kf(o, sessions[i], result,
                                 out_dir + "/" + stems[i] + ".monitor.jsonl", false, false)
                  : calibrate_closed_form(o, sessions[i], result, false);
      } catch (const std::exception& e) {
        row.session = sessions[i];
        row.status = "failed";
        row.message = e.what();
      }
      const std::lock_guard<std::mutex> lock(print_mutex);
      std::fprintf(stderr, "[%zu/%zu] %s: %s%s%s\n", i + 1, sessions.size(), sessions[i].c_str(),
                   row.status.c_str(), row.message.empty() ? "" : ": ", row.message.c_str());
    }
  };
  jobs = std::max(1u, std::min<unsigned>(jobs, static_cast<unsigned>(sessions.size())));
  std::vector<std::thread> threads;
  for (unsigned k = 1; k < jobs; ++k) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  const std::string summary = out_dir + "/summary.csv";
  write_summary_csv(summary, rows);
  std::printf("Batch calibration (%s) of %zu sessions on %u threads, %.2f s\n\n", o.method.c_str(),
              sessions.size(), jobs, seconds);
  std::printf("%-24s %-9s %9s %9s %10s %12s %12s  %s\n", "result", "status", "samples", "data [s]",
              "NIS/dof", "converged [s]", "max|err|/sig", "session");
  int bad = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const SessionSummary& r = rows[i];
    auto opt = [](const std::optional<double>& v, const char* f) {
      return v ? fmt(f, *v) : std::string("-");
    };
    std::printf("%-24s %-9s %9zu %9.1f %10s %12s %12s  %s\n", (stems[i] + ".json").c_str(),
                r.status.c_str(), r.samples, r.duration, opt(r.nis_per_dof, "%.3f").c_str(),
                opt(r.converged_at, "%.1f").c_str(), opt(r.max_error_over_sigma, "%.2f").c_str(),
                r.session.c_str());
    if (r.status != "ok") ++bad;
  }
  std::printf("\nSummary table written to %s\n", summary.c_str());
  if (bad > 0) {
    std::fprintf(stderr, "sinscal calibrate: error: %d of %zu sessions not ok (see %s)\n", bad,
                 sessions.size(), summary.c_str());
    return g_stop ? kInterrupted : kDataError;
  }
  return 0;
}

int cmd_calibrate(const std::vector<std::string>& args) {
  po::options_description d("sinscal calibrate options");
  CalibrateOptions o;
  std::vector<std::string> session_paths;
  std::string session_list, out_path, monitor_path;
  unsigned jobs = 0;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("session", po::value(&session_paths)->composing(),
       "session.ini of the recording; or a directory: its session.ini, else every subdirectory "
       "holding one (batch). Repeatable (batch)")
      ("session-list", po::value(&session_list),
       "batch: a file naming one session (session.ini or directory) per line")
      ("method", po::value(&o.method)->default_value("closed-form"),
       "closed-form | kf (error-state Kalman filter)")
      ("out", po::value(&out_path)->required(),
       "result JSON to write; in a batch, the directory of the results and summary.csv")
      ("jobs", po::value(&jobs)->default_value(0),
       "batch: sessions calibrated at once (0: one per processor core)")
      ("stage1", po::value(&o.stage1)->default_value("fit"),
       "closed-form: fit (weighted least squares over each dwell) | point (the paper's eq. 5)")
      ("model", po::value(&o.model)->default_value("coupled"),
       "closed-form: coupled | uncoupled (the paper's Schuler channels)")
      ("channels", po::value(&o.channels)->default_value("north,east,vertical,heading"),
       "closed-form: stage-1 channels, comma separated (the paper: north,east)")
      ("table-sigma", po::value(&o.table_sigma)->default_value(2.5),
       "table attitude error per orientation, 1-sigma [arcsec]")
      ("arw", po::value(&o.arw), "gyro angle random walk [deg/sqrt(h)] (default: the session's sensor)")
      ("vrw", po::value(&o.vrw), "accelerometer velocity random walk [ug/sqrt(Hz)] (default: sensor)")
      ("min-dwell", po::value(&o.min_dwell)->default_value(20.0), "closed-form: shortest dwell [s]")
      ("stream", "kf: read the samples from standard input (the session's log format)")
      ("monitor", po::value(&monitor_path),
       "kf: write a JSON line of estimates and sigmas here (a batch writes RESULT.monitor.jsonl "
       "beside each result)")
      ("monitor-interval", po::value(&o.monitor_interval)->default_value(10.0),
       "kf: seconds of data between monitor lines (and live-table refreshes on a terminal)")
      ("attitude", po::value(&o.attitude),
       "kf: table-attitude updates: every (dwell) | first (dwell) | none (zero velocity only; "
       "body frame = accelerometer triad). Default: every")
      ("no-position", "kf: no known-position updates")
      ("no-zero-velocity", "kf: no zero-velocity updates at rest")
      ("terms", po::value(&o.terms),
       ("kf: extended blocks on or off beyond the sensor profile's, e.g. k2,-lever_arm: " +
        extended_terms_help() + "; vertical_velocity; or a family's name").c_str())
      ("no-motion-zero-velocity", "kf: no zero-velocity updates while the table turns")
      ("no-table-angles", "kf: ignore the log's table-angle columns (attitude from the plan)")
      ("passes", po::value(&o.passes)->default_value(1),
       "kf: passes over the log, each from the previous pass's coefficients (large errors: MEMS)")
      ("static-from", po::value(&o.static_from)->default_value("plan"),
       "kf: where the static dwells are: plan (its timing, shifted by the session's time_offset) "
       "| data (detected; the k-th static interval is the plan's k-th dwell)")
      ("static-window", po::value(&o.static_window)->default_value(1.0),
       "kf, --static-from data: trailing window of the detector [s]")
      ("static-min", po::value(&o.static_min)->default_value(3.0),
       "kf, --static-from data: shortest static interval taken for a dwell [s]")
      ("static-rate-threshold", po::value(&o.static_rate)->default_value(3.0),
       "kf, --static-from data: a mean rate above this is motion [deg/s]")
      ("on-bad-sample", po::value(&o.on_bad_sample)->default_value("stop"),
       "kf: stop | skip (NaN, saturated, time going backwards; each reported)");
  // clang-format on
  const auto vm = parse(
      args, d,
      "Usage: sinscal calibrate --session DIR/session.ini --method closed-form|kf --out "
      "result.json\n"
      "       sinscal calibrate --session DIR_OF_SESSIONS | --session-list FILE [--session ...] "
      "--out OUT_DIR\n"
      "Estimates the calibration coefficients with their sigma. closed-form: the 24 base\n"
      "coefficients from the static dwells; the paper's method exactly:\n"
      "  --stage1 point --model uncoupled --channels north,east\n"
      "kf: the error-state Kalman filter, with the extended terms the sensor profile declares;\n"
      "--stream reads the samples from standard input as they arrive.\n"
      "Batch (several sessions): OUT_DIR/NAME.json per session and OUT_DIR/summary.csv.");
  o.stream = vm.count("stream") > 0;
  o.no_position = vm.count("no-position") > 0;
  o.no_motion_zero_velocity = vm.count("no-motion-zero-velocity") > 0;
  o.no_table_angles = vm.count("no-table-angles") > 0;
  o.no_zero_velocity = vm.count("no-zero-velocity") > 0;
  if (!o.terms.empty()) {  // checked before any session runs
    StateLayoutOptions check;
    try {
      apply_terms(check, o.terms);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--terms: ") + e.what());
    }
  }
  if (o.method != "kf" && o.method != "closed-form")
    throw UsageError("--method must be closed-form or kf");
  if (o.stage1 != "fit" && o.stage1 != "point") throw UsageError("--stage1 must be fit or point");
  if (o.model != "coupled" && o.model != "uncoupled")
    throw UsageError("--model must be coupled or uncoupled");
  parse_channels(o.channels);  // checked before any session runs
  if (!o.attitude.empty() && o.attitude != "every" && o.attitude != "first" && o.attitude != "none")
    throw UsageError("--attitude must be every, first or none");
  if (o.on_bad_sample != "stop" && o.on_bad_sample != "skip")
    throw UsageError("--on-bad-sample must be stop or skip");
  if (o.static_from != "plan" && o.static_from != "data")
    throw UsageError("--static-from must be plan or data");
  if (!(o.static_window > 0.0) || !(o.static_min >= o.static_window) || !(o.static_rate > 0.0))
    throw UsageError(
        "--static-window must be positive, --static-min at least the window, "
        "--static-rate-threshold positive");
  if (o.stream && o.method != "kf") throw UsageError("--stream needs --method kf");
  if (o.passes < 1 || o.passes > 20) throw UsageError("--passes must be 1 to 20");
  if (o.passes > 1 && o.stream) throw UsageError("--passes reads the log again: not with --stream");
  if (o.method == "kf") install_stop_handlers();  // Ctrl-C: stop, finish, write

  // One session.ini given as a file: a single run. Anything naming a folder of sessions, a
  // list, or several sessions: a batch.
  if (session_paths.empty() && session_list.empty())
    throw UsageError("give --session (or --session-list)");
  std::vector<std::string> sessions;
  bool batch = !session_list.empty() || session_paths.size() > 1;
  for (const auto& p : session_paths) {
    const auto found = find_sessions(p);
    batch |=
        found.size() > 1 || (std::filesystem::is_directory(p) &&
                             !std::filesystem::exists(std::filesystem::path(p) / "session.ini"));
    sessions.insert(sessions.end(), found.begin(), found.end());
  }
  if (!session_list.empty()) {
    const auto listed = read_session_list(session_list);
    sessions.insert(sessions.end(), listed.begin(), listed.end());
  }
  if (batch) {
    if (o.stream) throw UsageError("--stream reads one session from standard input, not a batch");
    if (!monitor_path.empty())
      throw UsageError("--monitor names one file; a batch writes OUT_DIR/NAME.monitor.jsonl");
    return calibrate_batch(o, sessions, out_path,
                           jobs > 0 ? jobs : std::max(1u, std::thread::hardware_concurrency()));
  }
  const SessionSummary row = o.method == "kf"
                                 ? calibrate_kf(o, sessions.front(), out_path, monitor_path, true,
                                                isatty(fileno(stderr)) != 0)
                                 : calibrate_closed_form(o, sessions.front(), out_path, true);
  if (row.status == "interrupted") {
    std::fprintf(stderr, "sinscal calibrate: %s (the estimates up to there are written)\n",
                 row.message.c_str());
    return kInterrupted;
  }
  if (row.status != "ok") {
    std::fprintf(stderr, "sinscal calibrate: error: %s (the estimates up to there are written)\n",
                 row.message.c_str());
    return kDataError;
  }
  return 0;
}

int cmd_compare(const std::vector<std::string>& args) {
  po::options_description d("sinscal compare options");
  std::vector<std::string> files;
  double max_sigma = 0.0, max_relative = 0.0;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("result", po::value(&files)->composing(), "the two result JSON files (also positional)")
      ("max-sigma", po::value(&max_sigma),
       "fail (exit 3) if a difference exceeds this many sigma of the difference")
      ("max-relative", po::value(&max_relative),
       "fail (exit 3) if a value or sigma differs by more than this fraction");
  // clang-format on
  po::positional_options_description pos;
  pos.add("result", 2);
  po::variables_map vm;
  po::store(po::command_line_parser(args).options(d).positional(pos).run(), vm);
  if (vm.count("help")) {
    std::cout << "Usage: sinscal compare A.json B.json [--max-sigma K] [--max-relative R]\n"
                 "Two calibration results side by side: difference, difference over its sigma\n"
                 "(sigma from both results, taken as independent) and relative difference.\n"
              << d << "\n";
    return 0;
  }
  po::notify(vm);
  if (files.size() != 2) throw UsageError("give two result files");
  const ResultCoefficients a = read_result_json(files[0]);
  const ResultCoefficients b = read_result_json(files[1]);
  const bool check_sigma = vm.count("max-sigma") > 0, check_relative = vm.count("max-relative") > 0;
  std::printf("A = %s\nB = %s\n\n%-28s %14s %14s %12s %8s %10s %-8s\n", files[0].c_str(),
              files[1].c_str(), "coefficient", "A", "B", "A - B", "z", "relative", "unit");
  int failures = 0;
  for (const auto& c : compare_results(a, b)) {
    auto num = [](const std::optional<double>& v, const char* f) {
      return v ? fmt(f, *v) : std::string("-");
    };
    std::string verdict;
    if (!c.a || !c.b) {
      verdict = !c.a && !c.b ? "in neither as a value" : !c.a ? "no value in A" : "no value in B";
      if (check_sigma || check_relative) {
        // Both unobservable (sigma only) is agreement; a value on one side only is not.
        const bool same_kind = !c.a && !c.b;
        if (!same_kind) ++failures;
      }
    } else {
      if (check_sigma && c.z && std::abs(*c.z) > max_sigma) {
        verdict += " |z| > " + fmt("%g", max_sigma);
        ++failures;
      }
      if (check_relative &&
          (*c.relative > max_relative || (c.sigma_relative && *c.sigma_relative > max_relative))) {
        verdict += " relative > " + fmt("%g", max_relative);
        ++failures;
      }
    }
    std::printf("%-28s %14s %14s %12s %8s %10s %-8s%s\n", c.name.c_str(), num(c.a, "%.6g").c_str(),
                num(c.b, "%.6g").c_str(), c.a && c.b ? fmt("%.4g", *c.a - *c.b).c_str() : "-",
                num(c.z, "%.2f").c_str(), num(c.relative, "%.2e").c_str(), c.unit.c_str(),
                verdict.c_str());
  }
  if (failures > 0) {
    std::fprintf(stderr, "sinscal compare: %d coefficients disagree\n", failures);
    return kDisagree;
  }
  return 0;
}

int cmd_plot_convergence(const std::vector<std::string>& args) {
  po::options_description d("sinscal plot-convergence options");
  std::string monitor_path, out_path, session_path, sensor_path;
  std::vector<std::string> families;
  ConvergencePlotOptions o;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("monitor", po::value(&monitor_path)->required(),
       "monitor JSON lines (calibrate --method kf --monitor)")
      ("out", po::value(&out_path)->required(), "PNG to write (the gnuplot script goes beside it, .gp)")
      ("family", po::value(&families)->composing(),
       "coefficient family to draw, e.g. gyro.scale (repeatable; default: all)")
      ("session", po::value(&session_path),
       "session.ini: draw its truth (simulations) and its sensor profile's sigma targets")
      ("sensor", po::value(&sensor_path), "sensor profile whose [targets] are drawn")
      ("width", po::value(&o.width_px)->default_value(1400), "picture width [px]")
      ("row-height", po::value(&o.row_height_px)->default_value(260),
       "height of each family's row [px]");
  // clang-format on
  parse(args, d,
        "Usage: sinscal plot-convergence --monitor M.jsonl --out conv.png [--session S]\n"
        "Draws, per coefficient family, the estimates and their sigma (log scale, with the\n"
        "target) over time, and the NIS per dof and the converged verdict, with gnuplot.");
  if (o.width_px < 200 || o.row_height_px < 80)
    throw UsageError("--width must be at least 200 and --row-height at least 80 px");
  const MonitorSeries series = read_monitor(monitor_path);
  o.families = families;
  if (!session_path.empty()) {
    const Session session = Session::load(session_path);
    o.truth = load_truth(session, series.body_frame == "accelerometer triad");
    if (sensor_path.empty() && !session.sensor_file.empty()) sensor_path = session.sensor_file;
  }
  if (!sensor_path.empty()) o.sigma_targets = SensorProfile::load(sensor_path).sigma_targets;
  const ConvergencePlot plot = plot_convergence(series, o, out_path);
  std::printf(
      "Convergence of %zu records (t = %.1f to %.1f s), %zu families, drawn to %s (%d x %d "
      "px)\ngnuplot script: %s\n",
      series.t.size(), series.t.front(), series.t.back(), plot.families.size(), plot.png.c_str(),
      plot.width_px, plot.height_px, plot.script.c_str());
  return 0;
}

const char* kUsage =
    "sinscal: calibration of strapdown inertial navigation systems\n"
    "Usage: sinscal COMMAND [options]   (sinscal COMMAND --help for the options)\n"
    "Commands:\n"
    "  simulate   simulate a calibration session on a two-axis table\n"
    "  navigate   navigate through the static dwells of a session, report navigation errors\n"
    "  calibrate  estimate the calibration coefficients of a session or a batch of sessions\n"
    "             (closed-form method or Kalman filter)\n"
    "  compare    two results side by side, difference over its sigma\n"
    "  plot-convergence\n"
    "             estimates and sigmas over time from a Kalman monitor file, to PNG (gnuplot)\n";

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    std::cout << kUsage;
    return argc < 2 ? kUsageError : 0;
  }
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  try {
    if (command == "simulate") return cmd_simulate(args);
    if (command == "navigate") return cmd_navigate(args);
    if (command == "calibrate") return cmd_calibrate(args);
    if (command == "compare") return cmd_compare(args);
    if (command == "plot-convergence") return cmd_plot_convergence(args);
    std::cerr << "sinscal: unknown command '" << command << "'\n" << kUsage;
    return kUsageError;
  } catch (int code) {
    return code;  // --help
  } catch (const po::error& e) {
    std::cerr << "sinscal " << command << ": " << e.what() << " (see sinscal " << command
              << " --help)\n";
    return kUsageError;
  } catch (const UsageError& e) {
    std::cerr << "sinscal " << command << ": " << e.what() << "\n";
    return kUsageError;
  } catch (const std::exception& e) {
    std::cerr << "sinscal " << command << ": error: " << e.what() << "\n";
    return kDataError;
  }
}
