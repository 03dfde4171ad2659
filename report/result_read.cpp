// The one reader of result and truth files (report/result.hpp read_result_file): the structure,
// and every coefficient against its family's physical range (models/coefficient_families.hpp),
// before anything leaves the tool (export, report, compare).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "report/result.hpp"

namespace sinscal {

namespace {

using Json = nlohmann::json;

[[noreturn]] void fail(const std::string& path, const std::string& cause) {
  throw std::runtime_error(path + ": " + cause);
}

std::string number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.6g", v);
  return b;
}

// A boolean field, false when absent; anything else is refused.
bool flag(const std::string& path, const std::string& name, const Json& e, const char* key,
          bool absent) {
  if (!e.contains(key)) return absent;
  if (!e[key].is_boolean())
    fail(path, "coefficient '" + name + "': \"" + key + "\" must be true or false");
  return e[key].get<bool>();
}

// A number field that must be finite (absent: nullopt).
std::optional<double> finite(const Json& e, const char* key) {
  if (!e.contains(key)) return std::nullopt;
  if (!e[key].is_number() || !std::isfinite(e[key].get<double>()))
    return std::numeric_limits<double>::quiet_NaN();
  return e[key].get<double>();
}

const CoefficientInfo& known_coefficient(const std::string& path, const std::string& name) {
  try {
    return coefficient_info(name);
  } catch (const std::invalid_argument&) {
    fail(path, "unknown coefficient '" + name +
                   "' (coefficient names: docs/conventions.md; a mistyped name is never skipped)");
  }
}

// The structure of one coefficient (malformed ones are refused, whatever --force says).
ResultCoefficient read_coefficient(const std::string& path, const std::string& name,
                                   const Json& e) {
  const CoefficientInfo& info = known_coefficient(path, name);
  if (!e.is_object()) fail(path, "coefficient '" + name + "' is not an object");
  ResultCoefficient r;
  r.observable = flag(path, name, e, "observable", true);
  r.fixed_by_convention = flag(path, name, e, "fixed_by_convention", false);
  r.unit = info.unit;
  if (e.contains("unit")) {
    if (!e["unit"].is_string() || e["unit"].get<std::string>() != info.unit)
      fail(path, "coefficient '" + name + "' is in '" +
                     (e["unit"].is_string() ? e["unit"].get<std::string>() : e["unit"].dump()) +
                     "', results give it in '" + info.unit + "' (docs/conventions.md)");
  }
  const std::optional<double> value = finite(e, "value");
  if (r.observable && !r.fixed_by_convention && !(value && std::isfinite(*value)))
    fail(path, "coefficient '" + name + "' has no finite value");
  if (value && !std::isfinite(*value))
    fail(path, "coefficient '" + name + "': the value is not a finite number");
  if (value && r.observable && !r.fixed_by_convention) r.value = *value;
  r.sigma = finite(e, "sigma");
  if (r.sigma && !(std::isfinite(*r.sigma) && *r.sigma >= 0.0))
    fail(path, "coefficient '" + name + "': a sigma must be a finite number > 0");
  return r;
}

// The misalignment frame a result states, or its method's and mode's default (results written
// before the field); a stated frame other than table or triad is refused.
std::string misalignment_frame_of(const std::string& path, const Json& j) {
  if (j.contains("misalignment_frame")) {
    const Json& f = j["misalignment_frame"];
    if (!f.is_string() || (f.get<std::string>() != "table" && f.get<std::string>() != "triad"))
      fail(path, "\"misalignment_frame\" must be \"table\" or \"triad\", not " + f.dump());
    return f.get<std::string>();
  }
  if (!j.contains("method") || !j["method"].is_object()) return "";
  const Json& m = j["method"];
  auto text = [&](const char* key) {
    return m.contains(key) && m[key].is_string() ? m[key].get<std::string>() : std::string();
  };
  if (text("body_frame") == "accelerometer triad") return "triad";
  if (text("body_frame") == "table") return "table";
  const std::string name = text("name");
  if (name == "kf") return text("attitude") == "none" ? "triad" : "table";
  if (name == "table-free") return "triad";
  if (name == "closed-form") return "table";
  return "";
}

}  // namespace

std::string check_plausible(const std::string& name, const ResultCoefficient& c,
                            bool sigma_required) {
  const CoefficientInfo& info = coefficient_info(name);
  const CoefficientFamily& family = coefficient_family_info(info.family);
  const double range = family.plausible_max / info.si_per_unit;
  const std::string beyond = " is beyond the physical range of " + family.name +
                             " (|x| <= " + number(range) + " " + info.unit +
                             "): not a calibration (a wrong unit or scale, a broken estimate)";
  if (c.fixed_by_convention) return "";
  const bool estimated = c.observable;
  if (estimated && std::abs(c.value) > range)
    return "value " + number(c.value) + " " + info.unit + beyond;
  if (c.sigma && *c.sigma > range) return "sigma " + number(*c.sigma) + " " + info.unit + beyond;
  if (estimated && c.sigma && *c.sigma == 0.0)
    return "sigma 0: no estimate is exact (a calibration result's sigma is > 0)";
  if (estimated && sigma_required && !c.sigma)
    return "no sigma: a calibration result gives every estimate's 1-sigma";
  return "";
}

namespace {
ResultFile read(const std::string& path, bool force, bool force_hint) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open");
  ResultFile f;
  try {
    f.json = Json::parse(in);
  } catch (const Json::exception& x) {
    fail(path, std::string("not a sinscal result file (not JSON: ") + x.what() + ")");
  }
  if (!f.json.is_object() || !f.json.contains("coefficients") ||
      !f.json["coefficients"].is_object())
    fail(path, "not a sinscal result file (no \"coefficients\" object)");
  // A calibration result names its method; a truth file (simulate's) has no sigmas.
  const bool result = f.json.contains("method");
  f.misalignment_frame = misalignment_frame_of(path, f.json);
  for (const auto& [name, e] : f.json["coefficients"].items()) {
    const ResultCoefficient c = read_coefficient(path, name, e);
    const std::string why = check_plausible(name, c, result);
    if (!why.empty() && !force)
      fail(path, "coefficient '" + name + "': " + why +
                     (force_hint ? "; --force uses it anyway, noted in the output" : ""));
    if (!why.empty()) f.forced.push_back(name + ": " + why);
    f.coefficients[name] = c;
  }
  return f;
}

}  // namespace

ResultFile read_result_file(const std::string& path, bool force) { return read(path, force, true); }

ResultCoefficients read_result_json(const std::string& path) {
  return read(path, false, false).coefficients;
}

}  // namespace sinscal
