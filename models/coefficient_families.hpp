// The one table of coefficient families. Everything that names, sizes, parses, switches, priors or
// reports a calibration coefficient reads it: the IMU error model's coefficient catalog, the sensor
// profile parser, the Kalman filter's state layout and priors, `--terms`, the result and monitor
// writers, the help text. A new error term is one entry here plus its physics in
// models/imu_error_model.cpp (TriadErrors::apply, ImuErrorModel::gyro_output / accel_output).
//
// Coefficient names are "<family>.<component>" ("gyro.bias.x", "accel.lever_arm.y.z"), or the
// family's name alone when it has one unnamed component ("time_delay"). Units and signs of every
// coefficient: docs/conventions.md.
#pragma once

#include <string>
#include <vector>

#include "models/config.hpp"

namespace sinscal {

class ImuErrorModel;

/// Which sensor output a family's coefficients enter.
enum class FamilyOutput {
  Gyro,   // the gyro outputs
  Accel,  // the accelerometer outputs
  Delay,  // the time of the accelerometer samples relative to the gyro samples
};

struct CoefficientFamily {
  std::string name;  // "gyro.bias"
  /// Key of the sensor profile that gives the family's range ("gyro.bias" is `[gyro] bias`).
  std::string profile_key;
  /// Component names; empty: one coefficient named like the family.
  std::vector<std::string> components;
  /// Units a profile may use; the first is the unit of results, reports and monitor files.
  std::vector<UnitToken> units;
  FamilyOutput output = FamilyOutput::Gyro;
  /// Base families are always estimated; extended ones are switched on by the sensor profile (a
  /// range given) or by `term` in `--terms`. Several families may share one term.
  bool base = false;
  std::string term;
  /// Kalman-filter prior 1-sigma (SI) when the sensor profile gives no range for the family.
  double default_prior = 0.0;
  /// The triad's bias instability and rate (acceleration) random walk make these states wander.
  bool wanders_with_bias_noise = false;
  std::string help;  // one line: what the family is
  /// The SI value of component k inside a model.
  double& (*value)(ImuErrorModel& model, int component) = nullptr;
  /// Extended families: the plan feature that separates the family from the base coefficients
  /// (named by the diagnosis when a plan cannot).
  std::string separated_by;
  /// Physical range: the largest magnitude (SI) a coefficient of the family (and its sigma) can
  /// have for any sensor this tool calibrates, consumer MEMS included, with a margin. Beyond it
  /// the figure is not a calibration (a wrong unit or scale, a broken estimate, a damaged file):
  /// results are refused by every reader of outputs (report/result.hpp check_plausible).
  double plausible_max = 0.0;

  /// A thermal family (terms thermal, thermal2, thermal3): it needs the sensors' temperatures.
  bool thermal() const { return term.rfind("thermal", 0) == 0; }
  int size() const { return components.empty() ? 1 : static_cast<int>(components.size()); }
  /// Name of component k ("gyro.bias.x"; the family's name for a single unnamed component).
  std::string coefficient_name(int k) const;
  const std::string& unit() const { return units.front().token; }
  double si_per_unit() const { return units.front().si_per_unit; }
};

/// Every family, in the contract order of coefficients (results, state blocks, catalog).
const std::vector<CoefficientFamily>& coefficient_families();
/// One family by name; throws std::invalid_argument naming the known families.
const CoefficientFamily& coefficient_family_info(const std::string& family);
/// The family of a coefficient name: "accel.lever_arm.x.y" -> "accel.lever_arm"; throws
/// std::invalid_argument for an unknown coefficient.
std::string coefficient_family(const std::string& coefficient);
/// The `--terms` names, each with the families it switches, in table order.
std::vector<std::pair<std::string, std::vector<std::string>>> extended_terms();
/// "k2 (accel.k2: quadratic scale factor), ..." for help texts.
std::string extended_terms_help();

}  // namespace sinscal
