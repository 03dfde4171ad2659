// Model discovery on a table session's static dwells: the closed form's stage-2 residual, each
// extended family of the family table refitted as a candidate, named by its likelihood ratio at a
// family-wise level with its leave-one-dwell-out gain; what the plan cannot separate is said, never
// guessed. docs/methods/diagnosis.md (the general notes: docs/methods/model-discovery.md).
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "filter/closed_form/closed_form.hpp"
#include "filter/diagnosis/diagnosis_core.hpp"

namespace sinscal {

/// alpha, max_findings (6) and the candidate families (DiagnosisSearch; empty: every extended
/// family of the family table, each of their components a candidate).
struct DiagnosisOptions : DiagnosisSearch {
  /// A candidate component is separable when the plan shrinks its sigma (given the base
  /// coefficients) below its family's default prior divided by this.
  double separable_ratio = 3.0;
  /// Families the user picks out of an ambiguous set (the first of them in the set extends the
  /// model; none: the data's pick, the member with the best fit).
  std::vector<std::string> prefer;
  /// The thermal families among the default candidates: the dwells' temperatures vary (a
  /// ramp's log; each dwell's inputs at its mean temperature and rate). Set by the caller.
  bool thermal = false;
  /// The weak prior 1-sigma (SI) of each catalog coefficient (by catalog index) in the dwells'
  /// regularized fits, and the scale a separable candidate's sigma is compared with; absent or
  /// 0: the family's default prior (a navigation-grade value). A session's grade sets it
  /// (diagnosis_table.hpp grade_priors).
  std::vector<double> prior_sigma;
};

/// Residuals of one dwell, measured minus model: df_n (m/s^2) and dw_n (rad/s), NED.
struct DwellResidual {
  int dwell = 0;
  std::string label;
  Eigen::Matrix<double, 6, 1> before = Eigen::Matrix<double, 6, 1>::Zero();  // initial model
  Eigen::Matrix<double, 6, 1> after = Eigen::Matrix<double, 6, 1>::Zero();   // final model
  Eigen::Matrix<double, 6, 1> sigma = Eigen::Matrix<double, 6, 1>::Zero();   // of the inputs
};

/// The held-out figures of one parameter set: each dwell (hand-held: each pose and turn) left out
/// of the fit in turn and predicted by the others.
struct HeldoutFigures {
  double heldout = 0.0;       // RMS of the leave-one-dwell-out prediction error, in sigmas
  double heldout_chi2 = 0.0;  // its sum of squares (whitened): the held-out dwells' chi-square
  /// The same prediction errors whitened by their predictive covariance (noise plus the other
  /// dwells' uncertainty of the prediction): chi-square of heldout_inputs dof when the model holds.
  double heldout_predictive_chi2 = 0.0;
  int heldout_inputs = 0;
  /// Its variance when the model holds, 2 tr(M^2), M the covariance of all the dwells' whitened
  /// prediction errors together (tr(M) = heldout_inputs). The dwells' predictions share their
  /// data, so the errors of different dwells correlate and the sum is wider than a chi-square of
  /// heldout_inputs dof (seed8: 8 dwells, 48 inputs, about 25 coefficients: variance about twice
  /// the chi-square's). 0: not computed (a chi-square of heldout_inputs dof is assumed).
  double heldout_predictive_variance = 0.0;
  /// Its third cumulant when the model holds, 8 tr(M^3) (the tail's skewness; 0: not computed).
  double heldout_predictive_cumulant3 = 0.0;
  double heldout_accel = 0.0;  // m/s^2, same in the sensor's units
  double heldout_gyro = 0.0;   // rad/s
  int heldout_dwells = 0;      // dwells whose prediction the others determine
  double heldout_turn = 0.0;   // hand-held: the turns' (rad), as turn_rms
};

/// Fit figures of one parameter set, with its held-out figures.
struct FitFigures : HeldoutFigures {
  Stage2Result fit;
  double chi2 = 0.0;       // whitened residual sum of squares
  double accel_rms = 0.0;  // m/s^2: RMS of the accelerometer residuals over dwells, axes
  double gyro_rms = 0.0;   // rad/s
  /// Hand-held sessions (filter/diagnosis/handheld_diagnosis.hpp): accel_rms, gyro_rms are the
  /// poses' gravity-magnitude residual and rate at rest; turn_rms (and heldout_turn) the turns'
  /// (rad), 0 for table sessions.
  double turn_rms = 0.0;
  double log_likelihood = 0.0;  // -chi2/2 (constant terms dropped)
  double bic = 0.0;             // chi2 + rank log(inputs)
};

/// The quantile at `level` of the held-out predictive chi-square when the model holds: a
/// chi-square shifted and scaled to its mean (heldout_inputs), variance and third cumulant
/// (Pearson's three-moment fit of a quadratic form), a chi-square of heldout_inputs dof when they
/// are not computed.
double heldout_predictive_quantile(const HeldoutFigures& f, double level);

/// A combination of a family's coefficients that the data determine although the coefficients
/// alone are not (each is aliased with base coefficients or the family's others): sum of
/// weight x coefficient (SI), with its value and sigma.
struct DeterminedCombination {
  std::vector<std::pair<int, double>> weights;  // catalog index, weight (unit norm)
  double value = 0.0;                           // SI
  double sigma = 0.0;                           // SI
  std::string text() const;                     // "+0.707 gyro.g_sensitivity.xx -0.707 ..."
};

/// The combinations of `components` (catalog indices) that `fit` determines although they are not
/// observable one by one: an orthonormal basis of the combinations orthogonal to every null
/// vector of the fit. Empty when every component is observable.
std::vector<DeterminedCombination> determined_combinations(const Stage2Result& fit,
                                                           const std::vector<int>& components);

/// One candidate (a component of an extended family) tested against the current model; its test
/// (TestVerdict): "chi2" while the noise model holds, the statistic the likelihood ratio,
/// chi-square(dof); "F" when the fit's residual rejects the noise model, the statistic
/// (likelihood_ratio / dof) / (chi2_1 / dof2), F(dof, dof2). named: the most significant, and no
/// other family explains it.
struct CandidateTest : TestVerdict {
  std::string family;
  std::vector<int> separable;  // catalog indices of the components the plan separates
  std::vector<int> aliased;    // those it does not
  std::string aliased_with;    // the base combination an aliased component hides in
  std::string separated_by;    // the plan feature that would separate it (family table)
  /// chi2_0 - chi2_1: the whitened residual's decrease (twice the log-likelihood ratio).
  double likelihood_ratio = 0.0;
  /// Other families' candidates that explain the same residual (each insignificant once the
  /// other is in the model): the plan cannot tell them apart.
  std::vector<CandidateTest> ambiguous_with;
  FitFigures with;  // the fit with the candidate
  /// The candidate's components that `with` determines one by one, and the combinations of the
  /// others it determines.
  std::vector<int> determined;
  std::vector<DeterminedCombination> combinations;
  /// A finding out of an ambiguous set (ambiguous_with holds other families): who picked this
  /// member to extend the model, "data" (the best fit) or "user" (DiagnosisOptions::prefer).
  std::string picked_by;
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
  /// The round's best the held-out data refuse (run_rounds): not named, the search stopped.
  std::vector<CandidateTest> rejected;
  std::vector<std::string> stops;  // why each refused candidate was refused
};

/// The statistics shared by the table and hand-held diagnoses.
namespace diagnosis_detail {
/// The test of a nested extension `c.with` of `now` (c.dof extra parameters): the chi-square test
/// of the likelihood ratio while the noise model holds, else the F test.
void test_statistic(const FitFigures& now, CandidateTest& c);
/// Tests `c`, its separable components added to `current` and fitted by `fit`, against `now`:
/// c.with, c.dof (the rank increase), its test and base shift. False (untested) when the
/// extension adds no parameter or leaves no degree of freedom.
bool test_extension(const std::vector<int>& current, const FitFigures& now, CandidateTest& c,
                    const std::function<FitFigures(const std::vector<int>&)>& fit);
/// Largest move of the first base.size() coefficients between two fits, in their sigmas before.
double largest_shift(const FitFigures& before, const FitFigures& after,
                     const std::vector<int>& base);
/// Marks the round's significant candidates (Bonferroni) and returns the most significant one,
/// or nullptr.
CandidateTest* best_of(std::vector<CandidateTest>& round, double alpha);
/// The most significant candidate with those that explain the residual as well; named unless
/// another family's does.
CandidateTest* choose(std::vector<CandidateTest>& round, double alpha);
/// Why the held-out figures refuse an extension of `dof` parameters from `before` to `after`
/// (empty: they confirm it): the held-out chi-square must fall by at least the chi-square quantile
/// of dof at 1 - alpha, measured in the extended model's held-out residual scale where that
/// exceeds 1 (as the F test scales the in-sample statistic). Held-out figures absent: empty.
std::string heldout_refusal(const FitFigures& before, const FitFigures& after, int dof,
                            double alpha);
/// What could not be separated (aliased components), one entry per family.
std::vector<CandidateTest> not_separable(const std::vector<CandidateTest>& last_round);
/// Catalog indices of the components of `families` (empty: every extended family of the family
/// table, the thermal ones with `thermal`) not yet in `current`. With `thermal` the default set
/// grows degree by degree: a thermal family of degree d once degree d - 1 of the same coefficient
/// is in `current`, a bias drift in time once the same bias's degree-1 temperature term is.
std::vector<int> candidate_components(const std::vector<std::string>& families,
                                      const std::vector<int>& current, bool thermal = false);
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

/// One dwell's estimated inputs whitened (R = L L^T): A = L^-1 H (the model's columns, then the
/// table base's three when it is estimated), y = L^-1 u; `rows` which of the 6 NED inputs.
struct WhitenedDwell {
  Eigen::MatrixXd A, L;
  Eigen::VectorXd y;
  std::vector<int> rows;
};

/// The static dwells' side of a table diagnosis: fits of parameter sets to stage 1's equivalent
/// inputs and the tests of candidates against a current model (filter/diagnosis/diagnosis_table.hpp
/// runs the rounds).
class DwellTests {
 public:
  /// Throws std::invalid_argument when the dwells are too few for the base model (fewer inputs
  /// than parameters plus one) or the options are out of range.
  DwellTests(std::vector<EquivalentInputs> inputs, const Site& site, const Stage2Options& base,
             const DiagnosisOptions& options);
  /// Fit, residuals and leave-one-dwell-out prediction of a parameter set.
  FitFigures fit(const std::vector<int>& parameters) const;
  /// Every candidate component against the current model, then each family's separable
  /// components together.
  std::vector<CandidateTest> round(const std::vector<int>& current, const FitFigures& now) const;
  /// Per-dwell residuals under the initial and the final parameter sets.
  std::vector<DwellResidual> residuals(const std::vector<int>& initial,
                                       const std::vector<int>& final) const;
  /// The dwells whitened for the model `parameters`, and the weak prior sigmas (SI) of its
  /// columns (filter/diagnosis/term_library.hpp fits what is left).
  std::vector<WhitenedDwell> whitened(const std::vector<int>& parameters) const;
  Eigen::VectorXd prior(const std::vector<int>& parameters) const;
  const std::vector<EquivalentInputs>& dwell_inputs() const { return inputs_; }
  const Site& site() const { return site_; }
  int inputs() const { return inputs_count_; }
  const Stage2Options& base() const { return base_; }
  const DiagnosisOptions& options() const { return options_; }

 private:
  std::vector<EquivalentInputs> inputs_;
  Site site_;
  Stage2Options base_;
  DiagnosisOptions options_;
  int inputs_count_ = 0;
};

}  // namespace sinscal
