// What the certificate says beside the coefficients: the conditions of the calibration (the log's
// temperature, the soaks', the site) and the method's settings in words instead of raw keys.
#include <cstdio>
#include <filesystem>
#include <map>

#include "models/units.hpp"
#include "report/certificate.hpp"
#include "rig/io/log_io.hpp"
#include "rig/session.hpp"

namespace sinscal {

namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

const std::map<std::string, std::string>& labels() {
  static const std::map<std::string, std::string> m = {
      {"name", "Method"},
      {"states", "Filter states"},
      {"zero_velocity", "Zero-velocity updates at rest"},
      {"zero_velocity_in_motion", "Zero-velocity updates while the table turns"},
      {"position", "Known-position updates"},
      {"attitude", "Table-attitude updates"},
      {"base", "Table base attitude"},
      {"body_frame", "Body frame"},
      {"body_frame_converted_from", "Estimated in, then converted from, the frame of"},
      {"frame", "Body frame"},
      {"static_from", "Static dwells taken from"},
      {"attitude_from", "Attitude updates taken from"},
      {"update_interval_s", "Update interval [s]"},
      {"prior_scale", "Prior sigma (times the sensor profile's range)"},
      {"table_sigma_arcsec", "Table attitude accuracy, 1-sigma [arcsec]"},
      {"fixed_by_convention", "Fixed by convention"},
      {"passes", "Passes over the log"},
      {"nis_per_dof", "Normalized innovation squared per degree of freedom"},
      {"samples", "Samples read"},
      {"stage1", "Stage 1 (per dwell)"},
      {"model", "Error model"},
      {"arw_deg_per_sqrt_h", "Angle random walk [deg/√h]"},
      {"vrw_ug_per_sqrt_hz", "Velocity random walk [µg/√Hz]"},
      {"solver", "Solver"},
      {"converged", "Converged"},
      {"iterations", "Iterations"},
      {"chi2", "Chi-square"},
      {"dof", "Degrees of freedom"},
      {"chi2_per_dof", "Chi-square per degree of freedom"},
      {"earth_rate", "Earth rate"},
      {"starting_values", "Starting values"},
      {"min_poses", "Fewest poses"},
      {"gravity_mps2", "Gravity [m/s²]"},
      {"earth_rate_not_modelled_deg_per_h", "Earth rate not modelled, at most [deg/h]"},
      {"accel_chi2", "Accelerometer fit chi-square"},
      {"accel_dof", "Accelerometer fit degrees of freedom"},
      {"per_soak", "Method per soak"},
      {"soaks", "Soaks"},
      {"log", "Log"}};
  return m;
}

std::string text(double v, int digits) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*f", digits, v);
  return b;
}

std::string span(double lo, double hi) {
  return lo == hi ? text(lo, 1) + " °C" : text(lo, 1) + " to " + text(hi, 1) + " °C";
}

// The temperature of the session's log (read through, constant memory), or why there is none.
std::vector<std::pair<std::string, std::string>> log_conditions(const std::string& session_path) {
  const std::string label = "Temperature of the log";
  Session s;
  try {
    s = Session::load(session_path, Session::PlanNeed::Optional);
  } catch (const std::exception& e) {
    return {
        {label, std::string("not available (the session cannot be read now: ") + e.what() + ")"}};
  }
  std::vector<std::pair<std::string, std::string>> out;
  if (s.has_site)
    out.emplace_back("Site", "latitude " + text(s.site.lat_rad / units::deg, 4) + " deg, height " +
                                 text(s.site.h_m, 1) + " m");
  try {
    LogReader reader(s.log);
    ImuSample x;
    for (bool first = true; reader.next(x); first = false)
      if (first && !x.has_temperature) break;  // no temperature column: nothing to read
    const TemperatureSummary& t = reader.temperature_summary();
    if (t.samples == 0) {
      out.emplace_back(label, "not recorded (the log has no temperature column)");
    } else if (t.one_per_unit) {
      out.emplace_back(label, span(t.accel_min_c, t.accel_max_c) + " over " +
                                  text(t.t_last - t.t_first, 0) + " s");
    } else {
      out.emplace_back(label + " (accelerometers)", span(t.accel_min_c, t.accel_max_c));
      out.emplace_back(label + " (gyros)", span(t.gyro_min_c, t.gyro_max_c));
    }
  } catch (const std::exception& e) {
    out.emplace_back(label, std::string("not available (") + e.what() + ")");
  }
  return out;
}

}  // namespace

std::string method_label(const std::string& key) {
  const auto it = labels().find(key);
  if (it != labels().end()) return it->second;
  static const std::vector<std::pair<std::string, std::string>> suffixes = {{"_deg_per_s", "deg/s"},
                                                                            {"_deg_per_h", "deg/h"},
                                                                            {"_arcsec", "arcsec"},
                                                                            {"_deg", "deg"},
                                                                            {"_m_per_s2", "m/s²"},
                                                                            {"_mps2", "m/s²"},
                                                                            {"_s", "s"},
                                                                            {"_c", "°C"},
                                                                            {"_hz", "Hz"},
                                                                            {"_ug", "µg"},
                                                                            {"_m", "m"}};
  std::string words = key, unit;
  for (const auto& [suffix, u] : suffixes)
    if (words.size() > suffix.size() &&
        words.compare(words.size() - suffix.size(), suffix.size(), suffix) == 0) {
      words.resize(words.size() - suffix.size());
      unit = u;
      break;
    }
  for (char& ch : words)
    if (ch == '_') ch = ' ';
  if (!words.empty() && words[0] >= 'a' && words[0] <= 'z')
    words[0] = static_cast<char>(words[0] - 'a' + 'A');
  return unit.empty() ? words : words + " [" + unit + "]";
}

std::vector<std::pair<std::string, std::string>> calibration_conditions(const Json& j) {
  std::vector<std::pair<std::string, std::string>> out;
  if (j.contains("thermal") && j["thermal"].is_object() && j["thermal"].contains("soaks") &&
      j["thermal"]["soaks"].is_array() && !j["thermal"]["soaks"].empty()) {
    double lo = 1e9, hi = -1e9;
    for (const auto& e : j["thermal"]["soaks"])
      for (const char* k : {"accel_temperature_c", "gyro_temperature_c"})
        if (e.is_object() && e.contains(k) && e[k].is_number()) {
          lo = std::min(lo, e[k].get<double>());
          hi = std::max(hi, e[k].get<double>());
        }
    if (lo <= hi)
      out.emplace_back(
          "Soak temperatures",
          span(lo, hi) + " (" + std::to_string(j["thermal"]["soaks"].size()) + " soaks)");
    return out;
  }
  const Json p = j.value("provenance", Json::object());
  if (!p.is_object() || !p.contains("session") || !p["session"].is_object() ||
      !p["session"].contains("file") || !p["session"]["file"].is_string()) {
    out.emplace_back("Temperature of the log", "not available (the result names no session)");
    return out;
  }
  std::string session = p["session"]["file"].get<std::string>();
  std::error_code ec;
  const std::string cwd = p.value("working_directory", "");
  if (!fs::exists(session, ec) && !cwd.empty() && fs::path(session).is_relative())
    session = (fs::path(cwd) / session).string();
  return log_conditions(session);
}

}  // namespace sinscal
