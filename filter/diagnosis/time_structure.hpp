// Time against orientation on a table session's dwells (issue 33): a bias drift (a family whose
// term is a function of time) is a time structure of the residual, but a plan that visits each
// orientation once also orders its orientations in time, so an effect of the orientation (a
// product of the specific force) can take the drift's shape. Dwells that revisit an orientation
// later in time separate them: the difference of their equivalent inputs holds every effect of
// time (a drift, a temperature's course, the bias wander) and none of the orientation's (biases,
// scale factors, misalignments, products of the specific force: the same at the same attitude).
// docs/methods/diagnosis.md "Time or orientation".
#pragma once

#include <string>
#include <vector>

#include "filter/closed_form/closed_form.hpp"

namespace sinscal {

/// How a refused time family's residual is stated: the set the plan leaves open.
constexpr const char* kTimeOrOrientation = "unexplained: time or orientation";

/// Two dwells closer in attitude than this are one orientation visited twice (rad).
constexpr double kRevisitAngle = 0.5 * 3.14159265358979323846 / 180.0;

/// The revisits against the drift the dwells fitted: each orientation's consecutive visits
/// differenced (the differences' covariance from each dwell's and the bias wander between them),
/// the chi-square of the differences with the fitted drift's trend against without it. A drift
/// predicts its trend between the visits; an effect of the orientation that the drift absorbed
/// elsewhere predicts none. The statistic is in the differences' own scale where their residual
/// rejects the noise model (an excess the noise model does not hold is not a trend).
struct RevisitCheck {
  int pairs = 0;       // consecutive visits of one orientation
  int rows = 0;        // difference rows (the family's sensor's NED inputs estimated in both)
  double trend = 0.0;  // the fitted drift's trend over the differences, chi-square (whitened)
  /// The differences' chi-square with the fitted drift's trend minus without it, in their scale:
  /// negative where the revisits hold the trend, near `trend` where they hold none.
  double statistic = 0.0;
  double scale = 1.0;        // the differences' residual chi-square per dof (>= 1)
  double needed = 0.0;       // the chi-square quantile of 1 dof at 1 - alpha
  bool contradicts = false;  // statistic > needed: the revisits refuse the drift
  /// "9 revisits (27 rows): the drift's trend over them 14.2, with it their chi-square 12.3 more
  /// than without, 6.63 allowed"
  std::string text() const;
};

/// Whether `family` is a function of time alone (its term a drift: gyro.bias_drift,
/// accel.bias_drift).
bool is_time_family(const std::string& family);

/// The revisit check of the time family's `components` (catalog indices) at the dwells' fitted
/// `values` (SI) on the dwells `inputs` (`base`: the table's attitude error, the bias wander and
/// T0). pairs == 0: the plan revisits no orientation.
RevisitCheck revisit_check(const std::vector<EquivalentInputs>& inputs, const Site& site,
                           const Stage2Options& base, const std::vector<int>& components,
                           const Eigen::VectorXd& values, double alpha);

}  // namespace sinscal
