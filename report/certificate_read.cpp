// read_certificate: what the page shows, from a result file (every method's sections) and a
// diagnosis directory.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <utility>

#include "models/imu_error_model.hpp"
#include "report/certificate.hpp"
#include "report/provenance.hpp"
#include "report/sha256.hpp"

namespace sinscal {

namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

[[noreturn]] void fail(const std::string& path, const std::string& cause) {
  throw std::runtime_error(path + ": " + cause);
}

std::string text(const Json& v, int digits = 4) {
  if (v.is_string()) return v.get<std::string>();
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number()) {
    char b[64];
    std::snprintf(b, sizeof b, "%.*g", digits, v.get<double>());
    return b;
  }
  if (v.is_null()) return "-";
  if (v.is_array()) {
    std::string out;
    for (const auto& e : v) out += (out.empty() ? "" : ", ") + text(e, digits);
    return out;
  }
  return v.dump();
}

// A member as text, "-" when absent.
std::string at(const Json& j, const char* key, int digits = 4) {
  return j.is_object() && j.contains(key) ? text(j[key], digits) : "-";
}

bool truthy(const Json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_boolean() && j[key].get<bool>();
}

// A recorded path as it reads from here: relative ones against the calibration's working
// directory.
std::string resolved(const std::string& path, const std::string& cwd) {
  if (path.empty() || fs::path(path).is_absolute() || cwd.empty()) return path;
  std::error_code ec;
  if (fs::exists(path, ec)) return path;
  return (fs::path(cwd) / path).string();
}

void identity_and_files(const Json& j, const std::string& result_path, Certificate& c) {
  const Json p = j.value("provenance", Json::object());
  const std::string cwd = p.value("working_directory", "");
  const Json session = p.value("session", Json::object());
  const Json profile = p.value("sensor_profile", Json::object());
  c.unit_name = profile.value("name", "");
  if (c.unit_name.empty()) c.unit_name = session.value("name", "");
  const std::string na = "not recorded";
  auto named = [&](const Json& o) {
    if (!o.contains("file")) return std::string(na);
    const std::string name = o.value("name", "");
    return (name.empty() ? "" : name + " (") + o.value("file", "") + (name.empty() ? "" : ")");
  };
  c.identity = {{"Unit (sensor profile)", named(profile)},
                {"Session", named(session)},
                {"Method", at(j.value("method", Json::object()), "name")},
                {"Calibrated on (UTC)", p.value("date_utc", na)},
                {"sinscal version", p.value("sinscal_version", na)},
                {"Command line", p.value("command_line", na)},
                {"Working directory", p.value("working_directory", na)}};
  std::uintmax_t bytes = 0;
  c.identity.emplace_back("Result file",
                          result_path + " (SHA-256 " + sha256_file(result_path, &bytes) + ")");
  if (!p.contains("inputs")) {
    c.files_note =
        "The result records no input files (it was written before sinscal recorded its inputs, "
        "or by a command that does not): the logs' SHA-256 hashes are not available.";
    return;
  }
  for (const auto& f : p["inputs"]) {
    CertificateFile file;
    file.role = f.value("role", "");
    file.path = f.value("file", "");
    if (f.contains("sha256") && f["sha256"].is_string()) file.sha256 = f["sha256"];
    if (f.contains("bytes") && f["bytes"].is_number_unsigned()) file.bytes = f["bytes"];
    std::error_code ec;
    const std::string now = resolved(file.path, cwd);
    if (file.path == "<stdin>") {
      file.state = "read from standard input: not available";
    } else if (file.sha256.empty()) {
      file.state = "no hash recorded (the file was missing at calibration): not available";
    } else if (!fs::is_regular_file(now, ec)) {
      file.state = "not found now (recorded hash only)";
    } else {
      file.state = sha256_file(now) == file.sha256 ? "unchanged" : "CHANGED since the calibration";
    }
    c.files.push_back(file);
  }
}

void verdict(const Json& j, Certificate& c) {
  const Json method = j.value("method", Json::object());
  const std::string name = method.value("name", "");
  auto set = [&](Verdict v, const std::string& title) {
    if (static_cast<int>(v) >= static_cast<int>(c.verdict) || c.verdict_title.empty()) {
      c.verdict = v;
      c.verdict_title = title;
    }
  };
  set(Verdict::Pass, "Calibrated");
  if (name == "kf" && j.contains("convergence")) {
    const Json& conv = j["convergence"];
    if (truthy(conv, "converged")) {
      set(Verdict::Pass, "Converged");
      c.verdict_reasons.push_back("every sigma at or below its sensor profile's target from t = " +
                                  at(conv, "converged_at_t") + " s");
    } else if (truthy(conv, "targets")) {
      set(Verdict::Warning, "Calibrated, sigma targets not reached");
      c.verdict_reasons.push_back("above their profile's sigma target: " +
                                  at(conv, "above_target"));
    } else {
      c.verdict_reasons.push_back("the sensor profile sets no sigma targets");
    }
    if (conv.contains("unobservable") && !conv["unobservable"].empty())
      c.verdict_reasons.push_back("not determined by the data (no value given): " +
                                  text(conv["unobservable"]));
    if (j.contains("consistency"))
      c.verdict_reasons.push_back("NIS per degree of freedom " +
                                  at(j["consistency"], "nis_per_dof") + " over " +
                                  at(j["consistency"], "samples") + " samples");
  } else if (name == "table-free") {
    if (method.contains("converged") && !truthy(method, "converged"))
      set(Verdict::Fail, "The least-squares solution did not converge");
    c.verdict_reasons.push_back("fit chi2 per dof " + at(method, "chi2_per_dof") + " (" +
                                at(method, "dof") + " dof)");
  } else if (name == "closed-form" && j.contains("identifiability")) {
    const Json& id = j["identifiability"];
    c.verdict_reasons.push_back("rank " + at(id, "rank") + " of " + at(id, "parameters") +
                                " coefficients; stage-2 chi2 per dof " + at(id, "chi2_per_dof"));
    if (id.contains("unobservable_directions") && !id["unobservable_directions"].empty()) {
      set(Verdict::Warning, "Calibrated, some directions not determined");
      for (const auto& d : id["unobservable_directions"])
        c.verdict_reasons.push_back("unobservable direction: " + text(d));
    }
  } else if (name == "six-face") {
    c.verdict_reasons.push_back("accelerometer fit chi2 " + at(method, "accel_chi2") + " on " +
                                at(method, "accel_dof") + " dof");
    if (j.contains("not_determined"))
      for (const auto& d : j["not_determined"]) c.verdict_reasons.push_back(text(d));
  } else if (name == "thermal" && j.contains("thermal")) {
    const Json& fit = j["thermal"].value("fit", Json::object());
    c.verdict_reasons.push_back("fit over " + at(method, "soaks") + " soaks: chi2 " +
                                at(fit, "chi2") + " on " + at(fit, "dof") +
                                " dof, p = " + at(fit, "p_value"));
  }
  if (j.contains("plausibility") && !truthy(j["plausibility"], "passed")) {
    set(Verdict::Fail, "Plausibility gate failed (calibrated with --force)");
    for (const auto& ch : j["plausibility"].value("checks", Json::array()))
      if (!truthy(ch, "passed"))
        c.verdict_reasons.push_back(at(ch, "check") + ": " + at(ch, "detail"));
  }
  if (j.contains("stopped")) {
    set(Verdict::Fail, "Stopped before the end of the data");
    c.verdict_reasons.push_back(at(j["stopped"], "reason"));
  }
  if (j.contains("diverged")) {
    set(Verdict::Fail, "Diverged");
    c.verdict_reasons.push_back(at(j["diverged"], "reason"));
  }
  if (j.contains("skipped_samples"))
    c.verdict_reasons.push_back(at(j["skipped_samples"], "count") + " bad samples skipped");
}

// The method's settings: every scalar of "method" (and "consistency").
CertificateSection method_section(const Json& j) {
  CertificateSection s;
  s.title = "Method";
  for (const char* key : {"method", "consistency", "data"}) {
    if (!j.contains(key) || !j[key].is_object()) continue;
    for (const auto& [k, v] : j[key].items())
      if (!v.is_object() && !(v.is_array() && v.size() > 6))
        s.facts.emplace_back(method_label(k), text(v));
  }
  return s;
}

std::optional<CertificateSection> installation_section(const Json& j) {
  if (!j.contains("installation")) return std::nullopt;
  const Json& in = j["installation"];
  CertificateSection s;
  s.title = "Installation: table base and mounting";
  const Json base = in.value("base", Json::object());
  const Json mount = in.value("mounting", Json::object());
  if (truthy(base, "estimated")) {
    const Json sig = base.value("sigma_arcsec", Json::array({nullptr, nullptr, nullptr}));
    s.facts.emplace_back("Base level North [arcsec]",
                         at(base, "level_north_arcsec") + " ± " + text(sig[0], 2));
    s.facts.emplace_back("Base level East [arcsec]",
                         at(base, "level_east_arcsec") + " ± " + text(sig[1], 2));
    s.facts.emplace_back("Base heading [arcsec]",
                         at(base, "heading_arcsec") + " ± " + text(sig[2], 2));
  } else {
    s.facts.emplace_back("Table base", "not estimated");
  }
  if (truthy(mount, "estimated")) {
    s.facts.emplace_back(
        "Mounting rotation x, y, z [arcsec]",
        at(mount, "rotation_vector_arcsec") + " (± " + at(mount, "sigma_arcsec", 2) + ")");
    s.facts.emplace_back("Mounting angle [deg]", at(mount, "angle_deg"));
    s.facts.emplace_back("Mounting from", at(mount, "from"));
  } else {
    s.facts.emplace_back("IMU mounting", "not estimated");
  }
  if (in.contains("alignment"))
    s.facts.emplace_back("Alignment from the dwells", truthy(in["alignment"], "applied")
                                                          ? "applied (the filter started from it)"
                                                          : "not applied");
  return s;
}

// Per-dwell (closed form), per-pose (table-free), per-face (six-face), per-soak (thermal).
std::vector<CertificateSection> residual_sections(const Json& j) {
  std::vector<CertificateSection> out;
  auto table = [&](const char* key, const std::string& title,
                   const std::vector<std::string>& header, auto row) {
    if (!j.contains(key) || !j[key].is_array() || j[key].empty()) return;
    CertificateSection s;
    s.title = title;
    s.table.header = header;
    for (const auto& e : j[key]) s.table.rows.push_back(row(e));
    out.push_back(s);
  };
  table(
      "stage1", "Residuals per dwell (stage 1)",
      {"dwell", "label", "duration [s]", "RMS velocity [m/s]", "RMS attitude [arcsec]", "chi2/dof"},
      [](const Json& e) {
        const Json r = e.value("residuals", Json::object());
        return std::vector<std::string>{at(e, "dwell"),
                                        at(e, "label"),
                                        at(e, "duration_s"),
                                        at(r, "rms_velocity_m_per_s", 3),
                                        at(r, "rms_attitude_arcsec", 3),
                                        at(r, "chi2_per_dof", 3)};
      });
  table("poses", "Residuals per pose",
        {"pose", "start [s]", "duration [s]", "|f| - g [m/s²]", "accel RMS [m/s²]",
         "gyro RMS [deg/s]", "turn error [deg]"},
        [](const Json& e) {
          const Json f = e.value("fit", Json::object());
          return std::vector<std::string>{at(e, "pose"),
                                          at(e, "t_start"),
                                          at(e, "duration_s"),
                                          at(f, "gravity_error_m_per_s2", 3),
                                          at(f, "accel_rms_m_per_s2", 3),
                                          at(f, "gyro_rms_deg_per_s", 3),
                                          at(f, "turn_error_deg", 3)};
        });
  table("faces", "Residuals per face",
        {"face", "duration [s]", "tilt [deg]", "tilt sigma [deg]", "|f| - g [m/s²]"},
        [](const Json& e) {
          return std::vector<std::string>{at(e, "label"), at(e, "duration_s"), at(e, "tilt_deg", 3),
                                          at(e, "tilt_sigma_deg", 3),
                                          at(e, "gravity_error_mps2", 3)};
        });
  if (j.contains("thermal")) {
    const Json& t = j["thermal"];
    CertificateSection s;
    s.title = "Thermal soaks";
    s.table.header = {"soak", "session", "T accel [°C]", "T gyro [°C]", "NIS/dof"};
    int k = 0;
    for (const auto& e : t.value("soaks", Json::array()))
      s.table.rows.push_back({std::to_string(++k), at(e, "session"), at(e, "accel_temperature_c"),
                              at(e, "gyro_temperature_c"), at(e, "nis_per_dof", 3)});
    for (const auto& d : t.value("degrees", Json::array()))
      s.paragraphs.push_back(at(d, "family") + ": degree " + at(d, "degree") + " of at most " +
                             at(d, "max_degree"));
    out.push_back(s);
  }
  return out;
}

std::optional<CertificateSection> noise_section(const Json& j) {
  if (!j.contains("noise") || !j["noise"].is_object()) return std::nullopt;
  CertificateSection s;
  s.title = "Noise at rest (per reading, pooled over the poses)";
  s.table.header = {"triad", "x", "y", "z", "unit"};
  const Json& n = j["noise"];
  if (n.contains("accel_m_per_s2"))
    s.table.rows.push_back({"accelerometers", text(n["accel_m_per_s2"][0], 3),
                            text(n["accel_m_per_s2"][1], 3), text(n["accel_m_per_s2"][2], 3),
                            "m/s²"});
  if (n.contains("gyro_deg_per_s"))
    s.table.rows.push_back({"gyros", text(n["gyro_deg_per_s"][0], 3),
                            text(n["gyro_deg_per_s"][1], 3), text(n["gyro_deg_per_s"][2], 3),
                            "deg/s"});
  return s;
}

}  // namespace

Certificate read_certificate(const CertificateOptions& o) {
  const std::string& path = o.result_path;
  if (!(o.coverage_factor >= 1.0 && o.coverage_factor <= 10.0))
    throw std::invalid_argument("the coverage factor k must be 1 to 10");
  ResultFile r = read_result_file(path, o.force);
  const Json& j = r.json;
  if (!j.contains("method") || !j["method"].is_object())
    fail(path, j.contains("note") ? "a truth file (simulate's), not a calibration result: report "
                                    "takes the result of calibrate"
                                  : "not a calibration result (no \"method\" section)");
  Certificate c;
  c.coefficients = std::move(r.coefficients);
  c.misalignment_frame = r.misalignment_frame;
  c.forced = std::move(r.forced);
  c.coverage_factor = o.coverage_factor;
  c.approver = o.approver;
  identity_and_files(j, path, c);
  verdict(j, c);
  if (!c.forced.empty()) {
    c.verdict = Verdict::Fail;
    c.verdict_title = "Implausible coefficients (certified with --force)";
    for (const auto& f : c.forced)
      c.verdict_reasons.push_back("beyond what a sensor can have: " + f);
  }
  c.conditions = calibration_conditions(j);
  c.sections.push_back(method_section(j));
  if (auto s = installation_section(j)) c.sections.push_back(*s);
  const Json p = j.value("provenance", Json::object());
  std::string monitor = o.monitor_path;
  if (monitor.empty() && p.contains("monitor"))
    monitor = resolved(p["monitor"].get<std::string>(), p.value("working_directory", ""));
  if (j["method"].value("name", "") == "kf" || !monitor.empty()) {
    const Json conv = j.value("convergence", Json::object());
    const double at_t = conv.contains("converged_at_t") ? conv["converged_at_t"].get<double>() : -1;
    std::string profile;
    if (p.contains("sensor_profile"))
      profile = resolved(p["sensor_profile"].value("file", ""), p.value("working_directory", ""));
    c.sections.push_back(convergence_section(monitor, profile, at_t, o.gnuplot));
  }
  for (auto& s : residual_sections(j)) c.sections.push_back(s);
  if (auto s = noise_section(j)) c.sections.push_back(*s);
  if (!o.diagnosis_dir.empty()) c.sections.push_back(diagnosis_section(o.diagnosis_dir));
  c.issued = "sinscal " + sinscal_version() + ", " + utc_timestamp();
  return c;
}

}  // namespace sinscal
