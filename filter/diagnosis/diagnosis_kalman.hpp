// Model discovery from the Kalman filter's innovations, for the effects that act only while the
// table turns (inner lever arms, time delay, gyro scale asymmetry): each candidate family switched
// on in the filter, its estimate tested against zero with the covariance it has when the effect is
// absent (a Wald test). docs/methods/diagnosis.md "The turns' test".
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "filter/diagnosis/diagnosis_core.hpp"
#include "filter/kalman/kalman_run.hpp"

namespace sinscal {

/// alpha, max_findings (3) and the candidate families (DiagnosisSearch: extended families of the
/// family table not in the base model).
struct KalmanDiagnosisOptions : DiagnosisSearch {
  KalmanDiagnosisOptions() : DiagnosisSearch(3) {}
  /// A prior-normalized direction counts when the data leave at most this fraction of its prior
  /// variance (the rule of CoefficientEstimate::observed()).
  double separable_remaining = 0.5;
};

/// One candidate family run in the filter beside the current model; its test (TestVerdict):
/// "wald", the statistic W (after the NIS scaling) against chi-square(dof), dof the directions the
/// data determine.
struct KalmanCandidateTest : TestVerdict {
  std::string family;
  std::string separated_by;  // the plan feature that separates it (family table)
  double nis_scale = 1.0;    // the NIS per dof W was divided by (1: none)
  /// The run with the candidate stopped or diverged (the reason): not tested (dof 0).
  std::string failed;
  std::vector<int> catalog;  // the family's coefficient indices
  /// Every coefficient of the run with the candidate (catalog order, SI).
  std::vector<CoefficientEstimate> estimates;
  double nis_per_dof = 0.0;     // of the run with the candidate
  double log_likelihood = 0.0;  // of the run with the candidate
};

struct KalmanDiagnosis {
  std::vector<std::string> initial_families;  // extended families of the session's model
  double initial_nis_per_dof = 0.0;
  double initial_log_likelihood = 0.0;
  std::vector<std::vector<KalmanCandidateTest>> rounds;
  std::vector<KalmanCandidateTest> findings;       // named, in order
  std::vector<KalmanCandidateTest> not_separable;  // no direction the data determine
  KalmanRun final_run;                             // the model with the findings
  double alpha = 0.0;
};

/// The turns' held-out prediction of one model: the filter run twice, each time without any
/// update during every other turn between dwells (the odd turns, then the even ones), and the
/// first update after each held-out turn scored: how well the coefficients learnt from the other
/// turns and the dwells predict the navigation error a turn accumulates.
struct HeldoutTurns {
  int turns = 0;          // held-out turns scored (0: none; see `failed`)
  std::string failed;     // a run with turns held out diverged (errors too large to predict)
  double sigmas = 0.0;    // RMS of sqrt(NIS / dof) of those updates (1: as predicted)
  double velocity = 0.0;  // m/s: RMS of the zero-velocity innovation's norm
  double chi2 = 0.0;      // the scored updates' NIS summed (the held-out turns' chi-square)
  int dof = 0;            // their measurement dimensions summed
};

/// The held-out turns of `options`' model on the session (two runs of the filter). Turns with
/// no time between their dwells' update margins are skipped; none: turns = 0. A run that
/// diverges (the turns' errors too large to predict without updates) leaves turns = 0 and the
/// reason in `failed`.
HeldoutTurns heldout_turns(const Session& session, const CalibratorOptions& options);
/// The same with each run of the filter made by `run` (e.g. over an ideal IMU without noise,
/// pair_separation.hpp); it throws std::runtime_error for a run that stops.
HeldoutTurns heldout_turns(const Session& session, const CalibratorOptions& options,
                           const std::function<KalmanRun(const CalibratorOptions&)>& run);

/// The turns' side of a table diagnosis: the filter run with the current model, then with each
/// candidate family added (filter/diagnosis/diagnosis_table.hpp runs the rounds).
class TurnTests {
 public:
  /// Runs the filter with `base`. Throws std::runtime_error when the run stops early.
  TurnTests(const Session& session, const CalibratorOptions& base,
            const KalmanDiagnosisOptions& options);
  const KalmanRun& now() const { return now_; }
  /// The current model and its run, to return to when an extension is withdrawn.
  struct State {
    CalibratorOptions model;
    KalmanRun now;
  };
  State state() const { return {model_, now_}; }
  void restore(State s) {
    model_ = std::move(s.model);
    now_ = std::move(s.now);
    last_round_.clear();
  }
  const CalibratorOptions& model() const { return model_; }
  /// Tests each family against the current model (the runs are kept for extend()). Throws
  /// std::invalid_argument for a family that is not extended or already in the model; a run
  /// that stops or diverges leaves its family untested (KalmanCandidateTest::failed).
  std::vector<KalmanCandidateTest> round(const std::vector<std::string>& families);
  /// Adds a family to the model: the last round's run with it, else a new run.
  void extend(const std::string& family);
  HeldoutTurns heldout() const { return heldout_turns(session_, model_); }

 private:
  const Session& session_;
  KalmanDiagnosisOptions options_;
  CalibratorOptions model_;
  KalmanRun now_;
  std::vector<std::pair<std::string, KalmanRun>> last_round_;
};

/// Marks the round's candidates significant below `threshold` (p-value, with a tested direction)
/// and returns the most significant one (smallest log10 p), or nullptr.
KalmanCandidateTest* most_significant(std::vector<KalmanCandidateTest>& round, double threshold);

/// Runs the filter on the session with `base`, then each candidate family added. Throws
/// std::invalid_argument for a candidate that is not an extended family or already in `base`,
/// and std::runtime_error when a run of the filter stops early (bad sample, divergence).
KalmanDiagnosis diagnose_kalman(const Session& session, const CalibratorOptions& base,
                                const KalmanDiagnosisOptions& options);

}  // namespace sinscal
