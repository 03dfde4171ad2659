// Effects outside the family catalog, found by their signature on a table session's static
// dwells: what the final model leaves is fitted against a library of candidate terms wider than
// the catalog (products f_i f_j per accelerometer and gyro axis, bias steps between dwells), by
// sequential thresholded least squares (as in SINDy) with the threshold chosen on held-out dwells.
// docs/methods/diagnosis.md "Out-of-catalog terms".
#pragma once

#include <string>
#include <vector>

#include "filter/diagnosis/diagnosis.hpp"

namespace sinscal {

/// One library term: the sensor axis it acts on, its function of the dwell's inputs, its
/// magnitude with sigma (in `unit`).
struct LibraryTerm {
  std::string sensor;   // "accel" or "gyro"
  int axis = 0;         // 0 x, 1 y, 2 z (body)
  std::string formula;  // "f_y f_z", "step at t = 612 s"
  std::string unit;     // "ug/g^2", "deg/h", ...
  double si_per_unit = 1.0;
  double value = 0.0;  // in `unit`
  double sigma = 0.0;  // in `unit`, scaled by the library fit's residual where it exceeds noise
  /// Other library terms this plan cannot tell from it (their columns, with the model's
  /// projected out, correlate beyond kAliasCorrelation): each with its own value and sigma.
  std::vector<LibraryTerm> aliases;
  /// "accel x: 97 +- 6 ug/g^2 * f_y f_z"
  std::string text() const;
};

/// Two library columns correlated beyond this (with the model's columns projected out) are one
/// function on the plan's dwells: the library reports them together.
constexpr double kAliasCorrelation = 0.999;

struct LibraryFit {
  int candidates = 0;            // library terms tried
  double threshold_sigma = 0.0;  // STLSQ threshold chosen on the held-out dwells (|value|/sigma)
  /// Held-out dwells' chi-square of the residual without and with the selected terms.
  double heldout_before = 0.0, heldout_after = 0.0;
  double heldout_needed = 0.0;  // the gain asked for (chi-square quantile of the terms' count)
  double chi2_before = 0.0, chi2_after = 0.0;
  int dof_after = 0;
  std::vector<LibraryTerm> terms;  // selected, held-out confirmed (empty: none)
  /// How to add the terms as a family: one entry in the family table.
  std::string how_to_add;
};

/// Fits the residual of the model `parameters` on the dwells against the library (alpha: the
/// level of the held-out confirmation). Terms the model's columns explain are projected out.
LibraryFit fit_term_library(const DwellTests& dwells, const std::vector<int>& parameters,
                            double alpha);

}  // namespace sinscal
