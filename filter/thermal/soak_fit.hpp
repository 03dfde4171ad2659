// Thermal calibration from soaks: one calibration per soak (each at its own temperature), then a
// weighted least-squares fit of each coefficient against temperature with the full covariance of
// the per-soak estimates. Each family's polynomial degree is chosen by a test, not by hand: the
// degree rises while the drop in chi-square is beyond the chi-square quantile, at the significance
// over the number of families, of the family's size (the family table says how far: a family F has
// degrees 1 ... d when F_temp1 ... F_tempd exist). Degree k of family F is the thermal family
// F_tempk (models/coefficient_families.hpp); degree 0 is F itself at the reference temperature T0.
// docs/methods/thermal.md.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "rig/io/log_io.hpp"

namespace sinscal {

/// One soak's calibration: the coefficients it determined and their covariance, at its
/// temperature.
struct SoakEstimate {
  std::string name;                  // the soak's session
  double accel_temperature_c = 0.0;  // mean over the soak's log (deg C)
  double gyro_temperature_c = 0.0;
  std::vector<int> catalog;    // coefficient_catalog() indices
  Eigen::VectorXd value;       // SI, in `catalog` order
  Eigen::MatrixXd covariance;  // SI
};

/// A log's temperatures over a soak: mean, and the span with where it happened.
struct SoakTemperature {
  double accel_mean_c = 0.0, gyro_mean_c = 0.0;
  double min_c = 0.0, max_c = 0.0;  // over both triads
  double t_min = 0.0, t_max = 0.0;  // s: when
  std::size_t line_min = 0, line_max = 0;
  std::string file_min, file_max;
  std::size_t samples = 0;
};
/// Reads a log once for its temperatures; throws LogError when it has none.
SoakTemperature measure_soak_temperature(const LogFormat& log);

struct ThermalFitOptions {
  double reference_temperature_c = 25.0;  // T0
  int max_degree = 3;                     // the family table allows at most 3
  /// Of the whole choice: each family's tests at significance / families (Bonferroni), so a fit
  /// whose truth has the degrees the table allows takes a degree too many in at most this share.
  double significance = 0.01;
};

/// How one family's degree was chosen.
struct ThermalDegreeTest {
  std::string family;        // "gyro.bias"
  int degree = 0;            // chosen
  int max_degree = 0;        // allowed (family table, soaks)
  std::vector<double> chi2;  // the family's own fit at degree 0, 1, ... (tried)
  int dof_step = 0;          // the family's size: the dof of each step's test
  double threshold = 0.0;    // chi-square quantile a step had to beat
};

struct ThermalFit {
  ThermalFitOptions options;
  std::vector<ThermalDegreeTest> degrees;
  /// The fitted coefficients (catalog indices: families at T0 and their thermal families), values
  /// and joint covariance (SI).
  std::vector<int> catalog;
  Eigen::VectorXd value;
  Eigen::MatrixXd covariance;
  double chi2 = 0.0;  // of the joint fit
  int dof = 0;
  double p_value = 1.0;
  /// The degree chosen for `family` (-1: not fitted or no degree chosen: fit_soaks_with).
  int degree(const std::string& family) const;
  /// Coefficient `catalog_index` (a family's, not a thermal one's) at `temperature_c` from the
  /// fit: value and sigma (SI); the sum over its thermal coefficients in the fit.
  std::pair<double, double> at(int catalog_index, double temperature_c) const;
  /// The fit's prediction of a soak's `coefficients` (catalog indices, not thermal ones) at the
  /// soak's temperatures (each family at its triad's): values and their covariance from the fit
  /// (SI).
  std::pair<Eigen::VectorXd, Eigen::MatrixXd> predict(const SoakEstimate& soak,
                                                      const std::vector<int>& coefficients) const;
};

/// Fits the soaks (at least 2, sharing their estimated coefficients: those all soaks have).
/// Throws std::invalid_argument naming the problem (too few soaks, a singular covariance).
ThermalFit fit_soaks(const std::vector<SoakEstimate>& soaks, const ThermalFitOptions& options);

/// The joint fit of a chosen model: every coefficient the soaks share at T0, plus the given
/// thermal families (each with the components whose coefficient at T0 the soaks share; no degree
/// test). Throws std::invalid_argument as fit_soaks, and for a name that is not a thermal family.
ThermalFit fit_soaks_with(const std::vector<SoakEstimate>& soaks,
                          const std::vector<std::string>& thermal_families,
                          double reference_temperature_c);

/// The thermal family of degree `degree` of `family` ("gyro.bias", 2: "gyro.bias_temp2"), and
/// whether the family table has it.
std::string thermal_family_name(const std::string& family, int degree);
bool thermal_family_exists(const std::string& family, int degree);
/// The family and degree of a polynomial thermal family ("accel.scale_temp2": {"accel.scale",
/// 2}); {"", 0} for any other name (the gyro bias in dT/dt among them).
std::pair<std::string, int> thermal_family_parts(const std::string& name);

}  // namespace sinscal
