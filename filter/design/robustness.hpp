// Plan design, robustness: how the predicted sigmas of a plan hold when the world differs from
// the design's assumptions. Simulated sessions of the plan (coefficients drawn from the profile,
// its noise) are calibrated by the design's filter; per family, the RMS of error / predicted
// sigma over seeds and components is reported for the nominal world (it confirms the
// prediction: near 1) and for each perturbation: a table worse than its description, the IMU's
// reference point off the table's axes, noise above the profile's.
// docs/methods/design.md "Robustness".
#pragma once

#include <Eigen/Core>
#include <map>
#include <string>
#include <vector>

#include "filter/design/prediction.hpp"
#include "models/sensor_profile.hpp"

namespace sinscal {

struct Perturbation {
  std::string name;
  double table_factor = 1.0;  // the table sets each dwell to this times its stated accuracy
  /// The IMU's reference point this far from the axes' intersection (m, body axes): every
  /// accelerometer's lever arm grows by it (the filter estimates the lever arms).
  Eigen::Vector3d reference_offset_b = Eigen::Vector3d::Zero();
  double noise_factor = 1.0;  // white noise of both triads this times the profile's
};

/// The perturbations `design --robustness` runs: nominal, the table 2x worse, the reference point
/// 50 mm off the axes on each body axis, the noise 2x the profile's.
std::vector<Perturbation> standard_perturbations();

struct RobustnessRow {
  std::string perturbation;
  std::map<std::string, double> rms_ratio;  // family: RMS of error / predicted sigma
  std::map<std::string, int> count;         // family: errors in it
  double worst = 0.0;                       // the largest ratio of the row
  std::string worst_family;
};

/// `seeds` sessions per perturbation at `rate_hz`, simulated and calibrated in memory. Throws
/// std::invalid_argument for fewer than 2 seeds.
std::vector<RobustnessRow> robustness(const Plan& plan, const SensorProfile& profile,
                                      const CalibratorOptions& options,
                                      const std::vector<Perturbation>& perturbations, int seeds,
                                      double rate_hz);

}  // namespace sinscal
