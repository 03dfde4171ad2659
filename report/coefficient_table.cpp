#include "report/coefficient_table.hpp"

#include <cstdio>

#include "models/coefficient_families.hpp"

namespace sinscal {

std::string coefficient_number(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.4f", v);
  return b;
}

std::vector<CoefficientRow> coefficient_rows(const ResultCoefficients& coefficients,
                                             const ResultCoefficients& truth) {
  std::vector<CoefficientRow> rows;
  for (const auto& info : coefficient_catalog()) {
    const auto it = coefficients.find(info.name);
    if (it == coefficients.end()) continue;
    const ResultCoefficient& c = it->second;
    CoefficientRow r;
    r.name = info.name;
    r.family = info.family;
    r.unit = c.unit;
    if (c.fixed_by_convention) {
      r.kind = CoefficientRow::Kind::FixedByConvention;
      r.value = "0 (convention)";
    } else if (!c.observable || !c.sigma) {
      r.kind = CoefficientRow::Kind::Unobservable;
      r.value = c.observable ? "no sigma" : "unobservable";
    } else {
      r.value = coefficient_number(c.value);
      r.sigma = coefficient_number(*c.sigma);
    }
    const auto t = truth.find(info.name);
    if (t != truth.end()) {
      r.truth = coefficient_number(t->second.value);
      if (r.kind == CoefficientRow::Kind::Estimated) {
        const double e = c.value - t->second.value;
        r.error = coefficient_number(e);
        char b[32];
        std::snprintf(b, sizeof b, "%.2f", e / *c.sigma);
        r.error_over_sigma = b;
      }
    }
    rows.push_back(r);
  }
  return rows;
}

}  // namespace sinscal
