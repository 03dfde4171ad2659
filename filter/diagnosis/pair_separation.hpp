// Whether a plan can tell two families apart at all (issue 33: the K2 / scale-asymmetry pair). On
// dwells with an axis at 0 and +-1 g, K2's f^2 and the asymmetry's |f| are one function (g^2 and
// g at +-g, 0 at 0), so only what else the plan gives (the turns' specific force, dwells with an
// axis between 0 and g) separates them. The answer comes from the information of the plan, not
// from one session: the covariance pass of the calibration's filter (design's prediction) over
// the plan's motion with both families estimated, their priors widened so that the data alone
// decide. docs/methods/diagnosis.md "Ambiguous sets".
#pragma once

#include <string>
#include <vector>

#include "filter/kalman/kalman_calibrator.hpp"
#include "rig/plan.hpp"

namespace sinscal {

/// What a plan gives a pair of families of the same sensor triad (components per axis).
struct PairSeparation {
  std::string plan;  // the plan's name
  std::string a, b;  // the families; `a` taken as the truth for the expected gap
  /// Per axis: the correlation of a's and b's estimates in the joint covariance (the dwells and
  /// the turns of the plan, the profile's noise).
  std::vector<double> correlations;
  double correlation = 0.0;  // the largest |correlation| of the axes
  /// The expected chi-square difference between the model with `a` and the model with `b` when
  /// the truth is `a` at `size`: size' (P_aa)^-1 size, P_aa a's block of the joint covariance
  /// (the information of a the data keep with b free). The noise moves it by about
  /// 2 sqrt(expected_gap). Over all the plan's data: the held-out turns' difference is at most it.
  double expected_gap = 0.0;
  /// The held-out turns' chi-square (diagnosis_kalman.hpp heldout_turns, the test that picks a
  /// member) on the plan without noise, the truth `a` at `size`, with the model extended with
  /// `a` and with `b`: their difference is the expected difference of a session's held-out
  /// turns (the noise adds about equally to both), the figure the pick needs above the chi-square
  /// quantile of one dof. Negative: not computed (no turns to hold out).
  double heldout_a = -1.0, heldout_b = -1.0;
  double heldout_gap() const { return heldout_b - heldout_a; }
  bool heldout() const { return heldout_a >= 0.0 && heldout_b >= 0.0; }
};

/// The widening of the pair's priors in the covariance pass (their information is then the
/// data's to within 1 / kPairPriorWidening^2).
constexpr double kPairPriorWidening = 100.0;

/// The pair's separation on `plan` with the filter's options `model` (the profile's noise,
/// families and priors, without its thermal families: the plan's ideal IMU has no temperature;
/// a and b switched on, their priors widened by kPairPriorWidening for the
/// correlation and expected_gap, as they are for the held-out turns' figures), `size`
/// a's coefficients (SI, catalog order of a's components); the held-out turns' figures only with
/// `heldout` (four more runs of the filter). Throws std::invalid_argument for
/// families of different numbers of components or a plan without a site.
PairSeparation pair_separation(const Plan& plan, const CalibratorOptions& model,
                               const std::string& a, const std::string& b,
                               const std::vector<double>& size, bool heldout = true,
                               double rate_hz = 20.0);

/// `plan` with every turn about a body axis split into two half turns of half its time (at least
/// the shortest the plan's acceleration allows), the turn's pause after each half (rot19's 90 deg
/// turns: dwells with two axes at 45 deg to gravity, where f^2 = g^2 / 2 and |f| = 0.707 g differ
/// in ratio from the axis-aligned dwells). The plan unchanged when it has no such turn (an
/// orientation plan).
Plan split_turns(const Plan& plan);

/// The statement of a pick: the pair not separable on `here` (correlation, expected gap against
/// `need`; `session_gap` this session's held-out difference, noise when at least `need`), and
/// what separates it: `other` (the split-turns plan) with its figures, or
/// for a plan without turns to split, dwells at 45 deg.
std::string separation_statement(const PairSeparation& here, const PairSeparation* other,
                                 double need, double session_gap);

}  // namespace sinscal
