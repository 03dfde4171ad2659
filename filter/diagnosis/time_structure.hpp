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

/// The time family's components fitted to the revisits alone: each orientation's consecutive
/// visits differenced (the differences' covariance from each dwell's and the bias wander between
/// them), the components' chi-square from those differences in the differences' own residual
/// scale (their chi-square per dof after the fit, where above 1: an excess the noise model does
/// not hold, such as timing jitter on the vertical accelerometer, is not a trend).
struct RevisitCheck {
  int pairs = 0;           // consecutive visits of one orientation
  int rows = 0;            // difference rows (the family's sensor's NED inputs estimated in both)
  int dof = 0;             // the family's components the differences determine
  double statistic = 0.0;  // the components' chi-square from the differences, in their scale
  double scale = 1.0;      // the differences' residual chi-square per dof after the fit (>= 1)
  double needed = 0.0;     // the chi-square quantile of dof at 1 - alpha
  bool confirms = false;   // statistic >= needed
  /// "12 revisits (36 rows): the drift's chi-square from them 3.1 (scale x2.4), 11.3 needed"
  std::string text() const;
};

/// Whether `family` is a function of time alone (its term a drift: gyro.bias_drift,
/// accel.bias_drift).
bool is_time_family(const std::string& family);

/// The revisit check of the time family's `components` (catalog indices) on the dwells `inputs`
/// (`base`: the table's attitude error, the bias wander and T0). pairs == 0: the plan revisits no
/// orientation (dof 0: the revisits do not determine the components).
RevisitCheck revisit_check(const std::vector<EquivalentInputs>& inputs, const Site& site,
                           const Stage2Options& base, const std::vector<int>& components,
                           double alpha);

}  // namespace sinscal
