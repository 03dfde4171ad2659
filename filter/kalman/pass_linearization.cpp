#include "filter/kalman/pass_linearization.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "models/imu_error_model.hpp"

namespace sinscal {

namespace {

// The relative errors: scale factors (their asymmetries too) and misalignments (rad); not their
// temperature terms (gyro.scale_temp1 is per deg C), which a prefix would also match.
bool relative(const std::string& name) {
  const std::string family = name.substr(0, name.rfind('.'));
  for (const char* f : {"gyro.scale", "gyro.scale_asym", "gyro.misalignment", "accel.scale",
                        "accel.scale_asym", "accel.misalignment"})
    if (family == f) return true;
  return false;
}

// The triad whose relative errors multiply a coefficient's in the compensation
// x = (I + S + M)^-1 (y - b): 0 the gyros, 1 the accelerometers, 2 both (other terms).
int triad(const std::string& name) {
  if (name.rfind("gyro.", 0) == 0) return 0;
  if (name.rfind("accel.", 0) == 0) return 1;
  return 2;
}

}  // namespace

std::string PassLinearization::text() const {
  char buf[200];
  std::snprintf(buf, sizeof buf, "%s: %.3g sigma (%s changed by %.3g)", coefficient.c_str(), share,
                epsilon_coefficient.c_str(), epsilon);
  return buf;
}

PassLinearization pass_linearization(const std::vector<CoefficientEstimate>& estimates,
                                     const Eigen::VectorXd& estimate,
                                     const Eigen::VectorXd& point) {
  const auto& cat = coefficient_catalog();
  if (estimates.size() != cat.size() || estimate.size() != point.size() ||
      static_cast<std::size_t>(estimate.size()) != cat.size())
    throw std::invalid_argument("pass_linearization: estimates and models are not the catalog's");
  // The largest relative change per triad (0 gyros, 1 accelerometers, 2 either: the other terms).
  double epsilon[3] = {0.0, 0.0, 0.0};
  std::string which[3];
  for (std::size_t c = 0; c < cat.size(); ++c) {
    const double change = std::abs(estimate(c) - point(c));
    if (!estimates[c].observed() || !relative(cat[c].name)) continue;
    for (const int k : {triad(cat[c].name), 2})
      if (change > epsilon[k]) {
        epsilon[k] = change;
        which[k] = cat[c].name;
      }
  }
  PassLinearization p;
  for (std::size_t c = 0; c < cat.size(); ++c) {
    if (!estimates[c].observed() || !(estimates[c].sigma > 0.0)) continue;
    const int k = triad(cat[c].name);
    const double share = epsilon[k] * std::abs(estimate(c) - point(c)) / estimates[c].sigma;
    if (share > p.share) {
      p.share = share;
      p.coefficient = cat[c].name;
      p.epsilon = epsilon[k];
      p.epsilon_coefficient = which[k];
    }
  }
  return p;
}

}  // namespace sinscal
