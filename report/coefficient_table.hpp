// The coefficient table as the terminal and the certificate show it: one row per coefficient in
// the catalog's order, the figures in the result's display units (docs/conventions.md), formatted
// once here.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "report/result.hpp"

namespace sinscal {

struct CoefficientRow {
  enum class Kind { Estimated, FixedByConvention, Unobservable };
  std::string name;    // "gyro.bias.x"
  std::string family;  // "gyro.bias"
  std::string unit;    // "deg/h"
  Kind kind = Kind::Estimated;
  std::string value;  // Estimated: the estimate's text; otherwise what stands instead of it
  std::string sigma;  // Estimated: the sigma's text; otherwise empty
  // Against a truth (simulations), when it has the coefficient:
  std::optional<std::string> truth;
  std::optional<std::string> error;             // Estimated only
  std::optional<std::string> error_over_sigma;  // Estimated only
};

/// A coefficient's figure as every table shows it ("%.4f").
std::string coefficient_number(double v);

/// The rows of `coefficients` in catalog order; truth, error and error/sigma when `truth` has the
/// coefficient.
std::vector<CoefficientRow> coefficient_rows(const ResultCoefficients& coefficients,
                                             const ResultCoefficients& truth = {});

}  // namespace sinscal
