// Model discovery on a table session's static dwells: what the calibrated model fails to explain,
// which missing effect explains it, and what adding it gains (../shared/model-discovery.md).
//
// The residual is the closed form's stage-2 residual: each dwell's equivalent inputs (measured,
// from stage 1) minus those the calibrated error model predicts at the dwell's attitude (the same
// error-model Jacobian the simulator's error model linearizes to; exact for the static dwells,
// whose inputs are constant). The candidates are the extended families of the one family table
// (models/coefficient_families.hpp), component by component: a new family there is a new
// candidate here. Each candidate is refitted; the most significant is named when its likelihood
// ratio is significant at the stated family-wise level (Bonferroni over the round's candidates)
// and no other family's candidate explains the same residual; then the next round tests the rest
// against the extended model. The leave-one-dwell-out prediction error is reported beside it.
// A candidate whose signature lies in the span of the model on this plan is "not separable",
// with the plan feature that would separate it; two candidates the plan cannot tell apart are
// reported as ambiguous, neither named. Effects that act only while the table turns (inner lever
// arms, time delay, gyro scale asymmetry) have no static signature: on the static dwells they are
// reported as not separable, never guessed.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "filter/closed_form.hpp"

namespace sinscal {

struct DiagnosisOptions {
  /// Family-wise false-alarm level of one round of tests (Bonferroni over the candidates).
  double alpha = 0.01;
  /// A candidate component is separable when the plan shrinks its sigma (given the base
  /// coefficients) below its family's default prior divided by this.
  double separable_ratio = 3.0;
  int max_findings = 6;
  /// Candidate families (each of their components is a candidate); empty: every extended family
  /// of the family table.
  std::vector<std::string> candidates;
};

/// Residuals of one dwell, measured minus model: df_n (m/s^2) and dw_n (rad/s), NED.
struct DwellResidual {
  int dwell = 0;
  std::string label;
  Eigen::Matrix<double, 6, 1> before = Eigen::Matrix<double, 6, 1>::Zero();  // initial model
  Eigen::Matrix<double, 6, 1> after = Eigen::Matrix<double, 6, 1>::Zero();   // final model
  Eigen::Matrix<double, 6, 1> sigma = Eigen::Matrix<double, 6, 1>::Zero();   // of the inputs
};

/// Fit figures of one parameter set.
struct FitFigures {
  Stage2Result fit;
  double chi2 = 0.0;           // whitened residual sum of squares
  double accel_rms = 0.0;      // m/s^2: RMS of the accelerometer residuals over dwells, axes
  double gyro_rms = 0.0;       // rad/s
  double heldout = 0.0;        // RMS of the leave-one-dwell-out prediction error, in sigmas
  double heldout_accel = 0.0;  // m/s^2, same in the sensor's units
  double heldout_gyro = 0.0;   // rad/s
  int heldout_dwells = 0;      // dwells whose prediction the others determine
  /// Hand-held sessions (filter/handheld_diagnosis.hpp): accel_rms, gyro_rms are the poses'
  /// gravity-magnitude residual and rate at rest; these the turns' (rad), 0 for table sessions.
  double turn_rms = 0.0;
  double heldout_turn = 0.0;
  double log_likelihood = 0.0;  // -chi2/2 (constant terms dropped)
  double bic = 0.0;             // chi2 + rank log(inputs)
};

/// One candidate (a component of an extended family) tested against the current model.
struct CandidateTest {
  std::string family;
  std::vector<int> separable;  // catalog indices of the components the plan separates
  std::vector<int> aliased;    // those it does not
  std::string aliased_with;    // the base combination an aliased component hides in
  std::string separated_by;    // the plan feature that would separate it (family table)
  int dof = 0;                 // extra parameters fitted (rank increase)
  /// chi2_0 - chi2_1 (test "chi2": the noise model holds), or that over chi2_1/dof_1 (test "F":
  /// the fit's residual rejects the noise model, which is rescaled by it).
  double likelihood_ratio = 0.0;
  std::string test;
  double p_value = 1.0;    // upper tail: chi-square(dof), or F(dof, dof_1) of likelihood_ratio/dof
  double threshold = 0.0;  // p below this is significant (alpha / candidates)
  bool significant = false;
  bool named = false;  // the most significant, and no other family explains it
  /// Other families' candidates that explain the same residual (each insignificant once the
  /// other is in the model): the plan cannot tell them apart.
  std::vector<CandidateTest> ambiguous_with;
  FitFigures with;                // the fit with the candidate
  double base_shift_sigma = 0.0;  // largest move of a base coefficient, in its sigma
};

struct DiagnosisReport {
  std::vector<int> initial_parameters;  // catalog indices
  FitFigures initial;
  std::vector<std::vector<CandidateTest>> rounds;  // every candidate of every round
  std::vector<CandidateTest> findings;             // named, in order
  std::vector<CandidateTest> not_separable;        // components the plan hides, per family
  std::vector<CandidateTest> ambiguous;  // the round's best, which another family explains too
  std::vector<int> final_parameters;
  FitFigures final_fit;
  std::vector<DwellResidual> residuals;
  int inputs = 0;  // equivalent inputs over all dwells
  double alpha = 0.0;
};

/// The statistics shared by the table and hand-held diagnoses.
namespace diagnosis_detail {
/// The test of a nested extension `c.with` of `now` (c.dof extra parameters): the chi-square test
/// of the likelihood ratio while the noise model holds, else the F test.
void test_statistic(const FitFigures& now, CandidateTest& c);
/// Largest move of the first base.size() coefficients between two fits, in their sigmas before.
double largest_shift(const FitFigures& before, const FitFigures& after,
                     const std::vector<int>& base);
/// Marks the round's significant candidates (Bonferroni) and returns the most significant one,
/// or nullptr.
CandidateTest* best_of(std::vector<CandidateTest>& round, double alpha);
/// The most significant candidate with those that explain the residual as well; named unless
/// another family's does.
CandidateTest* choose(std::vector<CandidateTest>& round, double alpha);
/// What could not be separated (aliased components), one entry per family.
std::vector<CandidateTest> not_separable(const std::vector<CandidateTest>& last_round);
/// Catalog indices of the components of `families` (empty: every extended family of the family
/// table) not yet in `current`.
std::vector<int> candidate_components(const std::vector<std::string>& families,
                                      const std::vector<int>& current);
/// Tests every candidate against the model `current` whose fit is `now`.
using RoundRunner = std::function<std::vector<CandidateTest>(const std::vector<int>& current,
                                                             const FitFigures& now)>;
/// Adds figures to the round's best candidate (`with`: the model with it) before it is recorded.
using BestCompleter = std::function<void(const std::vector<int>& with, CandidateTest& best)>;
/// The rounds of a diagnosis, from rep.initial_parameters and rep.initial: the round's named best
/// joins the model, until no candidate is significant, the best is ambiguous or `max_findings`
/// are named. Fills rounds, findings, ambiguous, not_separable, final_parameters and final_fit.
void run_rounds(DiagnosisReport& rep, int max_findings, const RoundRunner& run_round,
                const BestCompleter& complete = {});
}  // namespace diagnosis_detail

/// Diagnoses the stage-1 equivalent inputs of a session, starting from `base` (its parameters:
/// the session's model). Throws std::invalid_argument when the dwells are too few for the base
/// model (fewer inputs than parameters plus one).
DiagnosisReport diagnose_static(const std::vector<EquivalentInputs>& inputs, const Site& site,
                                const Stage2Options& base, const DiagnosisOptions& options = {});

}  // namespace sinscal
