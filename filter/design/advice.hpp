// Plan design, identifiability advice: for each family a rotation plan does not observe (a
// coefficient not determined better than its prior, or part of a combination the plan cannot
// observe: the diagnosis's "not separable" and "ambiguous" sets), the one turn that, appended to
// the plan with a dwell, determines it best, found by a covariance pass per candidate turn.
#pragma once

#include <string>
#include <vector>

#include "filter/design/prediction.hpp"

namespace sinscal {

struct SeparationAdvice {
  std::string family;
  double sigma_before = 0.0;  // SI: the family's worst predicted sigma on the plan
  double prior = 0.0;         // SI: its prior sigma
  std::string turn;           // the turn to append, e.g. "+y 180 deg, then 20 s at rest"
  double sigma_after = 0.0;   // SI: the family's worst sigma with the turn appended
  bool observed_after = false;
};

/// Candidate turns: about each body axis, both signs, 90 and 180 deg, at 10 deg/s and the plan's
/// acceleration, then `dwell` s at rest. Empty for
/// orientation plans (the advice appends turns) or when every family is observed.
std::vector<SeparationAdvice> separation_advice(const Plan& plan, const CalibratorOptions& options,
                                                const PlanPrediction& prediction, double rate_hz,
                                                double dwell = 20.0);

}  // namespace sinscal
