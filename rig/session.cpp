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
  const std::string dir = std::filesystem::path(path).parent_path().string();
  return dir.empty() ? "." : dir;
}

// Session::load's limits (docs/formats.md): a nominal rate up to 100 kHz, a time offset within
// 1e10 s either way (GPS or Unix seconds are about 1e9 s).
constexpr double kMaxRateHz = 100000.0;
constexpr double kMaxTimeOffset = 1e10;
// [site] gravity: the Earth's surface gravity is 9.76-9.84 m/s^2 (equator to pole, mountains to
// ocean floors); a value outside 9.7-9.9 is a wrong unit.
constexpr double kMinGravity = 9.7;
constexpr double kMaxGravity = 9.9;

// A file named by `key` (a path relative to the session's directory): not empty, and (when
// `must_exist`) an existing regular file. Empty when the key is absent.
std::string named_file(const IniFile& ini, const std::string& dir, const std::string& key,
                       bool must_exist) {
  if (!ini.has(key)) return {};
  const std::string value = ini.get_string(key);
  if (value.empty()) throw ConfigError(ini.where(key) + "no file name given");
  std::string file = path_in(dir, value);
  std::error_code ec;  // a name the system refuses (too long, ...) reads as "no such file"
  if (must_exist && !std::filesystem::is_regular_file(file, ec))
    throw ConfigError(ini.where(key) + "'" + value + "': no such file (" + file + ")");
  return file;
}
}  // namespace

Session Session::load(const std::string& path, PlanNeed plan_need) {
  const bool optional_plan = plan_need == PlanNeed::Optional;
  const IniFile ini(path);
  for (const auto& section : ini.sections())
    if (section != "session" && section != "site" && section != "log" && section != "six_face" &&
        section != "table_free") {
      std::string where = path + ": ";
      for (const auto& key : ini.keys())
        if (key.compare(0, section.size() + 1, section + ".") == 0) {
          where = ini.where(key);
          break;
        }
      throw ConfigError(where + "unknown section [" + section +
                        "] (known: session, site, log, six_face, table_free)");
    }
  ini.check_keys("session", {"name", "rate", "time_offset", "plan", "truth", "sensor"});
  ini.check_keys("site", {"latitude", "longitude", "height", "gravity"});
  Session s;
  if (std::find(ini.sections().begin(), ini.sections().end(), "six_face") != ini.sections().end())
    s.six_face = read_ferraris_declaration(ini);
  ini.check_keys("table_free", {"pose_window", "min_pose", "edge_trim", "pose_accel_only"});
  auto seconds = [&](const char* key, double lo, double hi) -> std::optional<double> {
    const std::string k = std::string("table_free.") + key;
    if (!ini.has(k)) return std::nullopt;
    const double v = ini.get_quantity(k, QuantityKind::Time, "s");
    if (!(v >= lo && v <= hi))
      throw ConfigError(ini.where(k) +
                        (lo == 0.0 ? "must be 0 to " : "must be above 0 and at most ") +
                        std::to_string(static_cast<int>(hi)) + " s");
    return v;
  };
  s.table_free.pose_window = seconds("pose_window", 1e-9, 60.0);
  s.table_free.min_pose = seconds("min_pose", 1e-9, 3600.0);
  s.table_free.edge_trim = seconds("edge_trim", 0.0, 60.0);
  if (ini.has("table_free.pose_accel_only"))
    s.table_free.pose_accel_only = ini.get_bool("table_free.pose_accel_only", false);
  s.path = path;
  s.dir = directory_of(path);
  s.name = ini.get_string("session.name", "session");
  s.rate_hz = ini.get_quantity("session.rate", QuantityKind::Frequency, "Hz");
  if (!(s.rate_hz > 0.0 && s.rate_hz <= kMaxRateHz))
    throw ConfigError(ini.where("session.rate") + "must be above 0 and at most 100 kHz");
  s.time_offset = ini.get_quantity("session.time_offset", QuantityKind::Time, "s", 0.0);
  if (!(std::abs(s.time_offset) <= kMaxTimeOffset))
    throw ConfigError(ini.where("session.time_offset") + "must be within -1e10 and 1e10 s");
  if (ini.has("session.plan")) {
    s.plan = Plan::load(named_file(ini, s.dir, "session.plan", true));
  } else if (!optional_plan) {
    throw ConfigError(path +
                      ": [session] has no 'plan' (the plan the data follow; a hand-held session "
                      "without a plan is read by 'calibrate --method table-free' and 'allan' "
                      "only)");
  } else {
    s.has_plan = false;
  }
  if (ini.has("site.gravity")) {
    if (!optional_plan)
      throw ConfigError(ini.where("site.gravity") +
                        "the local gravity magnitude is read by 'calibrate --method table-free' "
                        "and 'allan' only (the table methods use the WGS-84 gravity model)");
    s.gravity = ini.get_quantity("site.gravity", QuantityKind::Acceleration, "m/s^2");
    if (!(s.gravity >= kMinGravity && s.gravity <= kMaxGravity))
      throw ConfigError(ini.where("site.gravity") +
                        "must be within 9.7 and 9.9 m/s^2 (the Earth's surface)");
  }
  s.truth_file = named_file(ini, s.dir, "session.truth", true);
  s.sensor_file = named_file(ini, s.dir, "session.sensor", true);
  if (ini.has("site.latitude")) {
    s.site = read_site(ini);
  } else if (ini.has("site.longitude") || ini.has("site.height")) {
    throw ConfigError(ini.where(ini.has("site.longitude") ? "site.longitude" : "site.height") +
                      "[site] without 'latitude' (give the whole site, or none to take the "
                      "plan's)");
  } else if (s.has_plan && s.plan.has_site) {
    s.site = s.plan.site;
  } else if (optional_plan) {
    s.has_site = false;
  } else {
    throw ConfigError(path + ": no [site] latitude in the session or its plan");
  }
  s.log = LogFormat::from_ini(ini, s.dir, s.rate_hz);
  return s;
}

SimulatedSession simulate_session(const std::string& out_dir, const SessionSimulation& spec) {
  if (!(spec.rate_hz > 0.0)) throw std::invalid_argument("simulate_session: rate must be positive");
  SimulatedSession r;
  r.plan = Plan::load(spec.plan_path);
  if (spec.plan_repeat > 1) {
    // The plan's own text with `repeat` in [plan]: what the session's plan.ini says.
    std::string text = r.plan.text;
    const auto at = text.find("[plan]");
    const auto eol = at == std::string::npos ? at : text.find('\n', at);
    if (eol == std::string::npos)
      throw ConfigError(spec.plan_path + ": no [plan] line to add 'repeat' to");
    text.insert(eol + 1, "repeat = " + std::to_string(spec.plan_repeat) +
                             "  # added by simulate --chamber: the plan runs while the chamber "
                             "ramps\n");
    r.plan = Plan::parse(spec.plan_path, text);
  }
  if (!r.plan.has_site)
    throw ConfigError(spec.plan_path + ": the plan has no [site] for the simulation");
  r.profile = SensorProfile::load(spec.data_sensor_path);
  // The sensors' own errors (in the IMU's axes, what the simulator applies) and the truth an
  // estimator must find: the same sensors relative to the platform, the mounting included.
  const ImuErrorModel sensor_errors =
      spec.perfect ? ImuErrorModel{} : r.profile.draw(derive_seed(spec.seed, 1));
  r.truth = in_platform_frame(sensor_errors, dcm_from_rotvec(spec.table.mounting_b));
  const Motion motion = build_motion(r.plan, r.plan.site, spec.table);
  r.duration = motion.duration();
  r.dwells = motion.dwells().size();
  SimulatorOptions so;
  so.rate_hz = spec.rate_hz;
  so.noise = spec.noise && !spec.perfect;
  so.noise_seed = spec.noise_stream == 0
                      ? derive_seed(spec.seed, 2)
                      : derive_seed(derive_seed(spec.seed, 2), spec.noise_stream);
  so.temperature = spec.temperature;
  so.gyro_range = r.profile.gyro_range;
  so.accel_range = r.profile.accel_range;
  so.table_angles = spec.table_angles;
  so.motion_start = spec.table.dynamics.start_offset;
  ImuSimulator sim(motion, sensor_errors, r.profile.noise, so);

  std::filesystem::create_directories(out_dir);
  LogWriter log(out_dir + "/imu.csv", spec.rate_hz, spec.table_angles, spec.temperature != nullptr);
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
                       " --seed " + std::to_string(spec.seed) + (so.noise ? "" : " (no noise)"),
                   &spec.table);
  char site[256];
  std::snprintf(
      site, sizeof site, "latitude = %.12g deg\nlongitude = %.12g deg\nheight = %.12g m\n",
      r.plan.site.lat_rad / units::deg, r.plan.site.lon_rad / units::deg, r.plan.site.h_m);
  char rate[64];
  std::snprintf(rate, sizeof rate, "%.12g", spec.rate_hz);
  r.session_path = out_dir + "/session.ini";
  write(r.session_path, "# Written by sinscal simulate\n" +
                            (spec.note.empty() ? std::string() : "# " + spec.note + "\n") +
                            "[session]\nname = " + (spec.name.empty() ? r.plan.name : spec.name) +
                            "\nrate = " + rate +
                            " Hz\nplan = plan.ini\nsensor = sensor.ini\ntruth = truth.json\n\n"
                            "[site]\n" +
                            site + "\n[log]\nfile = imu.csv\nformat = sinscal\n");
  return r;
}

void write_truth_json(const std::string& path, const ImuErrorModel& model, const std::string& note,
                      const TableErrors* table) {
  nlohmann::ordered_json j;
  if (!note.empty()) j["note"] = note;
  auto& c = j["coefficients"];
  ImuErrorModel copy = model;
  for (const auto& [info, ptr] : copy.coefficient_refs())
    c[info.name] = {{"value", *ptr / info.si_per_unit}, {"unit", info.unit}};
  if (model.has_thermal())
    j["thermal"] = {{"reference_temperature_c", model.reference_temperature_c}};
  if (table) {
    const Eigen::Vector3d m = table->mounting_b / units::deg;
    j["installation"] = {{"base_level_north_deg", table->base_level_north / units::deg},
                         {"base_level_east_deg", table->base_level_east / units::deg},
                         {"base_heading_deg", table->base_heading / units::deg},
                         {"mounting_deg", {m.x(), m.y(), m.z()}},
                         {"mounting_angle_deg", table->mounting_b.norm() / units::deg}};
    const TableDynamics& d = table->dynamics;
    if (d.any() || d.start_offset != 0.0) {
      // What the table really did: the estimators never read it (tests compare with it).
      auto& o = j["table_dynamics"];
      o["start_offset_s"] = d.start_offset;
      o["max_rate_deg_s"] = d.max_rate / units::deg;
      o["max_acceleration_deg_s2"] = d.max_acceleration / units::deg;
      o["jerk_time_s"] = d.jerk_time;
      o["smoothing_s"] = d.smoothing;
      o["servo_frequency_hz"] = d.servo_frequency;
      o["servo_damping"] = d.servo_damping;
      o["ripple_frequency_hz"] = d.ripple_frequency;
      o["ripple_damping"] = d.ripple_damping;
      o["rate_ripple_arcsec"] = d.rate_ripple / units::arcsec;
      o["rate_ripple_period_deg"] = d.rate_ripple_period / units::deg;
    }
  }
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace sinscal
