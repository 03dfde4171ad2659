// sinscal simulate: a calibration session on a two-axis table, written to a directory.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "models/units.hpp"
#include "report/output.hpp"
#include "rig/session.hpp"
#include "rig/table_spec.hpp"

namespace sinscal::cli {

namespace {
constexpr double kMaxRateHz = 100000.0;       // a log beyond this is not an IMU's
constexpr double kMaxInstallationDeg = 10.0;  // base level and mounting errors simulated, deg
// The marker of a session directory simulate wrote: the files it wrote, one per line.
constexpr const char* kSimulationMarker = ".sinscal-simulation";

// --out: a new or empty directory, or an earlier simulation (replaced whole); anything else is
// refused unless --force (which writes into it, keeping its other files). Returns whether to
// merge into it.
bool check_out_dir(const std::string& out_dir, bool force) {
  std::vector<std::string> foreign;
  const DirectoryState state = directory_state(out_dir, kSimulationMarker, foreign);
  if (state != DirectoryState::Foreign) return false;
  if (force) return true;
  std::string names;
  for (std::size_t i = 0; i < foreign.size() && i < 3; ++i)
    names += (i > 0 ? ", " : "") + foreign[i];
  if (foreign.size() > 3) names += " and " + std::to_string(foreign.size() - 3) + " more";
  throw UsageError("--out " + out_dir +
                   ": not empty and not an earlier simulate output (it holds " + names +
                   "): simulate writes a new or empty directory, or replaces an earlier "
                   "simulation whole (its results would not match the new data); --force writes "
                   "into it anyway, keeping its other files");
}

// The comma-separated numbers of `text`; empty when an item is not a whole finite number.
std::vector<double> comma_numbers(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(v)) return {};
    out.push_back(v);
  }
  return out;
}

// "a[,b]": one or two numbers (the second optional); a usage error naming the option otherwise.
std::pair<double, std::optional<double>> one_or_two(const std::string& option,
                                                    const std::string& text) {
  const std::vector<double> out = comma_numbers(text);
  if (out.empty() || out.size() > 2)
    throw UsageError("--" + option + " takes one or two comma-separated numbers, not '" + text +
                     "'");
  return {out[0], out.size() > 1 ? std::optional<double>(out[1]) : std::nullopt};
}

// The table's dynamics: the --table file's, then each --table-* option over it.
TableDynamics table_dynamics(const po::variables_map& vm, const std::string& table_path) {
  TableDynamics d;
  if (!table_path.empty()) d = TableSpec::load(table_path).dynamics;
  auto get = [&](const char* name) -> std::optional<std::string> {
    if (!vm.count(name)) return std::nullopt;
    return vm[name].as<std::string>();
  };
  if (auto v = get("table-smoothing")) d.smoothing = one_or_two("table-smoothing", *v).first;
  if (auto v = get("table-jerk-time")) d.jerk_time = one_or_two("table-jerk-time", *v).first;
  if (auto v = get("table-servo")) {
    const auto [f, z] = one_or_two("table-servo", *v);
    d.servo_frequency = f;
    if (z) d.servo_damping = *z;
  }
  if (auto v = get("table-ripple")) {
    const auto [f, z] = one_or_two("table-ripple", *v);
    d.ripple_frequency = f;
    if (z) d.ripple_damping = *z;
  }
  if (auto v = get("table-rate-ripple")) {
    const auto [a, period] = one_or_two("table-rate-ripple", *v);
    d.rate_ripple = a * units::arcsec;
    d.rate_ripple_period = period.value_or(1.0) * units::deg;
  }
  if (auto v = get("start-offset")) d.start_offset = one_or_two("start-offset", *v).first;
  try {
    d.validate();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  return d;
}

// "a,b[,c]" (deg) as `count` angles in rad; a usage error naming the option otherwise.
std::vector<double> angles_deg(const std::string& option, const std::string& text, int count) {
  std::vector<double> out = comma_numbers(text);
  const bool in_range = !out.empty() && std::all_of(out.begin(), out.end(), [](double v) {
    return std::abs(v) <= kMaxInstallationDeg;
  });
  if (!in_range)
    throw UsageError("--" + option + " takes " + std::to_string(count) +
                     " comma-separated angles in deg, each within +-" +
                     fmt("%g", kMaxInstallationDeg) + ", not '" + text + "'");
  for (double& v : out) v *= units::deg;
  if (static_cast<int>(out.size()) != count)
    throw UsageError("--" + option + " takes " + std::to_string(count) +
                     " comma-separated angles in deg, not '" + text + "'");
  return out;
}

void print_simulation(const SimulatedSession& sim, const SessionSimulation& spec,
                      const std::string& session_file, double seconds) {
  const bool noise = spec.noise && !spec.perfect;
  std::cout << "Simulated plan '" << sim.plan.name << "' (" << sim.plan.path << "), sensor '"
            << sim.profile.name << "'\n  " << sim.samples << " samples at " << spec.rate_hz
            << " Hz, " << fmt("%.1f", sim.duration) << " s, " << sim.dwells << " dwells, "
            << (noise ? "noise on" : "noise off") << ", "
            << fmt("%.0f", static_cast<double>(sim.samples) / seconds) << " samples/s written\n";
  if (spec.table.has_installation_errors()) {
    const Eigen::Vector3d m = spec.table.mounting_b / units::deg;
    std::printf(
        "  table base: level %.4f deg (North) %.4f deg (East), heading %.4f deg; IMU mounting "
        "%.4f %.4f %.4f deg (rotation vector, body axes)\n",
        spec.table.base_level_north / units::deg, spec.table.base_level_east / units::deg,
        spec.table.base_heading / units::deg, m.x(), m.y(), m.z());
  }
  if (sim.saturated > 0)
    std::cout << "  WARNING: " << sim.saturated << " samples clipped at the sensor range\n";
  std::cout << "  session: " << session_file << "\n  injected coefficients (truth.json):\n";
  const auto truth = sim.truth.coefficients();
  for (const auto& info : coefficient_catalog()) {
    const double v = truth.at(info.name);
    if (v != 0.0) std::printf("    %-28s %12.4f %s\n", info.name.c_str(), v, info.unit.c_str());
  }
}
}  // namespace

int cmd_simulate(const std::vector<std::string>& args) {
  po::options_description d("sinscal simulate options");
  SessionSimulation spec;
  std::string out_dir;
  double angle_sigma_arcsec = 0.0, non_orth_arcsec = 0.0, base_heading_deg = 0.0;
  double attitude_sigma_arcsec = 0.0;
  std::string base_level = "0,0", mounting = "0,0,0", chamber_path, table_path;
  unsigned long long seed = 1;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("plan", po::value(&spec.plan_path)->required(), "plan INI file (config/plans/*.ini)")
      ("sensor", po::value(&spec.data_sensor_path)->required(),
       "sensor profile INI (config/sensors/*.ini)")
      ("out", po::value(&out_dir)->required(), "output session directory")
      ("chamber", po::value(&chamber_path),
       "in a thermal chamber (config/chambers/*.ini): soaks, one session per soak in DIR/soak-K "
       "listed by DIR/chamber.ini; or a ramp, one session with the plan repeated")
      ("rate", po::value(&spec.rate_hz)->default_value(100.0), "IMU output rate [Hz]")
      ("seed", po::value(&seed)->default_value(1), "seed of all random draws")
      ("no-noise", "no sensor noise (coefficients still drawn)")
      ("table-angles", "log the table's outer and inner axis angles (plans of table moves)")
      ("perfect", "no sensor errors at all (zero coefficients, no noise)")
      ("force", "write into a non-empty --out directory that is not an earlier simulation "
       "(its other files kept)")
      ("table-angle-sigma", po::value(&angle_sigma_arcsec)->default_value(0.0),
       "table angle error per commanded angle, 1-sigma [arcsec]")
      ("table-attitude-sigma", po::value(&attitude_sigma_arcsec)->default_value(0.0),
       "the table's attitude error at each dwell, 1-sigma about each axis [arcsec] (what the "
       "Kalman filter's --table-sigma models)")
      ("table-non-orthogonality", po::value(&non_orth_arcsec)->default_value(0.0),
       "lean of the inner axis [arcsec]")
      ("base-level-error", po::value(&base_level),
       "level error of the table's base: N,E [deg], rotations about North and East")
      ("base-heading-error", po::value(&base_heading_deg)->default_value(0.0),
       "heading error of the table's base, about Down [deg]")
      ("mounting-error", po::value(&mounting),
       "the IMU's mounting on the platform: x,y,z [deg], rotation vector in body axes")
      ("table", po::value(&table_path),
       "table file (config/tables/*.ini): its rate and acceleration limits and dynamics realize "
       "the plan's turns")
      ("table-smoothing", po::value<std::string>(),
       "turns smoothed by a zero-phase Gaussian of this sigma [s] (another tool's profile)")
      ("table-jerk-time", po::value<std::string>(),
       "jerk limit: the acceleration ramps over this time [s]")
      ("table-servo", po::value<std::string>(),
       "servo lag and overshoot: natural frequency [Hz][,damping (0.7)]")
      ("table-ripple", po::value<std::string>(),
       "settling ripple: a structural mode's frequency [Hz][,damping (0.05)]")
      ("table-rate-ripple", po::value<std::string>(),
       "rate ripple: cogging amplitude [arcsec][,period in turned angle [deg] (1)]")
      ("start-offset", po::value<std::string>(),
       "the plan starts this late in the log [s] (session.ini does not know it)");
  // clang-format on
  const auto vm =
      parse(args, d,
            "Usage: sinscal simulate --plan P --sensor S --out DIR [--rate HZ] "
            "[--seed N] [--no-noise]\n       [--base-level-error N,E] [--base-heading-error DEG] "
            "[--mounting-error X,Y,Z]\nSimulates a calibration session: DIR/imu.csv, "
            "session.ini, plan.ini, sensor.ini, truth.json.");
  if (!vm) return 0;
  if (!(spec.rate_hz > 0.0 && spec.rate_hz <= kMaxRateHz))
    throw UsageError("--rate must be above 0 and at most " + fmt("%g", kMaxRateHz) + " Hz");
  if (!(std::abs(angle_sigma_arcsec) < 3600.0 && angle_sigma_arcsec >= 0.0 &&
        std::abs(non_orth_arcsec) < 3600.0))
    throw UsageError(
        "--table-angle-sigma must be 0 to 3600 arcsec and "
        "--table-non-orthogonality within +-3600 arcsec");
  spec.seed = seed;
  spec.perfect = vm->count("perfect") > 0;
  spec.noise = !vm->count("no-noise");
  spec.table_angles = vm->count("table-angles") > 0;
  if (!(attitude_sigma_arcsec >= 0.0 && attitude_sigma_arcsec < 3600.0))
    throw UsageError("--table-attitude-sigma must be 0 to 3600 arcsec");
  spec.table.angle_sigma = angle_sigma_arcsec * units::arcsec;
  spec.table.attitude_sigma = attitude_sigma_arcsec * units::arcsec;
  spec.table.non_orthogonality = non_orth_arcsec * units::arcsec;
  spec.table.seed = derive_seed(seed, 3);
  const std::vector<double> level = angles_deg("base-level-error", base_level, 2);
  const std::vector<double> mount = angles_deg("mounting-error", mounting, 3);
  if (!(std::abs(base_heading_deg) <= 180.0))
    throw UsageError("--base-heading-error must be within +-180 deg");
  spec.table.base_level_north = level[0];
  spec.table.base_level_east = level[1];
  spec.table.base_heading = base_heading_deg * units::deg;
  spec.table.mounting_b = Eigen::Vector3d(mount[0], mount[1], mount[2]);
  try {
    spec.table.dynamics = table_dynamics(*vm, table_path);
  } catch (const ConfigError& e) {
    throw UsageError(e.what());
  }
  std::vector<std::pair<std::string, std::string>> outputs;
  for (const char* f : {"imu.csv", "session.ini", "plan.ini", "sensor.ini", "truth.json"})
    outputs.emplace_back("output", out_dir + "/" + f);
  refuse_overwrite({{"plan", spec.plan_path},
                    {"sensor profile", spec.data_sensor_path},
                    {"chamber", chamber_path}},
                   outputs);
  std::optional<ChamberProgram> chamber;
  if (!chamber_path.empty()) chamber = ChamberProgram::load(chamber_path);
  const bool merge = check_out_dir(out_dir, vm->count("force") > 0);
  const auto t0 = std::chrono::steady_clock::now();
  SimulatedSession sim;
  write_directory_whole(
      out_dir, kSimulationMarker,
      [&](const std::string& dir) {
        if (!chamber) {
          sim = simulate_session(dir, spec);
          return;
        }
        const ChamberSimulation c = simulate_chamber(dir, spec, *chamber);
        sim = c.sessions.back();
        if (c.sessions.size() > 1)
          std::cout << c.sessions.size() << " soaks: " << out_dir
                    << "/chamber.ini lists their sessions (sinscal thermal --chamber)\n";
      },
      merge);
  const bool soaks = chamber && chamber->type == ChamberProgram::Type::Soaks;
  print_simulation(
      sim, spec,
      out_dir + (soaks ? "/soak-" + std::to_string(chamber->soaks_c.size()) : "") + "/session.ini",
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  return 0;
}

}  // namespace sinscal::cli
