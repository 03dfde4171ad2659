// Model discovery on a table session as one story across its dwells and turns: the static dwells'
// test (diagnosis.hpp) and the Kalman filter's (diagnosis_kalman.hpp) ranked in one round at one
// Bonferroni level, the dwells first; ambiguous sets as one finding; each finding's magnitudes and
// its gain as held-out prediction. docs/methods/diagnosis.md "One story across dwells and turns".
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "filter/diagnosis/diagnosis.hpp"
#include "filter/diagnosis/diagnosis_kalman.hpp"
#include "filter/diagnosis/pair_separation.hpp"
#include "filter/diagnosis/term_library.hpp"
#include "filter/kalman/innovation_check.hpp"

namespace sinscal {

struct TableDiagnosisOptions {
  /// alpha, candidates, preferred members of ambiguous sets, max_findings.
  DiagnosisOptions dwells;
  /// The filter's test (separable_remaining); its alpha and candidates are the dwells'.
  KalmanDiagnosisOptions turns;
  /// Held-out turns for each finding's gain (two runs of the filter per model).
  bool heldout_turns = true;
};

/// The session's model from its sensor profile: the extended families it declares join the
/// dwells' initial model too (the model both tests use), and the filter runs the turns' test.
struct TurnModel {
  const Session* session = nullptr;
  CalibratorOptions base;
  bool run_filter = true;  // false: the profile's families only (no turns' test)
};

/// The prior 1-sigma (SI) of every catalog coefficient for a sensor of the grade of `model` (the
/// filter's options from a profile): the profile's own prior where it gives the family a range,
/// else the family's default prior (navigation grade) times the ratio of the profile's prior of
/// the triad's base family of the same kind to that family's default prior, never below the
/// default: a rate or force offset (g-sensitivity, bias drift, bias temperature terms) follows the
/// bias, a relative error (K2, scale asymmetry, scale temperature terms) the scale factor, a
/// misalignment temperature term the misalignment; lever arms and the time delay keep theirs.
std::vector<double> grade_priors(const CalibratorOptions& model);

/// The turns' model of a session as `sinscal diagnose` runs it: the filter's options from the
/// session's sensor profile (the families it lacks with priors of its grade, grade_priors), the
/// table's attitude sigma (rad), the session's time offset.
TurnModel turn_model_of(const Session& session, const SensorProfile& profile, double table_sigma);

/// The dwells' model of the diagnosis: `base` plus the extended families `turn_model`'s profile
/// declares (the model both tests use; not repeated when already in `base`), the dwells
/// correlated by the profile's bias wander (`turn_model->base.noise`); `base` itself without a
/// turn model.
Stage2Options dwells_model(const Stage2Options& base, const TurnModel* turn_model);

/// One pass's NIS per dof above this: the session's errors are too large for one linearization
/// about zero (MEMS), and both tests linearize about a first calibration.
constexpr double kRelinearizeNis = 1.5;
/// Or the first pass's gyro bias turns the attitude through a dwell by more than this (rad, about
/// 0.6 deg): stage 1's navigation errors are beyond small angles about zero (a MEMS unit).
constexpr double kSmallAngle = 0.01;

/// The model both tests linearize about, or none (about zero, as one pass of calibrate): the
/// filter's estimate after `passes` passes over the log with the session's model; `passes` 0:
/// automatic, 3 passes when one pass's NIS per dof is above kRelinearizeNis or its gyro bias
/// times the longest dwell above kSmallAngle, else none. Sets the
/// model (and its base) as the filter's starting point (`model.base.initial_model`); the closed
/// form takes it as `run_closed_form(..., false, about)` (no alignment: the model carries the
/// mounting), so the dwells' fits are corrections to it. When a pass stops or diverges: none
/// (about zero), the reason in `failed`.
std::optional<ImuErrorModel> linearize(TurnModel& model, int passes, std::string* failed = nullptr);

/// A coefficient of a finding in the extended calibration.
struct FindingCoefficient {
  int catalog = 0;
  double value = 0.0;  // SI
  double sigma = 0.0;  // SI (scaled by the unexplained residual, ResidualCheck)
  /// "kalman" (the filter with the extended model), "dwells" (the dwells' fit), or "" when
  /// neither determines it alone (see the finding's combinations).
  std::string source;
};

/// One finding of the story: the round's most significant effect, which then joined the model.
/// Its test (TestVerdict): "chi2" (likelihood ratio), "F" (likelihood ratio over the residual's
/// scale) or "wald" (the filter's estimate against zero, chi-square); base_shift_sigma the largest
/// move of a coefficient already in the model.
struct TableFinding : TestVerdict {
  int round = 0;  // 1-based
  enum class Source { Dwells, Turns };
  Source source = Source::Dwells;
  std::string family;           // the family the model was extended with
  std::vector<int> components;  // catalog indices added (the dwells: the separable ones)
  /// Other families that explain the same residual as well on the dwells (an ambiguous set), and
  /// who picked `family` out of it ("turns": the filter's best log-likelihood; "data": the
  /// dwells' best fit; "user": DiagnosisOptions::prefer).
  std::vector<std::string> ambiguous_with;
  std::string picked_by;
  /// picked_by "turns" with the runner-up's held-out turns within the chi-square quantile of one
  /// dof at 1 - alpha: "close: ..." with both figures (the turns do not choose), else "".
  std::string pick_note;
  /// picked_by "turns" (a pair): whether the plan can tell the pair apart at all, from its
  /// information (pair_separation.hpp: the correlation of the two families' estimates on the
  /// dwells and turns, the expected chi-square difference at the size found), and the plan with
  /// the turns split in halves (tilted dwells) that separates it; the statement, else "".
  std::string separability;
  std::optional<double>
      pick_gap;  // picked_by "turns": the runner-up's held-out chi2 minus the pick's
  std::optional<PairSeparation> separation;  // on this session's plan
  std::optional<PairSeparation> separating;  // on split_turns of it (a rotation plan)
  /// What separates each family of the set from the base coefficients (the family table):
  /// `family` first, then each of ambiguous_with.
  std::vector<std::string> separated_by;
  /// The family's coefficients in the final extended calibration (every finding in the model).
  std::vector<FindingCoefficient> coefficients;     // catalog order
  std::vector<DeterminedCombination> combinations;  // determined only together (dwells)
  /// Dwells: the fits before and after (residual RMS, leave-one-dwell-out prediction); only
  /// for dwell findings (the effects of the turns leave the dwells' fit as it was).
  std::optional<FitFigures> dwells_before, dwells_after;
  /// The filter: NIS per dof and innovation log-likelihood before and after, and the turns'
  /// held-out prediction.
  bool filter = false;
  double nis_before = 0.0, nis_after = 0.0, log_likelihood_before = 0.0, log_likelihood_after = 0.0;
  std::optional<HeldoutTurns> turns_before, turns_after;
  /// A library term that predicts the held-out dwells and turns as well as the family (the plan
  /// cannot tell them apart, term_library.hpp HeldoutContest): the contest's statement, else "".
  /// The finding is then a set the plan cannot separate, as an ambiguous set of families is: the
  /// term's name() in ambiguous_with, its separated_by in separated_by, picked_by "catalog" (the
  /// model holds catalog families only; the data cannot choose); the term (its value and sigma
  /// with the model before the finding) in alternative_term.
  std::string library_alternative;
  std::optional<LibraryTerm> alternative_term;
  /// A bias drift in time against the same bias's degree-1 temperature term (a session whose
  /// temperature varies): the held-out dwells' verdict between them (CandidateTest), else "".
  std::string time_temperature;
  /// A dwell finding the held-out data refused in an earlier round while a significant turns'
  /// candidate was not yet in the model: that candidate was judged instead and this finding again
  /// with it in the model, which the held-out data then confirmed. The first refusal and its
  /// round ("round 1: the held-out turns' chi-square goes from ..."), else "".
  std::string refused_before;
};

/// The final model's residual against its noise model: whether the findings leave the dwells and
/// the turns as the noise model predicts. When they do not, the reported sigmas are scaled by the
/// excess (sqrt of chi2 per dof) and the rest is "unexplained".
struct ResidualCheck {
  double dwells_chi2 = 0.0;
  int dwells_dof = 0;
  double dwells_quantile = 0.0;  // the chi-square quantile of dwells_dof at kResidualLevel
  bool dwells_hold = true;       // the in-sample chi2 within its quantile
  /// The held-out dwells' predictive chi-square (each dwell predicted by the others, whitened by
  /// its predictive covariance) against its quantile at kResidualLevel: the dwell findings must
  /// leave it consistent with the noise (few dwells fit a model closely in sample).
  double heldout_chi2 = 0.0;
  int heldout_inputs = 0;
  double heldout_quantile = 0.0;
  bool heldout_hold = true;
  bool filter = false;  // the filter ran
  double nis_per_dof = 0.0;
  /// The filter's innovations per channel: NIS (upper tail) and whiteness (Ljung-Box) at the
  /// family-wise kInnovationAlpha (filter/kalman/innovation_check.hpp); filter_holds is its
  /// verdict.
  InnovationCheck innovations;
  bool filter_holds = true;         // the innovations consistent with the noise model
  double dwells_sigma_scale = 1.0;  // sqrt(chi2 / dof) where the dwells do not hold, else 1
  double filter_sigma_scale = 1.0;  // sqrt(NIS per dof) where the filter does not hold, else 1
  /// sqrt(held-out chi2 / inputs) where the held-out dwells do not hold, else 1.
  double heldout_sigma_scale = 1.0;
  /// The turns' attitude residual (the term library's test, LibraryFit) with the final model:
  /// sqrt(chi2 / dof) where it rejects, else 1. turns_tested false: no session to read.
  bool turns_tested = false;
  double turns_chi2 = 0.0, turns_dof = 0.0;
  bool turns_hold = true;
  double turns_sigma_scale = 1.0;
  /// The factor every reported sigma of a finding carries: the largest of the four scales (an
  /// incomplete model aliases what it lacks into every estimate, whichever data reject it; on an
  /// all-hidden ramp the dwells held while the turns rejected, and the magnitudes were 2.7-130
  /// sigma off, issue 33).
  double sigma_scale = 1.0;
  /// False when the model is still rejected at the stop (any of the data above, a finding the
  /// held-out data refused, or the findings cap with a candidate still significant): the scaled
  /// sigmas are then a lower bound, not a confidence interval; `sigmas_note` says why.
  bool sigmas_hold = true;
  std::string sigmas_note;
  bool holds() const { return dwells_hold && heldout_hold && filter_holds; }
};

/// The level of the residual's chi-square test (the final model against its noise model).
constexpr double kResidualLevel = 0.99;

/// A finding the in-sample test took but the held-out data contradict: not named, and the
/// diagnosis stops there (its residual is "unexplained"); but a dwell finding that the held-out
/// data refuse while the round holds a significant turns' candidate is judged again after that
/// candidate (TableFinding::refused_before), and is rejected only if refused again or never
/// judged again.
struct RejectedFinding {
  TableFinding finding;
  std::string reason;  // "the held-out dwells' chi-square gains 2.1 (11.3 needed)", ...
};

/// What the final model leaves unexplained, by where it shows.
struct Unexplained {
  bool present = false;
  /// Where: "dwells, accel down: chi2 310 on 38 inputs; largest at ..."; "turns: NIS per dof ..."
  std::vector<std::string> signature;
  /// The dwells' residual fitted against the out-of-catalog library (term_library.hpp); its terms
  /// empty when none is confirmed on held-out dwells.
  std::optional<LibraryFit> library;
};

struct TableDiagnosis {
  DiagnosisReport dwells;  // the dwells' rounds, their findings, what they cannot separate
  /// The filter's rounds (aligned with the dwells' by round; a round with no turn candidate is
  /// empty), its findings, the families it cannot separate either, the final run.
  std::optional<KalmanDiagnosis> turns;
  std::vector<TableFinding> findings;  // the story, in order
  int rounds = 0;
  std::vector<RejectedFinding> rejected;  // the best candidate the held-out data contradict
  ResidualCheck check;                    // the final model against its noise model
  Unexplained unexplained;
  /// Every stop and every limit of the search: the findings cap reached with candidates still
  /// significant, families not tested on this kind of session, a name the held-out data refuse.
  std::vector<std::string> stops;
};

/// Diagnoses a table session from its stage-1 inputs, starting from `base` (the session's model);
/// with `turns`, the effects of the turns in the same rounds. Throws std::invalid_argument when the
/// dwells are too few for the base model or a candidate is not an extended family, and
/// std::runtime_error when a run of the filter stops early.
TableDiagnosis diagnose_table(const std::vector<EquivalentInputs>& inputs, const Site& site,
                              const Stage2Options& base, const TableDiagnosisOptions& options,
                              const TurnModel* turns = nullptr);

/// The dwells alone (no turns' test).
inline DiagnosisReport diagnose_static(const std::vector<EquivalentInputs>& inputs,
                                       const Site& site, const Stage2Options& base,
                                       const DiagnosisOptions& options = {}) {
  TableDiagnosisOptions o;
  o.dwells = options;
  return diagnose_table(inputs, site, base, o).dwells;
}

}  // namespace sinscal
