#include "rig/session.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "models/config.hpp"
#include "models/units.hpp"
#include "rig/imu_sim.hpp"

namespace sinscal {

namespace {
std::string directory_of(const std::string& path) {
  const auto slash = path.rfind('/');
  return slash == std::string::npos ? "." : path.substr(0, slash);
}
std::string resolve(const std::string& dir, const std::string& file) {
  return file.empty() || file.front() == '/' ? file : dir + "/" + file;
}
}  // namespace

Session Session::load(const std::string& path) {
  const IniFile ini(path);
  Session s;
  s.path = path;
  s.dir = directory_of(path);
  s.name = ini.get_string("session.name", "session");
  s.rate_hz = ini.get_quantity("session.rate", QuantityKind::Frequency, "Hz");
  if (!(s.rate_hz > 0.0)) throw ConfigError(ini.where("session.rate") + "must be positive");
  s.time_offset = ini.get_quantity("session.time_offset", QuantityKind::Time, "s", 0.0);
  s.plan = Plan::load(resolve(s.dir, ini.get_string("session.plan")));
  s.truth_file = resolve(s.dir, ini.get_string("session.truth", ""));
  s.sensor_file = resolve(s.dir, ini.get_string("session.sensor", ""));
  ini.check_keys("session", {"name", "rate", "time_offset", "plan", "truth", "sensor"});
  if (ini.has("site.latitude")) {
    s.site.lat_rad = ini.get_quantity("site.latitude", QuantityKind::Angle, "deg");
    s.site.lon_rad = ini.get_quantity("site.longitude", QuantityKind::Angle, "deg", 0.0);
    s.site.h_m = ini.get_quantity("site.height", QuantityKind::Length, "m", 0.0);
  } else if (s.plan.has_site) {
    s.site = s.plan.site;
  } else {
    throw ConfigError(path + ": no [site] latitude in the session or its plan");
  }
  ini.check_keys("site", {"latitude", "longitude", "height"});
  s.log = LogFormat::from_ini(ini, s.dir, s.rate_hz);
  return s;
}

SimulatedSession simulate_session(const std::string& out_dir, const SessionSimulation& spec) {
  if (!(spec.rate_hz > 0.0)) throw std::invalid_argument("simulate_session: rate must be positive");
  SimulatedSession r;
  r.plan = Plan::load(spec.plan_path);
  if (!r.plan.has_site)
    throw ConfigError(spec.plan_path + ": the plan has no [site] for the simulation");
  r.profile = SensorProfile::load(spec.data_sensor_path);
  r.truth = spec.perfect ? ImuErrorModel{} : r.profile.draw(derive_seed(spec.seed, 1));
  const Motion motion = build_motion(r.plan, r.plan.site, spec.table);
  r.duration = motion.duration();
  r.dwells = motion.dwells().size();
  SimulatorOptions so;
  so.rate_hz = spec.rate_hz;
  so.noise = spec.noise && !spec.perfect;
  so.noise_seed = derive_seed(spec.seed, 2);
  so.gyro_range = r.profile.gyro_range;
  so.accel_range = r.profile.accel_range;
  so.table_angles = spec.table_angles;
  ImuSimulator sim(motion, r.truth, r.profile.noise, so);

  std::filesystem::create_directories(out_dir);
  LogWriter log(out_dir + "/imu.csv", spec.rate_hz, spec.table_angles);
  ImuSample sample;
  while (sim.next(sample)) log.write(sample);
  log.close();
  r.samples = sim.total_samples();
  r.saturated = sim.saturated();

  auto write = [](const std::string& path, const std::string& text) {
    std::ofstream out(path);
    out << text;
    out.close();
    if (!out) throw std::runtime_error(path + ": cannot write");
  };
  write(out_dir + "/plan.ini", r.plan.text);
  const std::string& sensor_source =
      spec.filter_sensor_path.empty() ? spec.data_sensor_path : spec.filter_sensor_path;
  {
    std::ifstream in(sensor_source);
    if (!in) throw std::runtime_error(sensor_source + ": cannot open");
    std::ostringstream text;
    text << in.rdbuf();
    write(out_dir + "/sensor.ini", text.str());
  }
  write_truth_json(out_dir + "/truth.json", r.truth,
                   "simulate --plan " + spec.plan_path + " --sensor " + spec.data_sensor_path +
                       " --seed " + std::to_string(spec.seed) + (so.noise ? "" : " (no noise)"));
  char site[256];
  std::snprintf(
      site, sizeof site, "latitude = %.12g deg\nlongitude = %.12g deg\nheight = %.12g m\n",
      r.plan.site.lat_rad / units::deg, r.plan.site.lon_rad / units::deg, r.plan.site.h_m);
  char rate[64];
  std::snprintf(rate, sizeof rate, "%.12g", spec.rate_hz);
  r.session_path = out_dir + "/session.ini";
  write(r.session_path, "# Written by sinscal simulate\n[session]\nname = " +
                            (spec.name.empty() ? r.plan.name : spec.name) + "\nrate = " + rate +
                            " Hz\nplan = plan.ini\nsensor = sensor.ini\ntruth = truth.json\n\n"
                            "[site]\n" +
                            site + "\n[log]\nfile = imu.csv\nformat = sinscal\n");
  return r;
}

void write_truth_json(const std::string& path, const ImuErrorModel& model,
                      const std::string& note) {
  nlohmann::ordered_json j;
  if (!note.empty()) j["note"] = note;
  auto& c = j["coefficients"];
  ImuErrorModel copy = model;
  for (const auto& [info, ptr] : copy.coefficient_refs())
    c[info.name] = {{"value", *ptr / info.si_per_unit}, {"unit", info.unit}};
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace sinscal
