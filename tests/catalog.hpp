#pragma once

#include <stdexcept>
#include <string>
#include <vector>

#include "models/imu_error_model.hpp"

namespace sinscal::test {

/// The catalog index of one coefficient ("gyro.bias.x"); coefficient_info throws
/// std::invalid_argument for an unknown name, which fails the calling test with the name.
inline int coefficient_index(const std::string& name) {
  return static_cast<int>(&coefficient_info(name) - coefficient_catalog().data());
}

/// The catalog indices of one family's coefficients, in catalog order; fails the calling test
/// (std::invalid_argument) for a family with none.
inline std::vector<int> family_coefficients(const std::string& family) {
  const auto& cat = coefficient_catalog();
  std::vector<int> out;
  for (std::size_t k = 0; k < cat.size(); ++k)
    if (cat[k].family == family) out.push_back(static_cast<int>(k));
  if (out.empty()) throw std::invalid_argument("no coefficient of family '" + family + "'");
  return out;
}

}  // namespace sinscal::test
