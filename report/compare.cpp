#include "report/compare.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "models/imu_error_model.hpp"

namespace sinscal {

namespace {
double relative(double x, double y) {
  const double scale = std::max(std::abs(x), std::abs(y));
  return scale > 0.0 ? std::abs(x - y) / scale : 0.0;
}
std::optional<double> value(const ResultCoefficients& r, const std::string& name) {
  const auto it = r.find(name);
  if (it == r.end() || !it->second.observable) return std::nullopt;
  return it->second.fixed_by_convention ? 0.0 : it->second.value;
}
std::optional<double> sigma(const ResultCoefficients& r, const std::string& name) {
  const auto it = r.find(name);
  return it == r.end() ? std::nullopt : it->second.sigma;
}
std::string number(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", v);
  return b;
}

void judge(CoefficientComparison& c, const CompareTolerances& t) {
  const bool checking = t.max_sigma || t.max_relative;
  if (!c.a || !c.b) {
    c.verdict = !c.a && !c.b ? "in neither as a value" : !c.a ? "no value in A" : "no value in B";
    // Both unobservable (sigma only) is agreement; a value on one side only is not.
    c.disagrees = checking && (c.a || c.b);
    return;
  }
  if (t.max_sigma && c.z && std::abs(*c.z) > *t.max_sigma) {
    c.verdict += " |z| > " + number(*t.max_sigma);
    c.disagrees = true;
  }
  if (t.max_relative && (*c.relative > *t.max_relative ||
                         (c.sigma_relative && *c.sigma_relative > *t.max_relative))) {
    c.verdict += " relative > " + number(*t.max_relative);
    c.disagrees = true;
  }
}
}  // namespace

std::vector<CoefficientComparison> compare_results(const ResultCoefficients& a,
                                                   const ResultCoefficients& b,
                                                   const CompareTolerances& tolerances) {
  if ((tolerances.max_sigma && !(*tolerances.max_sigma >= 0.0)) ||
      (tolerances.max_relative && !(*tolerances.max_relative >= 0.0)))
    throw std::invalid_argument("tolerances must be numbers >= 0");
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
    judge(c, tolerances);
    out.push_back(c);
  }
  bool common = false;
  for (const auto& c : out) common = common || (a.count(c.name) && b.count(c.name));
  if (!common)
    throw std::runtime_error(
        "no known coefficient in both results (no coefficient name of sinscal's catalog): nothing "
        "to compare");
  return out;
}

}  // namespace sinscal
