// Two calibration results side by side (sinscal compare): difference, difference over its sigma,
// relative difference, and the verdict against tolerances.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "report/result.hpp"

namespace sinscal {

/// One coefficient of two results side by side.
struct CoefficientComparison {
  std::string name, unit;
  std::optional<double> a, b;              // absent: not in that file, or not observable there
  std::optional<double> sigma_a, sigma_b;  //
  std::optional<double> z;                 // (a - b) / hypot(sigma_a, sigma_b), both estimated
  std::optional<double> relative;          // |a - b| / max(|a|, |b|) (0 when both are 0)
  std::optional<double> sigma_relative;    // the same for the sigmas
  std::string verdict;                     // why it disagrees (empty: agrees or not checked)
  bool disagrees = false;
};

struct CompareTolerances {
  std::optional<double> max_sigma;     // |z| above it disagrees
  std::optional<double> max_relative;  // a relative difference of value or sigma above it
};

/// Every coefficient of the catalog either result has, in catalog order, with its verdict: a
/// value on one side only disagrees when a tolerance is given, both unobservable agree. Throws
/// std::invalid_argument when the two results have no coefficient of the catalog in common.
std::vector<CoefficientComparison> compare_results(const ResultCoefficients& a,
                                                   const ResultCoefficients& b,
                                                   const CompareTolerances& tolerances = {});

}  // namespace sinscal
