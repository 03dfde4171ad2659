// Effects outside the family catalog, found by their signature on a table session's static
// dwells and turns: what the final model leaves is fitted against a library of candidate terms
// wider than the catalog (products f_i f_j per accelerometer and gyro axis, bias steps between
// dwells, bias quadratic in time, periodic bias at the plan's cycle, gyro rate nonlinearity
// omega_i |omega_i|, omega_i^2, omega_i^3 of the gyro's output on the turns), by sequential
// thresholded least squares (as in SINDy) with the threshold chosen on held-out dwells and turns.
// docs/methods/diagnosis.md "Out-of-catalog terms".
#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "filter/diagnosis/diagnosis.hpp"
#include "models/noise_model.hpp"
#include "rig/session.hpp"

namespace sinscal {

/// One library term: the sensor axis it acts on, its function of the dwell's inputs, its
/// magnitude with sigma (in `unit`).
struct LibraryTerm {
  std::string sensor;   // "accel" or "gyro"
  int axis = 0;         // 0 x, 1 y, 2 z (body)
  std::string formula;  // "f_y f_z", "step after t = 612 s", "omega_x |omega_x|"
  std::string unit;     // "ug/g^2", "deg/h", "ppm/(deg/s)", ...
  double si_per_unit = 1.0;
  double value = 0.0;  // in `unit`
  double sigma = 0.0;  // in `unit`, scaled by the library fit's residual where it exceeds noise
  /// Other library terms this plan cannot tell from it (their columns, with the model's
  /// projected out, correlate beyond kAliasCorrelation): each with its own value and sigma.
  std::vector<LibraryTerm> aliases;
  /// What in a plan separates the term from a catalog family it shares a plan's data with (its
  /// kind's: turns at a second rate for the rate terms, ...), as the family table's separated_by.
  std::string separated_by;
  /// "accel x: 97 +- 6 ug/g^2 * f_y f_z"
  std::string text() const;
  /// "gyro y: omega_y^2 (library term)": the term as a member of a set a plan cannot separate.
  std::string name() const;
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
  /// The turns (a session's log read again): each segment from a dwell's middle to the next
  /// one's, the attitude the gyros integrate against the table's known attitude, whitened by the
  /// table's attitude error and the angle random walk; the model's columns projected out.
  int turn_segments = 0;
  double turns_chi2 = 0.0;      // its chi-square with the model
  double turns_dof = 0.0;       // its expected value (rows minus the model's share)
  double turns_quantile = 0.0;  // the chi-square quantile at kTurnsResidualLevel
  /// The turns' residual along the library column that holds most of it alone (z^2, chi-square
  /// of 1 dof under the noise model), tested at the Bonferroni quantile over the columns.
  std::string turns_term;
  double turns_term_z2 = 0.0;
  double turns_term_quantile = 0.0;
  bool turns_term_reject = false;
  /// The turns' residual along every library column alone, signed (z, as turns_term_z2 is its
  /// square), by the term's name: each at most N(0, 1) under the noise model, zero on average
  /// over sessions whatever the noise (the columns are functions of the table's known motion).
  std::vector<std::pair<std::string, double>> turns_term_z;
  /// turns_chi2 beyond its quantile, or turns_term_z2 beyond its: the turns hold what the model
  /// does not.
  bool turns_reject = false;
  std::string turns_signature;  // "turns: attitude residual chi2 ... ; largest after dwell ..."
};

/// The level of the turns' attitude-residual test.
constexpr double kTurnsResidualLevel = 0.99;

/// What the library needs of the turns: the session (its log is read again), the table's
/// attitude sigma per dwell (rad), the gyros' noise, the model the dwells' fit is a correction
/// to (null: zero).
struct LibraryTurns {
  const Session* session = nullptr;
  double attitude_sigma = 0.0;
  NoiseModel noise;
  const ImuErrorModel* about = nullptr;
  /// The log's temperatures (a ramp): the model's thermal columns take each sample's temperature
  /// against reference_temperature_c (deg C); with `thermal` the library adds the gyros' rates
  /// times the temperature (scale factor and misalignment linear in it, acting in the turns).
  bool thermal = false;
  double reference_temperature_c = 25.0;
  /// The table's known motion (the session's plan, rig/plan.hpp build_motion), built once for
  /// the session's many library fits and contests (library_turns_of); null: each fit builds it.
  std::shared_ptr<const Motion> motion;
};

/// `lt` with its motion built from the session's plan (none without a session or a plan).
LibraryTurns with_motion(LibraryTurns lt);

/// A catalog family against the library on the same held-out blocks (each dwell and each turn
/// segment left out in turn, its coefficients predicted from the others; the model `current`
/// projected out). The statistic is a fall of the held-out chi-square, in the residual's scale
/// (chi-square per row of the model with both, where above 1); a library term's gains are tested
/// against the chi-square quantile of 1 dof at 1 - alpha / (terms tried) (Bonferroni), the
/// family's against that of its dof at 1 - alpha. When both gain alone (the library sees the
/// family) and the family gains nothing once a term T is in, T explains the family's share of
/// the held-out data: better when T still gains with the family in (the family is replaced: not
/// named), else as well (the plan cannot tell them apart: T is the family's alternative, the
/// finding reported as the pair; this statement claims no finding of T: a T alone below its
/// Bonferroni level counts when it gains the quantile of 1 dof at 1 - alpha and predicts the
/// held-out data at least as well as the family alone).
struct HeldoutContest {
  int blocks = 0;            // dwells and turn segments
  int terms = 0;             // library terms tried (the catalog's own terms excluded)
  double before = 0.0;       // held-out chi-square of the model `current`
  double family = 0.0;       // with the family
  int family_dof = 0;        // its columns
  bool replaced = false;     // a library term explains the family's share better
  bool alternative = false;  // ... as well (and none better)
  LibraryTerm term;          // that term (its value and sigma with `current` and it alone)
  double term_alone = 0.0;   // held-out chi-square with the term instead of the family
  double both = 0.0;         // with the family and the term
  double term_gain = 0.0;    // (family - both) / scale
  double family_gain = 0.0;  // (term_alone - both) / scale
  double term_needed = 0.0;  // the quantiles the gains are tested against
  double family_needed = 0.0;
  /// With `alternative`: the other library terms that predict the held-out data as well as the
  /// family by the same test (each the family's alternative too), lowest held-out chi-square
  /// first. The set the plan cannot separate is the family, `term` and these.
  std::vector<LibraryTerm> others;
  /// "the library term gyro y: 52 +- 0.1 ppm/(deg/s) * omega_y^2 predicts the held-out dwells
  /// and turns better (...)"; empty when neither replaced nor an alternative.
  std::string reason() const;
};

/// The contest of the family's columns `family` (catalog indices) added to `current` against
/// every library term (alpha: the family-wise level); with `orientation_only` against the terms
/// that are functions of the orientation alone (the products of the specific force: a time
/// family's rivals on a plan that visits each orientation once, time_structure.hpp).
HeldoutContest contest_family(const DwellTests& dwells, const std::vector<int>& current,
                              const std::vector<int>& family, double alpha,
                              const LibraryTurns* turns = nullptr, bool orientation_only = false);

/// Fits the residual of the model `parameters` on the dwells (and with `turns`, on the turns)
/// against the library (alpha: the level of the held-out confirmation). Terms the model's columns
/// explain are projected out. With `select` false only the turns' test runs (the selection runs
/// when it rejects).
LibraryFit fit_term_library(const DwellTests& dwells, const std::vector<int>& parameters,
                            double alpha, const LibraryTurns* turns = nullptr, bool select = true);

}  // namespace sinscal
