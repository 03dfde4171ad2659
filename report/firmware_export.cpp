#include "report/firmware_export.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "filter/kalman/misalignment_frame.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/result.hpp"

#ifndef SINSCAL_VERSION
#define SINSCAL_VERSION "unknown"
#endif

namespace sinscal {

namespace {

using Json = nlohmann::ordered_json;

std::string joined(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& s : items) out += (out.empty() ? "" : ", ") + s;
  return out;
}

[[noreturn]] void fail(const std::string& path, const std::string& cause) {
  throw std::runtime_error(path + ": " + cause);
}

// The failed verdicts a result records: the plausibility gate, the divergence alarm, an early
// stop, a solver that did not converge.
std::vector<std::string> failed_verdicts(const nlohmann::json& j) {
  std::vector<std::string> out;
  if (j.contains("plausibility") && j["plausibility"].is_object() &&
      j["plausibility"].value("passed", true) == false) {
    std::vector<std::string> checks;
    if (j["plausibility"].contains("checks") && j["plausibility"]["checks"].is_array())
      for (const auto& c : j["plausibility"]["checks"])
        if (c.is_object() && c.value("passed", true) == false)
          checks.push_back(c.value("check", std::string("?")));
    out.push_back("the plausibility gate failed (" + joined(checks) +
                  "): the calibration ran with --force");
  }
  auto reason = [&](const char* key) {
    const auto& s = j[key];
    return s.is_object() && s.contains("reason") && s["reason"].is_string()
               ? s["reason"].get<std::string>()
               : std::string("no reason given");
  };
  if (j.contains("diverged")) out.push_back("the filter diverged (" + reason("diverged") + ")");
  if (j.contains("stopped"))
    out.push_back("the run stopped before the end of the data (" + reason("stopped") + ")");
  const auto& m = j["method"];
  if (m.contains("converged") && m["converged"].is_boolean() && !m["converged"].get<bool>())
    out.push_back("the solution did not converge (method.converged is false)");
  return out;
}

void body_frame_of(const nlohmann::json& method, FirmwareExport& e) {
  const std::string stated = method.contains("body_frame") && method["body_frame"].is_string()
                                 ? method["body_frame"].get<std::string>()
                                 : "";
  if (stated == "accelerometer triad" || (stated.empty() && e.method == "table-free")) {
    e.body_frame = "accelerometer triad";
    e.body_frame_note =
        "body x along the x accelerometer's sensitive axis, body y in the plane of the x and y "
        "accelerometers (docs/conventions.md); accel misalignments xy, xz, yz are zero by it";
  } else if (stated == "table" || (stated.empty() && e.method == "closed-form")) {
    e.body_frame = "table platform";
    e.body_frame_note =
        "the table platform's axes as the plan draws them: the misalignments include the IMU's "
        "mounting on the platform (docs/conventions.md \"Table base and mounting\")";
  } else if (stated.empty() && e.method == "six-face") {
    e.body_frame = "box faces";
    e.body_frame_note =
        "the axes of the box's faces the unit rested on (every misalignment "
        "estimated, relative to the faces)";
  } else {
    e.body_frame = stated.empty() ? "not stated by the result" : stated;
    e.body_frame_note = "the result's method does not state its body frame";
  }
}

// Shortest text that reads back as the same double, always with a decimal point (a float in
// YAML 1.1 and 1.2 and in C).
std::string number(double v) {
  char b[40];
  for (int precision = 15; precision <= 17; ++precision) {
    std::snprintf(b, sizeof b, "%.*g", precision, v);
    if (std::strtod(b, nullptr) == v) break;
  }
  std::string s = b;
  if (s.find_first_of(".n") == std::string::npos) {  // no point (nan/inf never exported)
    const auto e = s.find('e');
    s.insert(e == std::string::npos ? s.size() : e, ".0");
  }
  return s;
}

Json vec(const Eigen::Vector3d& v) { return Json::array({v(0), v(1), v(2)}); }
Json mat(const Eigen::Matrix3d& m) {
  Json rows = Json::array();
  for (int i = 0; i < 3; ++i) rows.push_back(Json::array({m(i, 0), m(i, 1), m(i, 2)}));
  return rows;
}

Eigen::Matrix3d linear_sigma(const TriadErrors& s) {
  Eigen::Matrix3d m = s.misalignment;
  m.diagonal() = s.scale;
  return m;
}

// Largest error per axis of evaluating the nonlinear terms at the linear estimate, at input |x|:
// (|a| + 2 |k2| |x|)(|a| |x| + |k2| x^2) (second order in them).
double first_order_error(const TriadErrors& t, double x) {
  double worst = 0.0;
  for (int i = 0; i < 3; ++i) {
    const double a = std::abs(t.scale_asym(i)), k2 = std::abs(t.k2(i));
    worst = std::max(worst, (a + 2.0 * k2 * x) * (a * x + k2 * x * x));
  }
  return worst;
}

Json triad_json(const FirmwareExport& e, const char* triad, const TriadErrors& v,
                const TriadErrors& s) {
  const std::string p = triad;
  Json t;
  t["bias"] = vec(v.bias);
  t["bias_sigma"] = vec(s.bias);
  t["correction_matrix"] = mat(v.linear().inverse());
  t["model_matrix"] = mat(v.linear());
  t["model_matrix_sigma"] = mat(linear_sigma(s));
  if (e.has(p + ".scale_asym")) {
    t["scale_asym"] = vec(v.scale_asym);
    t["scale_asym_sigma"] = vec(s.scale_asym);
  }
  if (e.has(p + ".k2")) {
    t["k2"] = vec(v.k2);
    t["k2_sigma"] = vec(s.k2);
  }
  if (e.has(p + ".bias_drift")) {
    t["bias_drift"] = vec(v.bias_drift);
    t["bias_drift_sigma"] = vec(s.bias_drift);
  }
  return t;
}

Json document(const FirmwareExport& e) {
  Json d;
  d["format"] = "sinscal firmware export";
  d["format_version"] = 1;
  d["sinscal_version"] = SINSCAL_VERSION;
  d["source"] = {{"file", e.source_file}, {"bytes", e.source_bytes}, {"method", e.method}};
  d["body_frame"] = e.body_frame;
  d["body_frame_note"] = e.body_frame_note;
  if (!e.misalignment_frame.empty()) d["misalignment_frame"] = e.misalignment_frame;
  if (!e.reference_point.empty()) d["reference_point"] = e.reference_point;
  d["units"] = {{"angular_rate", "rad/s"},
                {"specific_force", "m/s^2"},
                {"time", "s"},
                {"length", "m"},
                {"angle", "rad"},
                {"dimensionless", "1"},
                {"k2", "1/(m/s^2)"},
                {"g_sensitivity", "rad/s per m/s^2"},
                {"gyro_bias_drift", "rad/s^2"},
                {"accel_bias_drift", "m/s^3"}};
  d["terms"] = e.families;
  d["formula"] = export_formula(e);
  Json accuracy;
  accuracy["nonlinear_terms"] =
      "evaluated at the linear estimate v (first order); error per axis at most (|a| + 2 |k2| "
      "|x|) (|a| |x| + |k2| x^2) against the exact inverse";
  accuracy["accel_nonlinear_error_at_1g_m_per_s2"] = first_order_error(e.model.accel, units::g0);
  accuracy["gyro_nonlinear_error_at_1rad_per_s_rad_per_s"] = first_order_error(e.model.gyro, 1.0);
  d["accuracy"] = accuracy;

  Json gyro = triad_json(e, "gyro", e.model.gyro, e.sigma.gyro);
  if (e.has("gyro.g_sensitivity")) {
    gyro["g_sensitivity"] = mat(e.model.gyro_g_sensitivity);
    gyro["g_sensitivity_sigma"] = mat(e.sigma.gyro_g_sensitivity);
  }
  d["gyro"] = gyro;
  Json accel = triad_json(e, "accel", e.model.accel, e.sigma.accel);
  if (e.has("accel.lever_arm")) {
    // Row i: the position r_i of accelerometer i's proof mass (the model keeps it as column i).
    accel["lever_arm"] = mat(e.model.accel_lever_arm_b.transpose());
    accel["lever_arm_sigma"] = mat(e.sigma.accel_lever_arm_b.transpose());
  }
  d["accel"] = accel;
  if (e.has("time_delay"))
    d["time_delay"] = {{"value", e.model.time_delay}, {"sigma", e.sigma.time_delay}};
  d["fixed_by_convention"] = e.fixed_by_convention;
  d["unobservable_exported_as_zero"] = e.unobservable;
  d["warnings"] = e.warnings;
  return d;
}

// --- YAML: a plain emitter for the document's shapes (mappings, lists of scalars or of lists) --

std::string yaml_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char b[8];
      std::snprintf(b, sizeof b, "\\x%02x", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += b;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string yaml_scalar(const Json& v) {
  if (v.is_string()) return yaml_string(v.get<std::string>());
  if (v.is_boolean()) return v.get<bool>() ? "true" : "false";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number_float()) return number(v.get<double>());
  throw std::logic_error("yaml: unsupported value " + v.dump());
}

bool all_scalars(const Json& a) {
  return std::all_of(a.begin(), a.end(), [](const Json& x) { return x.is_primitive(); });
}

std::string yaml_flow(const Json& a) {
  std::string out = "[";
  for (std::size_t i = 0; i < a.size(); ++i) out += (i ? ", " : "") + yaml_scalar(a[i]);
  return out + "]";
}

void yaml_mapping(const Json& m, int indent, std::string& out) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  for (const auto& [key, v] : m.items()) {
    out += pad + key + ":";
    if (v.is_object()) {
      out += "\n";
      yaml_mapping(v, indent + 2, out);
    } else if (v.is_array() && v.empty()) {
      out += " []\n";
    } else if (v.is_array() && all_scalars(v) && !v[0].is_string()) {
      out += " " + yaml_flow(v) + "\n";
    } else if (v.is_array()) {
      out += "\n";
      for (const auto& x : v) {
        if (x.is_array())
          out += pad + "  - " + yaml_flow(x) + "\n";
        else if (x.is_primitive())
          out += pad + "  - " + yaml_scalar(x) + "\n";
        else
          throw std::logic_error("yaml: unsupported list item " + x.dump());
      }
    } else {
      out += " " + yaml_scalar(v) + "\n";
    }
  }
}

// --- C header ---------------------------------------------------------------------------------

std::string c_vec(const Eigen::Vector3d& v) {
  return "{" + number(v(0)) + ", " + number(v(1)) + ", " + number(v(2)) + "}";
}
std::string c_mat(const Eigen::Matrix3d& m) {
  return "{" + c_vec(m.row(0).transpose()) + ", " + c_vec(m.row(1).transpose()) + ", " +
         c_vec(m.row(2).transpose()) + "}";
}

std::string c_triad(const TriadErrors& t, const Eigen::Matrix3d& correction,
                    const Eigen::Matrix3d& model, const std::string& pad) {
  return "{\n" + pad + "  .bias = " + c_vec(t.bias) + ",\n" + pad +
         "  .correction = " + c_mat(correction) + ",\n" + pad + "  .model = " + c_mat(model) +
         ",\n" + pad + "  .scale_asym = " + c_vec(t.scale_asym) + ",\n" + pad +
         "  .bias_drift = " + c_vec(t.bias_drift) + "}";
}

std::string c_terms(const ImuErrorModel& m, bool sigma) {
  const Eigen::Matrix3d ga = sigma ? linear_sigma(m.gyro) : m.gyro.linear();
  const Eigen::Matrix3d aa = sigma ? linear_sigma(m.accel) : m.accel.linear();
  const Eigen::Matrix3d gc = sigma ? ga : Eigen::Matrix3d(ga.inverse());
  const Eigen::Matrix3d ac = sigma ? aa : Eigen::Matrix3d(aa.inverse());
  const std::string pad = "    ";
  return "{\n" + pad + ".gyro = " + c_triad(m.gyro, gc, ga, pad) + ",\n" + pad +
         ".accel = " + c_triad(m.accel, ac, aa, pad) + ",\n" + pad +
         ".gyro_g_sensitivity = " + c_mat(m.gyro_g_sensitivity) + ",\n" + pad +
         ".accel_k2 = " + c_vec(m.accel.k2) + ",\n" + pad +
         ".accel_lever_arm = " + c_mat(m.accel_lever_arm_b.transpose()) + ",\n" + pad +
         ".time_delay = " + number(m.time_delay) + "}";
}

// One comment paragraph, wrapped at 100 columns (continuation lines indented), never closing
// the comment early.
std::string c_comment_line(const std::string& text) {
  std::string safe = text;
  for (std::size_t p = 0; (p = safe.find("*/", p)) != std::string::npos;) safe.replace(p, 2, "* /");
  for (char& c : safe)
    if (static_cast<unsigned char>(c) < 0x20) c = ' ';
  const std::size_t indent =
      safe.find_first_not_of(' ') == std::string::npos ? 0 : safe.find_first_not_of(' ');
  std::string out, line = " *";
  std::istringstream words(safe);
  for (std::string word; words >> word;) {
    const bool first = line == " *";
    if (!first && line.size() + 1 + word.size() > 100) {
      out += line + "\n";
      line = " *" + std::string(indent + 4, ' ') + word;
    } else {
      line += (first ? " " + std::string(indent, ' ') : " ") + word;
    }
  }
  return out + line + "\n";
}

std::string c_header(const FirmwareExport& e) {
  const Json d = document(e);
  std::string h = "/* sinscal firmware export (format 1), sinscal " SINSCAL_VERSION "\n";
  h += c_comment_line("Source: " + e.source_file + " (" + std::to_string(e.source_bytes) +
                      " bytes), method " + e.method);
  h += c_comment_line("Body frame: " + e.body_frame + ": " + e.body_frame_note);
  if (!e.misalignment_frame.empty())
    h += c_comment_line("Misalignment frame: " + e.misalignment_frame + ": " +
                        misalignment_frame_words(parse_misalignment_frame(e.misalignment_frame)));
  if (!e.reference_point.empty()) h += c_comment_line("Reference point: " + e.reference_point);
  h += c_comment_line(
      "Units: SI (rad/s, m/s^2, s, m; k2 in 1/(m/s^2), g-sensitivity in rad/s "
      "per m/s^2, bias drift in rad/s^2 and m/s^3).");
  h += c_comment_line("Terms estimated: " + joined(e.families) +
                      "; every other term is zero here and its SINSCAL_HAS_ macro 0.");
  h += " *\n * Formula (what the firmware computes, in this order):\n";
  for (const auto& line : export_formula(e)) h += c_comment_line("  " + line);
  h += " *\n";
  h += c_comment_line(
      "Field names: value.gyro.bias = b_g, .correction = C_g = A_g^-1, .model = "
      "A_g, .scale_asym = a_g, .bias_drift = d_g; value.gyro_g_sensitivity = G; "
      "value.accel_k2 = k2; value.accel_lever_arm[i] = r_i; value.time_delay = "
      "tau. sigma: the 1-sigma of each (0: none; sigma.correction is the "
      "model's, to first order).");
  h += c_comment_line("Accuracy: " + d["accuracy"]["nonlinear_terms"].get<std::string>() + "; " +
                      number(d["accuracy"]["accel_nonlinear_error_at_1g_m_per_s2"].get<double>()) +
                      " m/s^2 at 1 g.");
  if (!e.fixed_by_convention.empty())
    h += c_comment_line("Zero by the result's convention: " + joined(e.fixed_by_convention));
  if (!e.unobservable.empty())
    h += c_comment_line("NOT DETERMINED by the data, exported as zero (--force): " +
                        joined(e.unobservable));
  for (const auto& w : e.warnings) h += c_comment_line("WARNING (--force): " + w);
  h +=
      " */\n#pragma once\n#ifndef SINSCAL_IMU_CALIBRATION_H\n#define SINSCAL_IMU_CALIBRATION_H\n\n";
  h += "#define SINSCAL_EXPORT_FORMAT_VERSION 1\n";
  if (!e.misalignment_frame.empty())
    h += "#define SINSCAL_MISALIGNMENT_FRAME \"" + e.misalignment_frame + "\"\n";
  for (const auto& f : coefficient_families()) {
    if (f.base || f.thermal()) continue;  // thermal results are refused (read_export_input)
    std::string macro = "SINSCAL_HAS_" + f.name;
    for (char& c : macro) c = c == '.' ? '_' : static_cast<char>(std::toupper(c));
    h += "#define " + macro + (e.has(f.name) ? " 1\n" : " 0\n");
  }
  h += R"(
struct sinscal_triad_terms {
  double bias[3];          /* b: rad/s (gyro), m/s^2 (accel) */
  double correction[3][3]; /* C = A^-1, [row][column], dimensionless */
  double model[3][3];      /* A = I + diag(scale) + misalignment (accel: used by the size effect) */
  double scale_asym[3];    /* a, dimensionless */
  double bias_drift[3];    /* d: rad/s^2 (gyro), m/s^3 (accel); t from the session's start */
};

struct sinscal_imu_terms {
  struct sinscal_triad_terms gyro;
  struct sinscal_triad_terms accel;
  double gyro_g_sensitivity[3][3]; /* G[i][j]: gyro i per specific force along j, rad/s per m/s^2 */
  double accel_k2[3];              /* 1/(m/s^2) */
  double accel_lever_arm[3][3];    /* [i]: r_i, accelerometer i's proof mass, m */
  double time_delay;               /* tau, s: accelerometers late is positive */
};

struct sinscal_imu_calibration {
  struct sinscal_imu_terms value;
  struct sinscal_imu_terms sigma;
};

)";
  h += "static const struct sinscal_imu_calibration sinscal_calibration = {\n  .value = " +
       c_terms(e.model, false) + ",\n  .sigma = " + c_terms(e.sigma, true) + "};\n\n";
  h += "#endif /* SINSCAL_IMU_CALIBRATION_H */\n";
  return h;
}

// The coefficients of a result read (and checked) by read_result_file into the export's models.
std::vector<std::string> take_coefficients(const ResultFile& r, FirmwareExport& e) {
  std::vector<std::string> present;
  for (const auto& [name, c] : r.coefficients) {
    if (c.fixed_by_convention)
      e.fixed_by_convention.push_back(name);
    else if (!c.observable)
      e.unobservable.push_back(name);
    e.model.set(name, c.fixed_by_convention || !c.observable ? 0.0 : c.value);
    e.sigma.set(name, c.sigma.value_or(0.0));
    present.push_back(name);
  }
  return present;
}

// The export of a result file `path` read by read_result_file.
FirmwareExport export_of(const std::string& path, const ResultFile& r,
                         const FirmwareExportOptions& options) {
  const nlohmann::json& j = r.json;
  if (!j.contains("method") || !j["method"].is_object() || !j["method"].contains("name") ||
      !j["method"]["name"].is_string())
    fail(path, j.contains("note")
                   ? "a truth file (simulate's), not a calibration result: export takes the "
                     "result of calibrate"
                   : "not a calibration result (no \"method\" section naming the method)");
  FirmwareExport e;
  e.source_file = path;
  std::error_code ec;
  e.source_bytes = std::filesystem::file_size(path, ec);
  e.method = j["method"]["name"].get<std::string>();
  body_frame_of(j["method"], e);
  e.misalignment_frame = r.misalignment_frame;
  const std::vector<std::string> present = take_coefficients(r, e);
  // Families whole or absent; the base ones required.
  std::vector<std::string> missing;
  for (const auto& f : coefficient_families()) {
    std::vector<std::string> lacking;
    for (int k = 0; k < f.size(); ++k)
      if (std::find(present.begin(), present.end(), f.coefficient_name(k)) == present.end())
        lacking.push_back(f.coefficient_name(k));
    if (lacking.size() == static_cast<std::size_t>(f.size()) && !f.base) continue;
    missing.insert(missing.end(), lacking.begin(), lacking.end());
    e.families.push_back(f.name);
  }
  // Thermal families: zero ones (a model written whole) add nothing; any other is refused.
  std::vector<std::string> thermal;
  for (const auto& f : e.families) {
    const CoefficientFamily& info = coefficient_family_info(f);
    if (!info.thermal()) continue;
    for (int k = 0; k < info.size(); ++k)
      if (info.value(e.model, k) != 0.0) {
        thermal.push_back(f);
        break;
      }
  }
  e.families.erase(
      std::remove_if(e.families.begin(), e.families.end(),
                     [](const std::string& f) { return coefficient_family_info(f).thermal(); }),
      e.families.end());
  if (!thermal.empty())
    fail(path, "thermal coefficients (" + joined(thermal) +
                   "): the export does not carry a temperature compensation yet; the thermal "
                   "result's thermal_table.csv gives each coefficient on a temperature grid");
  if (!missing.empty())
    fail(path, "coefficients missing (" + joined(missing) +
                   "): a firmware correction needs every coefficient of the base 24 and of each "
                   "extended family the result has");
  // Order of the lists: the catalog's.
  auto catalog_order = [](std::vector<std::string>& names) {
    std::vector<std::string> sorted;
    for (const auto& info : coefficient_catalog())
      if (std::find(names.begin(), names.end(), info.name) != names.end())
        sorted.push_back(info.name);
    names = sorted;
  };
  catalog_order(e.fixed_by_convention);
  catalog_order(e.unobservable);
  if (e.has("accel.lever_arm")) {
    e.reference_point =
        "the IMU reference point of the calibration (on a table with zero velocity while "
        "turning: the intersection of the table's axes); lever_arm row i is accelerometer i's "
        "proof mass relative to it";
    for (const char* axis : {"x", "y", "z"})
      if (std::find(e.fixed_by_convention.begin(), e.fixed_by_convention.end(),
                    std::string("accel.lever_arm.") + axis + ".x") != e.fixed_by_convention.end())
        e.reference_point = std::string("the proof mass of the ") + axis +
                            " accelerometer (the result's lever-arm reference: its lever arm is "
                            "zero by convention, the others are relative to it)";
  }

  const std::vector<std::string> verdicts = failed_verdicts(j);
  if (!verdicts.empty() && !options.force)
    fail(path, "the calibration failed its own checks: " + joined(verdicts) +
                   "; a firmware must not apply it (--force exports it anyway)");
  e.warnings = verdicts;
  for (const auto& f : r.forced)
    e.warnings.push_back("implausible coefficient exported as given: " + f);
  if (!e.unobservable.empty()) {
    if (!options.force)
      fail(path, std::to_string(e.unobservable.size()) +
                     " coefficients are not determined by the data (\"observable\": false): " +
                     joined(e.unobservable) +
                     "; a firmware needs a value for each (calibrate with a plan that observes "
                     "them, or --force exports them as zero, listed in the export)");
    e.warnings.push_back("coefficients not determined by the data exported as zero: " +
                         joined(e.unobservable));
  }
  return e;
}

}  // namespace

bool FirmwareExport::has(const std::string& family) const {
  return std::find(families.begin(), families.end(), family) != families.end();
}

FirmwareExport read_result_for_export(const std::string& path,
                                      const FirmwareExportOptions& options) {
  const ResultFile r = read_result_file(path, options.force);
  try {
    return export_of(path, r, options);
  } catch (const nlohmann::json::exception& x) {  // a field of the wrong type
    fail(path, std::string("not a sinscal result file (") + x.what() + ")");
  }
}

ExportFormat export_format_from_name(const std::string& name) {
  if (name == "json") return ExportFormat::Json;
  if (name == "yaml") return ExportFormat::Yaml;
  if (name == "c-header") return ExportFormat::CHeader;
  throw std::invalid_argument("export format must be json | yaml | c-header, not '" + name + "'");
}

std::vector<std::string> export_formula(const FirmwareExport& e) {
  const bool asym_a = e.has("accel.scale_asym"), k2 = e.has("accel.k2");
  const bool drift_a = e.has("accel.bias_drift"), drift_g = e.has("gyro.bias_drift");
  const bool asym_g = e.has("gyro.scale_asym"), g_sens = e.has("gyro.g_sensitivity");
  const bool lever = e.has("accel.lever_arm"), delay = e.has("time_delay");
  std::vector<std::string> f;
  f.push_back(
      "inputs: raw gyro output y_g (rad/s) and accelerometer output y_a (m/s^2) of one "
      "sample, body axes, as the calibrated log gave them to sinscal (its columns converted "
      "to SI by the session's [log] units, scales and axis map); increments (rad, m/s over "
      "the interval dt): divide by dt first, multiply the results by dt");
  f.push_back(
      "C = correction_matrix = A^-1, A = model_matrix = I + diag(scale) + misalignment; "
      ".* and |.| per component");
  if (drift_a || drift_g)
    f.push_back(
        "t = time since the start of the calibration session (s; increments: the "
        "middle of their interval): the bias drift was measured over that session; "
        "applying it later extrapolates it");
  if (delay)
    f.push_back(
        "0. time delay: the accelerometers are late by tau (time_delay): use as y_a of "
        "sample k the accelerometer output at k + tau / dt, linearly interpolated between "
        "the two samples around it (one sample of latency); error at most tau (dt - tau) "
        "/ 2 |d2f/dt2|");
  std::string u_a = "y_a - b_a";
  if (drift_a) u_a += " - d_a t";
  // Gyros first: the size effect needs omega; the g-sensitivity takes the accelerometers'
  // linear estimate f0 (the terms it leaves out are second order in G).
  std::string u_g = "y_g - b_g";
  if (drift_g) u_g += " - d_g t";
  if (g_sens) u_g += " - G f0";
  const std::string f0 = g_sens ? "f0 = C_a (" + u_a + "); " : "";
  if (asym_g)
    f.push_back("1. gyros: " + f0 + "u_g = " + u_g +
                "; v_g = C_g u_g; omega_ib_b = C_g (u_g - a_g .* |v_g|)");
  else
    f.push_back("1. gyros: " + f0 + "omega_ib_b = C_g (" + u_g + ")");
  if (lever) {
    f.push_back(
        "2. size effect: omega_dot = rate of change of omega_ib_b (central difference "
        "(omega[k+1] - omega[k-1]) / (2 dt)); s_i = A_a(i,:) . (omega_dot x r_i + omega_ib_b x "
        "(omega_ib_b x r_i)), r_i = lever_arm row i");
    u_a += " - s";
  } else {
    f.push_back("2. size effect: none (no lever arms in the result)");
  }
  if (asym_a || k2) {
    std::string n;
    if (asym_a) n += " - a_a .* |v_a|";
    if (k2) n += " - k2 .* v_a .* v_a";
    f.push_back("3. accelerometers: u_a = " + u_a + "; v_a = C_a u_a; f_ib_b = C_a (u_a" + n + ")");
  } else {
    f.push_back("3. accelerometers: f_ib_b = C_a (" + u_a + ")");
  }
  if (asym_a || k2 || asym_g)
    f.push_back(
        "the nonlinear terms use the linear estimate v (first order): error per axis at "
        "most (|a| + 2 |k2| |x|) (|a| |x| + |k2| x^2), stated under accuracy");
  if (g_sens)
    f.push_back(
        "G f0 leaves out what f0 lacks (the accelerometers' nonlinear terms and size effect): "
        "error |G| |f_ib_b - f0| (second order)");
  return f;
}

std::string render_export(const FirmwareExport& e, ExportFormat format) {
  switch (format) {
    case ExportFormat::Json:
      return document(e).dump(2) + "\n";
    case ExportFormat::Yaml: {
      std::string out =
          "# sinscal firmware export (YAML 1.2; every number is a float in SI units).\n"
          "# The fields are those of the JSON export (docs/formats.md \"Firmware export\"):\n"
          "# correction_matrix C = A^-1 and bias b per triad, extended terms as listed in "
          "terms.\n# Formula, in the order the firmware computes it:\n";
      for (const auto& line : export_formula(e)) out += "#   " + line + "\n";
      yaml_mapping(document(e), 0, out);
      return out;
    }
    case ExportFormat::CHeader:
      return c_header(e);
  }
  throw std::logic_error("render_export: unknown format");
}

}  // namespace sinscal
