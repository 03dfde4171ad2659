// Model discovery over temperature, on a chamber's soaks: which thermal family the model lacks, by
// the soaks' fit against temperature with and without it (likelihood ratio, Bonferroni), its
// magnitude, and the gain of adding it on held-out soaks. docs/methods/diagnosis.md "Thermal
// families on a chamber's soaks".
#pragma once

#include <string>
#include <vector>

#include "filter/diagnosis/diagnosis_core.hpp"
#include "filter/thermal/soak_fit.hpp"

namespace sinscal {

/// alpha, max_findings (4) and the candidate thermal families (DiagnosisSearch; empty: every
/// thermal family of the family table not in `model`).
struct ThermalDiagnosisOptions : DiagnosisSearch {
  ThermalDiagnosisOptions() : DiagnosisSearch(4) {}
  /// The thermal families of the model (the sensor profile's).
  std::vector<std::string> model;
  /// The caller tests the non-thermal families elsewhere (a soak's session as a table session)
  /// and states it: no "only thermal families tested" stop.
  bool non_thermal_elsewhere = false;
};

/// Held-out soaks: each left out of the fit in turn and its coefficients predicted.
struct HeldoutSoaks {
  int soaks = 0;
  double sigmas = 0.0;                // RMS over the soaks of sqrt(d^2 / m)
  double chi2 = 0.0;                  // the sum of d^2: the held-out soaks' chi-square
  std::vector<double> per_soak;       // sqrt(d^2 / m) of each
  std::vector<double> temperature_c;  // each soak's gyro temperature (its label)
};

/// One thermal family tested on the soaks; its test (TestVerdict): "chi2" or "F", dof the
/// parameters added.
struct ThermalCandidateTest : TestVerdict {
  std::string family;
  std::string not_testable;  // why the soaks cannot test it (empty: tested)
  double likelihood_ratio = 0.0;
};

/// A coefficient of a finding: catalog index, value and sigma (SI) in the extended fit.
struct ThermalFindingCoefficient {
  int catalog = 0;
  double value = 0.0;
  double sigma = 0.0;
};

struct ThermalFinding {
  int round = 0;  // 1-based
  ThermalCandidateTest test;
  /// The family's coefficients in the final fit (every finding in the model).
  std::vector<ThermalFindingCoefficient> coefficients;
  HeldoutSoaks before, after;
  /// RMS over the held-out soaks and the components of the family's coefficient at the soak
  /// ("accel.scale" for accel.scale_temp1) minus its prediction, SI: before and after.
  double family_error_before = 0.0, family_error_after = 0.0;
};

struct ThermalDiagnosis {
  double alpha = 0.0;
  double reference_temperature_c = 0.0;
  std::vector<std::string> model;  // the initial model's thermal families
  double initial_chi2 = 0.0;
  int initial_dof = 0;
  HeldoutSoaks initial_heldout;
  std::vector<std::vector<ThermalCandidateTest>> rounds;
  std::vector<ThermalFinding> findings;
  std::vector<ThermalCandidateTest> not_testable;
  ThermalFit final_fit;  // the model with the findings
  HeldoutSoaks final_heldout;
  /// The most significant candidate the held-out soaks refuse (its chi-square not lower with
  /// it): not named, the search stops there.
  std::vector<ThermalCandidateTest> rejected;
  /// The final fit's residual rejects the soaks' covariance (p below alpha): what is left is
  /// unexplained, and the findings' sigmas are scaled by sigma_scale = sqrt(chi2 / dof).
  bool unexplained = false;
  double sigma_scale = 1.0;
  /// Every stop and limit: the findings cap reached with candidates still significant, the
  /// families a chamber's soaks do not test.
  std::vector<std::string> stops;
};

/// Held-out soaks of the model with `families`: needs at least 3 soaks, and the other soaks to
/// determine the model (at most soaks - 1 terms per coefficient; else soaks = 0).
HeldoutSoaks heldout_soaks(const std::vector<SoakEstimate>& soaks,
                           const std::vector<std::string>& families, double t0);

/// Diagnoses the soaks against the model. Throws std::invalid_argument for a model or candidate
/// that is not a thermal family, and as fit_soaks_with.
ThermalDiagnosis diagnose_soaks(const std::vector<SoakEstimate>& soaks, double t0,
                                const ThermalDiagnosisOptions& options);

}  // namespace sinscal
