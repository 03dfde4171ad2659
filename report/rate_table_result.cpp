#include "report/rate_table_result.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "models/imu_error_model.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

// Name, unit and SI per unit of a coefficient: the catalog's, or the rate table's own terms.
CoefficientInfo info_of(const RateCoefficient& c) {
  if (!c.in_catalog) {
    if (c.name.rfind("gyro.k2.", 0) == 0)
      return {c.name, "ppm/(deg/s)", 1e-6 / units::deg, "gyro.k2"};
    if (c.name.rfind("gyro.cross_asym.", 0) == 0) return {c.name, "ppm", 1e-6, "gyro.cross_asym"};
    return {c.name, "ug/g^3", 1e-6 / (units::g0 * units::g0), "accel.k3"};
  }
  for (const auto& i : coefficient_catalog())
    if (i.name == c.name) return i;
  throw std::logic_error("rate-table result: no coefficient " + c.name);
}

}  // namespace

ResultCoefficients result_coefficients(const RateTableResult& r) {
  ResultCoefficients out;
  for (const auto& c : r.coefficients) {
    if (!c.in_catalog) continue;
    out[c.name] = result_coefficient(info_of(c), c.value, c.sigma);
  }
  return out;
}

nlohmann::ordered_json result_sections(const RateTableResult& r,
                                       const std::vector<RateSegment>& segments) {
  nlohmann::ordered_json extra = nlohmann::ordered_json::object(),
                         own = nlohmann::ordered_json::object(),
                         segs = nlohmann::ordered_json::array();
  for (const auto& c : r.coefficients) {
    if (c.in_catalog) continue;
    const CoefficientInfo info = info_of(c);
    own[c.name] = {{"value", c.value / info.si_per_unit},
                   {"sigma", c.sigma / info.si_per_unit},
                   {"unit", info.unit}};
  }
  for (std::size_t i = 0; i < segments.size() && i < r.means.size(); ++i) {
    const SegmentMean& m = r.means[i];
    const Eigen::Vector3d w = m.omega / units::deg, f = m.f;
    segs.push_back({{"label", segments[i].label},
                    {"kind", segments[i].kind == RateSegment::Kind::Static ? "static" : "rate"},
                    {"readings", {m.first, m.last}},
                    {"mean_rate_deg_s", {w.x(), w.y(), w.z()}},
                    {"mean_specific_force_mps2", {f.x(), f.y(), f.z()}}});
    if (i < r.residual_sigma.size()) {  // null where the segment has no row
      nlohmann::ordered_json z = nlohmann::ordered_json::array();
      for (int k = 0; k < 6; ++k)
        z.push_back(std::isfinite(r.residual_sigma[i](k))
                        ? nlohmann::ordered_json(r.residual_sigma[i](k))
                        : nlohmann::ordered_json());
      segs.back()["residual_sigma"] = z;
    }
  }
  nlohmann::ordered_json unsteady = nlohmann::ordered_json::array();
  for (const auto& u : r.unsteady) {
    const bool gyro = u.output < 3;
    const double per = gyro ? units::deg_per_s : 1e-3 * units::g0;
    unsteady.push_back({{"segment", u.segment + 1},
                        {"readings", {u.first, u.last}},
                        {"output", std::string(gyro ? "gyro." : "accel.") + "xyz"[u.output % 3]},
                        {"level_change", u.change / per},
                        {"unit", gyro ? "deg/s" : "mg"},
                        {"at_reading", u.at},
                        {"sigma", u.sigma},
                        {"quantile_sigma", u.quantile},
                        {"scatter_ratio", u.scatter_ratio},
                        {"others_chi2", u.others_chi2},
                        {"others_dof", u.others_dof},
                        {"others_quantile", u.others_quantile},
                        {"excluded", u.excluded},
                        {"statement", u.statement}});
  }
  extra["method"] = "rate-table";
  extra["rate_table"] = {{"chi2", r.chi2},
                         {"dof", r.dof},
                         {"static_segments", r.static_segments},
                         {"rate_segments", r.rate_segments},
                         {"terms_outside_the_catalog", own},
                         {"undetermined", r.undetermined},
                         {"segments", segs},
                         {"unsteady_rests", unsteady}};
  return extra;
}

std::string rate_table_text(const RateTableResult& r, const std::vector<RateSegment>& segments,
                            const ResultCoefficients& truth) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "%-26s %14s %12s  %-12s%s\n", "coefficient", "value", "sigma",
                "unit", truth.empty() ? "" : "  error/sigma");
  out += line;
  for (const auto& c : r.coefficients) {
    const CoefficientInfo info = info_of(c);
    const double v = c.value / info.si_per_unit, s = c.sigma / info.si_per_unit;
    std::snprintf(line, sizeof line, "%-26s %14.6g %12.4g  %-12s", c.name.c_str(), v, s,
                  info.unit.c_str());
    out += line;
    const auto t = truth.find(c.name);
    const double tv = t != truth.end() ? t->second.value : 0.0;
    if (!truth.empty() && (t != truth.end() || !c.in_catalog)) {
      std::snprintf(line, sizeof line, " %8.2f", (v - tv) / s);
      out += line;
    }
    out += "\n";
  }
  std::snprintf(line, sizeof line,
                "\n%zu static positions, %zu rate segments; chi2/dof %.3f (%d dof)\n",
                r.static_segments, r.rate_segments, r.dof > 0 ? r.chi2 / r.dof : 0.0, r.dof);
  out += line;
  if (r.dof > 0 && r.chi2 / r.dof > 3.0)
    out +=
        "The means scatter beyond their noise (chi2/dof above 3): the model or the plan does "
        "not describe the data (an effect outside the model, a table rate or attitude off its "
        "command); the sigmas understate the errors. The largest residual: " +
        largest_residual(r, segments) + ".\n";
  for (const auto& u : r.unsteady) out += "Rest with a level change: " + u.statement + ".\n";
  if (!r.undetermined.empty()) {
    out += "Not determined by these segments (not estimated):";
    for (const auto& u : r.undetermined) out += " " + u;
    out += "\n";
  }
  return out;
}

}  // namespace sinscal
