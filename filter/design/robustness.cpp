#include "filter/design/robustness.hpp"

#include <cmath>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "rig/imu_sim.hpp"

namespace sinscal {

std::vector<Perturbation> standard_perturbations() {
  std::vector<Perturbation> out;
  out.push_back({"nominal", 1.0, Eigen::Vector3d::Zero(), 1.0});
  out.push_back({"table 2x worse", 2.0, Eigen::Vector3d::Zero(), 1.0});
  out.push_back({"reference 50 mm off the axes", 1.0, Eigen::Vector3d(0.05, 0.05, 0.05), 1.0});
  out.push_back({"noise 2x the profile's", 1.0, Eigen::Vector3d::Zero(), 2.0});
  return out;
}

namespace {

// One simulated session of the plan under `p`, calibrated: error / predicted sigma added per
// family.
void run_session(const Plan& plan, const SensorProfile& profile, const CalibratorOptions& ko,
                 const PlanPrediction& predicted, const Perturbation& p, std::uint64_t seed,
                 double rate_hz, std::map<std::string, std::pair<double, int>>& sum) {
  TableErrors table;
  table.attitude_sigma = p.table_factor * ko.attitude_sigma;
  table.seed = derive_seed(seed, 3);
  const Motion motion = build_motion(plan, plan.site, table);
  ImuErrorModel truth = profile.draw(derive_seed(seed, 1));
  for (int i = 0; i < 3; ++i) truth.accel_lever_arm_b.col(i) += p.reference_offset_b;
  NoiseModel noise = profile.noise;
  noise.gyro.white *= p.noise_factor;
  noise.accel.white *= p.noise_factor;
  SimulatorOptions so;
  so.rate_hz = rate_hz;
  so.noise_seed = derive_seed(seed, 2);
  ImuSimulator sim(motion, truth, noise, so);
  KalmanRunOptions run;
  run.align = false;
  run.nis_alarm_z = std::numeric_limits<double>::infinity();
  const KalmanRun r = run_kalman(design_session(plan, rate_hz), ko, &sim, run);
  const Eigen::VectorXd theta = truth.vector();
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    const CoefficientEstimate& e = predicted.run.estimates[i];
    if (e.status != CoefficientEstimate::Status::Estimated || !(e.sigma > 0.0)) continue;
    const double z = (r.estimates[i].value - theta(static_cast<Eigen::Index>(i))) / e.sigma;
    sum[cat[i].family].first += z * z;
    ++sum[cat[i].family].second;
  }
}

}  // namespace

std::vector<RobustnessRow> robustness(const Plan& plan, const SensorProfile& profile,
                                      const CalibratorOptions& options,
                                      const std::vector<Perturbation>& perturbations, int seeds,
                                      double rate_hz) {
  if (seeds < 2) throw std::invalid_argument("robustness: at least 2 seeds");
  DesignOptions d;
  d.rate_hz = rate_hz;
  const PlanPrediction predicted = predict_plan(plan, options, {}, d);
  std::vector<RobustnessRow> out;
  for (const Perturbation& p : perturbations) {
    std::map<std::string, std::pair<double, int>> sum;
    for (int k = 0; k < seeds; ++k)
      run_session(plan, profile, options, predicted, p, 1000 + static_cast<std::uint64_t>(k),
                  rate_hz, sum);
    RobustnessRow row;
    row.perturbation = p.name;
    for (const auto& [family, s] : sum) {
      const double rms = std::sqrt(s.first / s.second);
      row.rms_ratio[family] = rms;
      row.count[family] = s.second;
      if (rms > row.worst) {
        row.worst = rms;
        row.worst_family = family;
      }
    }
    out.push_back(row);
  }
  return out;
}

}  // namespace sinscal
