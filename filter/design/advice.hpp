// Plan design, identifiability advice: for each family a plan does not observe (a coefficient not
// determined better than its prior, or part of a combination the plan cannot observe: the
// diagnosis's "not separable" and "ambiguous" sets), what to append to the plan to determine it
// best, found by a covariance pass per candidate: a turn about a body axis with a dwell (rotation
// plans), or an orientation with a body axis up and another north (orientation plans).
// docs/methods/design.md "Identifiability advice".
#pragma once

#include <string>
#include <vector>

#include "filter/design/prediction.hpp"

namespace sinscal {

struct SeparationAdvice {
  std::string family;
  double sigma_before = 0.0;  // SI: the family's worst predicted sigma on the plan
  double prior = 0.0;         // SI: its prior sigma
  /// What to append: "turn" (rotation plans) or "orientation" (orientation plans).
  std::string kind;
  /// Its text ("" when no candidate improves the family), e.g. "+y 180 deg, then 20 s at rest",
  /// or "body +x up, +y north (heading 0, pitch 90, roll 0 deg), 180 s".
  std::string turn;
  double sigma_after = 0.0;  // SI: the family's worst sigma with the turn appended
  bool observed_after = false;
};

/// Rotation plans: candidate turns about each body axis, both signs, 90 and 180 deg, at 10 deg/s
/// and the plan's acceleration, then `dwell` s at rest. Orientation plans: the 24 orientations
/// with a body axis up and another north that the plan's table reaches, each with the plan's
/// median dwell (`dwell` unused). Empty when every family is observed.
std::vector<SeparationAdvice> separation_advice(const Plan& plan, const CalibratorOptions& options,
                                                const PlanPrediction& prediction, double rate_hz,
                                                double dwell = 20.0);

}  // namespace sinscal
