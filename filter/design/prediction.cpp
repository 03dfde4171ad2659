#include "filter/design/prediction.hpp"

#include <algorithm>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "rig/imu_sim.hpp"

namespace sinscal {

namespace {

// Per family: the largest sigma of its estimated coefficients in one record.
std::map<std::string, std::pair<double, std::string>> worst_by_family(
    const std::vector<CoefficientEstimate>& estimates) {
  std::map<std::string, std::pair<double, std::string>> out;
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (estimates[i].status != CoefficientEstimate::Status::Estimated) continue;
    auto& w = out[cat[i].family];
    if (w.second.empty() || estimates[i].sigma > w.first) w = {estimates[i].sigma, cat[i].name};
  }
  return out;
}

std::vector<FamilyPrediction> family_predictions(const PlanPrediction& p,
                                                 const std::map<std::string, double>& targets) {
  const auto worst = worst_by_family(p.run.estimates);
  const auto& cat = coefficient_catalog();
  std::vector<FamilyPrediction> out;
  for (const auto& fam : coefficient_families()) {
    const auto w = worst.find(fam.name);
    if (w == worst.end()) continue;
    FamilyPrediction f;
    f.family = fam.name;
    const auto t = targets.find(fam.name);
    f.target = t == targets.end() ? 0.0 : t->second;
    f.worst_sigma = w->second.first;
    f.worst = w->second.second;
    for (std::size_t i = 0; i < cat.size(); ++i)
      if (cat[i].family == fam.name &&
          p.run.estimates[i].status == CoefficientEstimate::Status::Estimated &&
          !p.run.estimates[i].observed())
        f.observed = false;
    if (f.target > 0.0 && f.worst_sigma <= f.target) {
      // Backwards through the history: the first record of the last run below the target.
      f.reached_at = p.duration;
      for (auto it = p.history.rbegin(); it != p.history.rend(); ++it) {
        const auto record = worst_by_family(it->estimates);
        const auto wr = record.find(fam.name);
        if (wr == record.end() || wr->second.first > f.target) break;
        f.reached_at = it->t;
      }
    }
    out.push_back(f);
  }
  return out;
}

}  // namespace

bool PlanPrediction::meets_targets() const {
  return std::all_of(families.begin(), families.end(),
                     [](const FamilyPrediction& f) { return f.meets_target(); });
}

std::optional<std::pair<std::string, double>> PlanPrediction::last_to_reach() const {
  std::optional<std::pair<std::string, double>> last;
  for (const auto& f : families) {
    if (f.target <= 0.0) continue;
    if (!f.reached_at) return std::nullopt;
    if (!last || *f.reached_at > last->second) last = std::make_pair(f.family, *f.reached_at);
  }
  return last;
}

CalibratorOptions design_filter_options(const CalibratorOptions& options) {
  CalibratorOptions o = options;
  o.time_offset = 0.0;
  o.initial_model.reset();  // linearized about the truth: zero errors
  o.static_from = CalibratorOptions::StaticFrom::Plan;
  o.use_table_angles = false;
  return o;
}

Session design_session(const Plan& plan, double rate_hz) {
  if (!plan.has_site)
    throw std::invalid_argument(plan.path +
                                ": the plan has no [site]: design needs the latitude "
                                "and height the table stands at");
  Session s;
  s.path = plan.path;
  s.name = plan.name;
  s.site = plan.site;
  s.rate_hz = rate_hz;
  s.plan = plan;
  s.log = LogFormat::native_format("<ideal IMU of " + plan.path + ">", rate_hz);
  return s;
}

PlanPrediction predict_plan(const Plan& plan, const CalibratorOptions& options,
                            const std::map<std::string, double>& targets,
                            const DesignOptions& design) {
  if (!(design.rate_hz > 0.0 && design.history_interval > 0.0))
    throw std::invalid_argument("design: the rate and the history interval must be positive");
  const Session session = design_session(plan, design.rate_hz);
  const Motion motion = build_motion(plan, plan.site);
  SimulatorOptions sim;
  sim.rate_hz = design.rate_hz;
  sim.noise = false;
  ImuSimulator ideal(motion, ImuErrorModel{}, NoiseModel{}, sim);
  const CalibratorOptions o = design_filter_options(options);
  PlanPrediction p;
  p.duration = motion.duration();
  KalmanRunOptions run;
  run.sigma_targets = targets;
  run.align = false;
  run.nis_alarm_z = std::numeric_limits<double>::infinity();
  run.monitor_interval = design.history_interval;
  run.monitor = [&p](const MonitorRecord& r) { p.history.push_back(r); };
  p.run = run_kalman(session, o, &ideal, run);
  if (!p.run.stopped.empty()) throw std::runtime_error("design: " + p.run.stopped);
  p.families = family_predictions(p, targets);
  return p;
}

}  // namespace sinscal
