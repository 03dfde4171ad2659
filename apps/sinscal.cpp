// sinscal command-line tool: parses options, calls the library, prints. No algorithms here.
#include <boost/program_options.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include "filter/dwell_navigation.hpp"
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
  const Plan plan = Plan::load(plan_path);
  if (!plan.has_site) throw ConfigError(plan_path + ": the plan has no [site] for the simulation");
  const SensorProfile profile = SensorProfile::load(sensor_path);
  const bool perfect = vm.count("perfect") > 0;
  const ImuErrorModel truth = perfect ? ImuErrorModel{} : profile.draw(derive_seed(seed, 1));
  TableErrors table_errors;
  table_errors.angle_sigma = angle_sigma_arcsec * units::arcsec;
  table_errors.non_orthogonality = non_orth_arcsec * units::arcsec;
  table_errors.seed = derive_seed(seed, 3);
  const Motion motion = build_motion(plan, plan.site, table_errors);
  SimulatorOptions so;
  so.rate_hz = rate;
  so.noise = !perfect && !vm.count("no-noise");
  so.noise_seed = derive_seed(seed, 2);
  so.gyro_range = profile.gyro_range;
  so.accel_range = profile.accel_range;
  ImuSimulator sim(motion, truth, profile.noise, so);

  std::filesystem::create_directories(out_dir);
  const auto t0 = std::chrono::steady_clock::now();
  LogWriter log(out_dir + "/imu.csv", rate);
  ImuSample s;
  while (sim.next(s)) log.write(s);
  log.close();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  {
    std::ofstream p(out_dir + "/plan.ini");
    p << plan.text;
    std::ifstream in(sensor_path);
    std::ofstream o(out_dir + "/sensor.ini");
    o << in.rdbuf();
  }
  std::ofstream ses(out_dir + "/session.ini");
  ses << "# Written by sinscal simulate\n[session]\nname = " << plan.name << "\nrate = " << rate
      << " Hz\nplan = plan.ini\nsensor = sensor.ini\ntruth = truth.json\n\n[site]\nlatitude = "
      << fmt("%.12g", plan.site.lat_rad / units::deg)
      << " deg\nlongitude = " << fmt("%.12g", plan.site.lon_rad / units::deg)
      << " deg\nheight = " << plan.site.h_m << " m\n\n[log]\nfile = imu.csv\nformat = sinscal\n";
  ses.close();
  if (!ses) throw std::runtime_error(out_dir + "/session.ini: cannot write");
  write_truth_json(out_dir + "/truth.json", truth,
                   "simulate --plan " + plan_path + " --sensor " + sensor_path + " --seed " +
                       std::to_string(seed) + (so.noise ? "" : " (no noise)"));

  std::cout << "Simulated plan '" << plan.name << "' (" << plan.path << "), sensor '"
            << profile.name << "'\n  " << sim.total_samples() << " samples at " << rate << " Hz, "
            << fmt("%.1f", motion.duration()) << " s, " << motion.dwells().size() << " dwells, "
            << (so.noise ? "noise on" : "noise off") << ", "
            << fmt("%.0f", static_cast<double>(sim.total_samples()) / seconds)
            << " samples/s written\n";
  if (sim.saturated())
    std::cout << "  WARNING: " << sim.saturated() << " samples clipped at the sensor range\n";
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
  const Motion motion = build_motion(session.plan, session.site);
  DwellNavOptions opt;
  opt.output_interval = interval;
  opt.time_offset = session.time_offset;
  opt.strapdown.vertical_held = vertical == "held";
  DwellNavigation run(motion.dwells(), session.site, opt);
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

const char* kUsage =
    "sinscal: calibration of strapdown inertial navigation systems\n"
    "Usage: sinscal COMMAND [options]   (sinscal COMMAND --help for the options)\n"
    "Commands:\n"
    "  simulate   simulate a calibration session on a two-axis table\n"
    "  navigate   navigate through the static dwells of a session, report navigation errors\n";

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
