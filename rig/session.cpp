#include "rig/session.hpp"

#include <fstream>
#include <nlohmann/json.hpp>

#include "models/config.hpp"

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

}  // namespace sinscal
