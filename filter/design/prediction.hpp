// Plan design, first part: the accuracy a plan will give, predicted without data. The Kalman
// filter of `calibrate --method kf` run over the plan's truth motion with an ideal IMU: with zero
// errors every innovation is zero and what the run produces is the covariance a calibration of
// the plan reaches. docs/methods/design.md "Prediction".
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "filter/kalman/kalman_run.hpp"
#include "rig/plan.hpp"

namespace sinscal {

struct DesignOptions {
  /// Sample rate of the ideal IMU (Hz). The prediction depends on it only through the
  /// discretization of the error dynamics: on rot19 with nav-fog-extended every sigma at 20, 50
  /// and 200 Hz is within 0.49 %, 0.12 % and 0.06 % of the one at 100 Hz.
  double rate_hz = 50.0;
  double history_interval = 1.0;  // s of plan time between records of the sigmas
};

/// What the plan gives one family of coefficients.
struct FamilyPrediction {
  std::string family;
  double target = 0.0;       // SI (0: the profile sets none)
  double worst_sigma = 0.0;  // SI, the largest predicted sigma of its estimated coefficients
  std::string worst;         // that coefficient's name
  /// Plan time (s) from which every coefficient of the family stays below its target.
  std::optional<double> reached_at;
  bool observed = true;  // every coefficient of the family observed (CoefficientEstimate)
  bool meets_target() const { return target <= 0.0 || worst_sigma <= target; }
};

struct PlanPrediction {
  KalmanRun run;  // the covariance pass: estimates hold the predicted sigmas (values zero)
  std::vector<MonitorRecord> history;      // sigmas over plan time
  std::vector<FamilyPrediction> families;  // estimated families, in the family table's order
  double duration = 0.0;                   // s, of the plan's motion
  /// Every family with a target meets it.
  bool meets_targets() const;
  /// The last family to reach its target and when (empty when some family never does).
  std::optional<std::pair<std::string, double>> last_to_reach() const;
};

/// A session that exists only in memory: the plan on its site at `rate_hz`, no log, no sensor
/// file (the options carry the profile's content).
Session design_session(const Plan& plan, double rate_hz);

/// The calibration's options as the design runs them: linearized about the truth (zero errors),
/// the dwells from the plan's timing, no log time offset, no table-angle columns.
CalibratorOptions design_filter_options(const CalibratorOptions& options);

/// The covariance pass over `plan`. `options`: as the calibration would run (from the sensor
/// profile and the table); `targets`: sigma targets by family (SI). Throws std::invalid_argument
/// for a plan without a site.
PlanPrediction predict_plan(const Plan& plan, const CalibratorOptions& options,
                            const std::map<std::string, double>& targets,
                            const DesignOptions& design = {});

}  // namespace sinscal
