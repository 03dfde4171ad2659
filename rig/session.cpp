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

// Session::load's limits (docs/formats.md): a nominal rate up to 100 kHz, a time offset within
// 1e10 s either way (GPS or Unix seconds are about 1e9 s).
constexpr double kMaxRateHz = 100000.0;
constexpr double kMaxTimeOffset = 1e10;

// A file named by `key` (a path relative to the session's directory): not empty, and (when
// `must_exist`) an existing regular file. Empty when the key is absent.
std::string named_file(const IniFile& ini, const std::string& dir, const std::string& key,
                       bool must_exist) {
  if (!ini.has(key)) return {};
  const std::string value = ini.get_string(key);
  if (value.empty()) throw ConfigError(ini.where(key) + "no file name given");
  const std::string file = resolve(dir, value);
  if (must_exist && !std::filesystem::is_regular_file(file))
    throw ConfigError(ini.where(key) + "'" + value + "': no such file (" + file + ")");
  return file;
}
}  // namespace

Session Session::load(const std::string& path) {
  const IniFile ini(path);
  for (const auto& section : ini.sections())
    if (section != "session" && section != "site" && section != "log") {
      std::string where = path + ": ";
      for (const auto& key : ini.keys())
        if (key.compare(0, section.size() + 1, section + ".") == 0) {
          where = ini.where(key);
          break;
        }
      throw ConfigError(where + "unknown section [" + section + "] (known: session, site, log)");
    }
  ini.check_keys("session", {"name", "rate", "time_offset", "plan", "truth", "sensor"});
  ini.check_keys("site", {"latitude", "longitude", "height"});
  Session s;
  s.path = path;
  s.dir = directory_of(path);
  s.name = ini.get_string("session.name", "session");
  s.rate_hz = ini.get_quantity("session.rate", QuantityKind::Frequency, "Hz");
  if (!(s.rate_hz > 0.0 && s.rate_hz <= kMaxRateHz))
    throw ConfigError(ini.where("session.rate") + "must be above 0 and at most 100 kHz");
  s.time_offset = ini.get_quantity("session.time_offset", QuantityKind::Time, "s", 0.0);
  if (!(std::abs(s.time_offset) <= kMaxTimeOffset))
    throw ConfigError(ini.where("session.time_offset") + "must be within -1e10 and 1e10 s");
  if (!ini.has("session.plan"))
    throw ConfigError(path + ": [session] has no 'plan' (the plan the data follow)");
  s.plan = Plan::load(named_file(ini, s.dir, "session.plan", true));
  s.truth_file = named_file(ini, s.dir, "session.truth", true);
  s.sensor_file = named_file(ini, s.dir, "session.sensor", true);
  if (ini.has("site.latitude")) {
    s.site = read_site(ini);
  } else if (ini.has("site.longitude") || ini.has("site.height")) {
    throw ConfigError(ini.where(ini.has("site.longitude") ? "site.longitude" : "site.height") +
                      "[site] without 'latitude' (give the whole site, or none to take the "
                      "plan's)");
  } else if (s.plan.has_site) {
    s.site = s.plan.site;
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

void write_result_json(const std::string& path, const ResultCoefficients& coefficients,
                       const nlohmann::ordered_json& extra) {
  nlohmann::ordered_json j;
  auto& c = j["coefficients"];
  for (const auto& info : coefficient_catalog()) {
    const auto it = coefficients.find(info.name);
    if (it == coefficients.end()) continue;
    nlohmann::ordered_json e = nlohmann::ordered_json::object();
    if (it->second.fixed_by_convention) {
      e["value"] = 0.0;
      e["fixed_by_convention"] = true;
    } else if (it->second.observable) {
      e["value"] = it->second.value;
      if (it->second.sigma) e["sigma"] = *it->second.sigma;
    } else {
      e["observable"] = false;
      if (it->second.sigma) e["sigma"] = *it->second.sigma;
    }
    e["unit"] = it->second.unit;
    c[info.name] = e;
  }
  for (const auto& [key, value] : extra.items()) j[key] = value;
  std::ofstream out(path);
  out << j.dump(2) << "\n";
  if (!out) throw std::runtime_error(path + ": cannot write");
}

ResultCoefficients read_result_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  ResultCoefficients out;
  try {
    const auto j = nlohmann::json::parse(in);
    for (const auto& [name, e] : j.at("coefficients").items()) {
      ResultCoefficient r;
      r.observable = e.value("observable", true);
      r.fixed_by_convention = e.value("fixed_by_convention", false);
      if (r.observable) r.value = e.at("value").get<double>();
      if (e.contains("sigma")) r.sigma = e.at("sigma").get<double>();
      r.unit = e.value("unit", "");
      out[name] = r;
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not a sinscal result file: " + e.what());
  }
  return out;
}

ResultCoefficients load_truth(const Session& session, bool accel_triad_frame) {
  if (session.truth_file.empty() || !std::filesystem::exists(session.truth_file)) return {};
  ResultCoefficients truth = read_result_json(session.truth_file);
  if (accel_triad_frame) {
    ImuErrorModel m;
    for (const auto& [name, t] : truth) m.set(name, t.value);
    for (const auto& [name, v] : in_accel_triad_frame(m).coefficients()) truth[name].value = v;
  }
  return truth;
}

std::optional<double> max_error_over_sigma(const ResultCoefficients& result,
                                           const ResultCoefficients& truth) {
  std::optional<double> worst;
  for (const auto& [name, c] : result) {
    const auto t = truth.find(name);
    if (t == truth.end() || !c.observable || c.fixed_by_convention || !c.sigma || !(*c.sigma > 0))
      continue;
    const double z = std::abs(c.value - t->second.value) / *c.sigma;
    if (!worst || z > *worst) worst = z;
  }
  return worst;
}

std::vector<CoefficientComparison> compare_results(const ResultCoefficients& a,
                                                   const ResultCoefficients& b) {
  auto relative = [](double x, double y) {
    const double scale = std::max(std::abs(x), std::abs(y));
    return scale > 0.0 ? std::abs(x - y) / scale : 0.0;
  };
  auto value = [](const ResultCoefficients& r, const std::string& name) -> std::optional<double> {
    const auto it = r.find(name);
    if (it == r.end() || !it->second.observable) return std::nullopt;
    return it->second.fixed_by_convention ? 0.0 : it->second.value;
  };
  auto sigma = [](const ResultCoefficients& r, const std::string& name) -> std::optional<double> {
    const auto it = r.find(name);
    return it == r.end() ? std::nullopt : it->second.sigma;
  };
  std::vector<CoefficientComparison> out;
  for (const auto& info : coefficient_catalog()) {
    if (!a.count(info.name) && !b.count(info.name)) continue;
    CoefficientComparison c;
    c.name = info.name;
    c.unit = info.unit;
    c.a = value(a, info.name);
    c.b = value(b, info.name);
    c.sigma_a = sigma(a, info.name);
    c.sigma_b = sigma(b, info.name);
    if (c.a && c.b) c.relative = relative(*c.a, *c.b);
    if (c.sigma_a && c.sigma_b) {
      c.sigma_relative = relative(*c.sigma_a, *c.sigma_b);
      const double s = std::hypot(*c.sigma_a, *c.sigma_b);
      if (c.a && c.b && s > 0.0) c.z = (*c.a - *c.b) / s;
    }
    out.push_back(c);
  }
  return out;
}

std::vector<std::string> find_sessions(const std::string& path) {
  namespace fs = std::filesystem;
  if (!fs::exists(path)) throw std::runtime_error(path + ": no such file or directory");
  if (!fs::is_directory(path)) return {path};
  if (fs::exists(fs::path(path) / "session.ini"))
    return {(fs::path(path) / "session.ini").string()};
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(path))
    if (entry.is_directory() && fs::exists(entry.path() / "session.ini"))
      out.push_back((entry.path() / "session.ini").string());
  std::sort(out.begin(), out.end());
  if (out.empty())
    throw std::runtime_error(path + ": no session.ini in this directory nor in its subdirectories");
  return out;
}

std::vector<std::string> read_session_list(const std::string& list_path) {
  std::ifstream in(list_path);
  if (!in) throw std::runtime_error(list_path + ": cannot open");
  const std::string dir = directory_of(list_path);
  std::vector<std::string> out;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.erase(hash);
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos) continue;
    line = line.substr(first, line.find_last_not_of(" \t\r") - first + 1);
    try {
      for (auto& s : find_sessions(resolve(dir, line))) out.push_back(std::move(s));
    } catch (const std::exception& e) {
      throw std::runtime_error(list_path + ":" + std::to_string(number) + ": " + e.what());
    }
  }
  if (out.empty()) throw std::runtime_error(list_path + ": the list names no session");
  return out;
}

namespace {
std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c == '\n' ? ' ' : c);
  return q + "\"";
}
std::string number(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.10g", v);
  return b;
}
std::string number(const std::optional<double>& v) { return v ? number(*v) : std::string(); }
}  // namespace

void write_summary_csv(const std::string& path, const std::vector<SessionSummary>& rows) {
  std::vector<const CoefficientInfo*> columns;  // catalog order, those any row has
  for (const auto& info : coefficient_catalog())
    for (const auto& r : rows)
      if (r.coefficients.count(info.name)) {
        columns.push_back(&info);
        break;
      }
  std::ofstream out(path);
  out << "session,name,status,result,samples,duration_s,nis_per_dof,converged_at_s,"
         "max_abs_error_over_sigma,message";
  for (const auto* c : columns)
    out << "," << c->name << " [" << c->unit << "]," << c->name << ".sigma [" << c->unit << "]";
  out << "\n";
  for (const auto& r : rows) {
    out << csv_field(r.session) << "," << csv_field(r.name) << "," << r.status << ","
        << csv_field(r.result) << "," << r.samples << "," << number(r.duration) << ","
        << number(r.nis_per_dof) << "," << number(r.converged_at) << ","
        << number(r.max_error_over_sigma) << "," << csv_field(r.message);
    for (const auto* c : columns) {
      const auto it = r.coefficients.find(c->name);
      std::string value, sigma;
      if (it != r.coefficients.end()) {
        const ResultCoefficient& e = it->second;
        if (e.fixed_by_convention)
          value = "0";
        else if (e.observable)
          value = number(e.value);
        if (!e.fixed_by_convention) sigma = number(e.sigma);
      }
      out << "," << value << "," << sigma;
    }
    out << "\n";
  }
  out.close();
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace sinscal
