// How far a pass of the Kalman filter ran from the model it linearized about (issue 34, consumer
// MEMS: scale factors up to 5 %, misalignments up to 1 deg). The filter's error model is linear
// in the coefficients' errors about its starting model; the products of two errors it neglects
// (a scale error times a misalignment, a scale error times a bias, of one triad) are of the size
// of the triad's largest relative error (scale, misalignment) times each coefficient's own
// error. Where that reaches a
// share of the coefficient's sigma the pass's estimate is biased by it (noise-free, one pass on a
// consumer unit on seed8: up to 1.7 sigma; a second pass from the first's estimates: 0.00), and
// another pass, linearized about the estimate, is needed. docs/methods/kalman-filter.md, "Passes".
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "filter/kalman/kalman_calibrator.hpp"

namespace sinscal {

/// The share of a coefficient's sigma the neglected second-order term may reach: at a tenth of a
/// sigma the estimate's error distribution is the noise's (a 4-sigma tail grows by at most 50 %).
constexpr double kLinearizationShare = 0.1;
/// Passes of the automatic mode (`--passes 0`) at most.
constexpr int kMaxAutomaticPasses = 3;

struct PassLinearization {
  /// The largest relative error of the worst coefficient's triad (a scale factor's or a
  /// misalignment's change from the model the pass linearized about) and its coefficient.
  double epsilon = 0.0;
  std::string epsilon_coefficient;
  /// The largest epsilon * |change| / sigma over the observed coefficients (epsilon of their own
  /// triad: the compensation x = (I + S + M)^-1 (y - b) multiplies a triad's errors together),
  /// and which.
  double share = 0.0;
  std::string coefficient;
  bool within() const { return share <= kLinearizationShare; }
  /// "gyro.misalignment.xy: 4.3 sigma (gyro.scale.x changed by 0.0512)"
  std::string text() const;
};

/// The pass's estimates (catalog order; sigmas and observed() as the filter gives them), its
/// final coefficients and the coefficients it started from (both SI, catalog order:
/// ImuErrorModel::vector()).
PassLinearization pass_linearization(const std::vector<CoefficientEstimate>& estimates,
                                     const Eigen::VectorXd& estimate, const Eigen::VectorXd& point);

}  // namespace sinscal
