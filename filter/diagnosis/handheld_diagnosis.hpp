// Model discovery on a hand-held session: what the table-free calibration
// (filter/table_free/table_free.hpp) fails to explain on its poses and turns, each candidate family
// refitted in the linearized table-free problem, plus noise candidates from the longest pose's
// Allan deviation. The hand-held counterpart of filter/diagnosis/diagnosis.hpp, with its
// statistics and report structures. docs/methods/diagnosis.md "Hand-held sessions".
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "filter/diagnosis/diagnosis.hpp"
#include "filter/noise/allan.hpp"
#include "filter/table_free/table_free.hpp"

namespace sinscal {

/// alpha, max_findings (6) and the candidate families (DiagnosisSearch; empty: every extended
/// family of the family table; {""}: none).
struct HandheldDiagnosisOptions : DiagnosisSearch {
  /// A candidate component is separable when the sine of its smallest principal angle to the
  /// model's columns is at least this ...
  double min_angle_sine = 0.05;
  /// ... and its detection sigma (given the model) below this many of its family's default
  /// prior (beyond it, the poses do not see the effect at any plausible size).
  double plausible_ratio = 1e4;
  /// The noise candidates (Allan deviation of the longest pose) are tested.
  bool noise = true;
  /// The noise candidates were asked for by name: a pose too short for them is refused (see
  /// HandheldDiagnosis::refused) rather than skipped.
  bool noise_requested = false;
};

/// The residuals of one pose (and the turn into it) before and after the findings.
struct PoseResidual {
  int pose = 0;        // the detector's index
  double t_mid = 0.0;  // s since the first reading
  double gravity_before = 0.0, gravity_after = 0.0, gravity_sigma = 0.0;  // |f| - g, m/s^2
  Eigen::Vector3d rate_before = Eigen::Vector3d::Zero();  // rad/s at rest, body axes
  Eigen::Vector3d rate_after = Eigen::Vector3d::Zero();
  Eigen::Vector3d rate_sigma = Eigen::Vector3d::Zero();
  /// rad: the turn into this pose (NaN for the first pose).
  double turn_before = 0.0, turn_after = 0.0, turn_sigma = 0.0;
};

/// One noise candidate of one channel from the Allan deviation of the longest pose.
struct NoiseCandidate {
  std::string effect;   // "noise.bias_instability" | "noise.rate_random_walk"
  std::string channel;  // "gyro.x" ... "accel.z"
  bool significant = false;
  double value = 0.0, sigma = 0.0;  // SI: rate unit (B) or rate unit / sqrt(s) (K)
  double tau = 0.0;                 // s: the first cluster time beyond the white-noise model
  double ratio = 0.0;               // measured ADEV over the white-noise model there (largest)
  double confidence = 0.0;          // two-sided, of each point's bound (Bonferroni)
  int points = 0;                   // cluster times tested on this channel (the long half)
};

struct HandheldDiagnosis {
  /// Findings, rounds, what cannot be separated, ambiguities and fits; in the fits accel_rms and
  /// gyro_rms are the poses' gravity-magnitude residual (m/s^2) and rate at rest (rad/s),
  /// turn_rms the turns' (rad); the held-out figures likewise. `residuals` (dwells) is empty.
  DiagnosisReport report;
  std::vector<PoseResidual> poses;
  std::vector<NoiseCandidate> noise;  // empty when not tested
  int noise_pose = 0;                 // the pose of the Allan analysis
  bool has_allan = false;
  AllanAnalysis allan;  // of the longest pose, bounds at the family-wise confidence
  int rows = 0, turns = 0;
  /// Requested candidates that could not be tested (too few poses, with how many are needed and
  /// found): the command reports them as bad input after writing the rest.
  std::vector<std::string> refused;
};

/// Diagnoses a table-free calibration. `readings_si` are the readings it took (SI through the
/// log's nominal conversion), `options` its options (site, gravity). Throws
/// std::invalid_argument for options out of range or too few poses for a candidate.
HandheldDiagnosis diagnose_handheld(const std::vector<ImuReading>& readings_si,
                                    const TableFreeResult& calibration,
                                    const TableFreeOptions& options,
                                    const HandheldDiagnosisOptions& o = {});

/// The calibration's model with the diagnosis's final coefficients (base terms refitted and the
/// named effects added), accelerometer-triad frame.
ImuErrorModel diagnosed_model(const HandheldDiagnosis& diagnosis,
                              const TableFreeResult& calibration);

/// Allan analysis of readings [first, last] (a static stretch) as increments over their median
/// interval, bounds at noise_confidence(samples, alpha). Throws AllanError when too short.
AllanAnalysis stretch_allan(const std::vector<ImuReading>& readings, std::size_t first,
                            std::size_t last, double alpha);

/// Noise candidates of every channel of an Allan analysis at the family-wise level `alpha`: the
/// long half of the cluster times against the white-noise-only model the short half sets, each
/// point's bound at confidence 1 - 2 alpha / (points tested on all channels); the analysis must
/// have been computed at `noise_confidence(samples, alpha)`.
std::vector<NoiseCandidate> noise_candidates(const AllanAnalysis& analysis, double alpha);
/// The white-noise-only model of one channel's Allan deviation, N (ADEV = N / sqrt(tau)): the
/// median of ADEV sqrt(tau) over the first half of the cluster times. `points` not empty.
double white_only_deviation(const std::vector<AllanPoint>& points);
/// The two-sided confidence of each point's bound for a family-wise level alpha over the long
/// half of the cluster times of a record of `samples` (octaves up to a quarter of it), six
/// channels.
double noise_confidence(std::size_t samples, double alpha);

}  // namespace sinscal
