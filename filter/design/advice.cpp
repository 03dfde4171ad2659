#include "filter/design/advice.hpp"

#include <algorithm>
#include <cstdio>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

constexpr double kAdviceTurnRate = 10.0 * units::deg_per_s;  // of the appended turn

struct FamilySigma {
  double worst = 0.0, prior = 0.0;
  bool observed = true;
};

FamilySigma family_sigma(const std::vector<CoefficientEstimate>& est, const std::string& family) {
  FamilySigma f;
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (cat[i].family != family || est[i].status != CoefficientEstimate::Status::Estimated)
      continue;
    f.worst = std::max(f.worst, est[i].sigma);
    f.prior = std::max(f.prior, est[i].prior_sigma);
    f.observed = f.observed && est[i].observed();
  }
  return f;
}

std::vector<RotationStep> candidate_turns(double dwell) {
  std::vector<RotationStep> out;
  for (int axis = 0; axis < 3; ++axis)
    for (const double sign : {1.0, -1.0})
      for (const double angle : {90.0 * units::deg, 180.0 * units::deg}) {
        RotationStep st;
        st.kind = RotationStep::Axis::Body;
        st.axis_b = sign * Eigen::Vector3d::Unit(axis);
        st.axis_name = std::string(sign > 0 ? "+" : "-") + static_cast<char>('x' + axis);
        st.angle = angle;
        st.rate = kAdviceTurnRate;
        st.pause = dwell;
        out.push_back(st);
      }
  return out;
}

}  // namespace

std::vector<SeparationAdvice> separation_advice(const Plan& plan, const CalibratorOptions& options,
                                                const PlanPrediction& prediction, double rate_hz,
                                                double dwell) {
  std::vector<SeparationAdvice> out;
  if (plan.type != Plan::Type::Rotations) return out;
  std::vector<std::string> families;
  for (const auto& f : prediction.families)
    if (!family_sigma(prediction.run.estimates, f.family).observed) families.push_back(f.family);
  if (families.empty()) return out;
  DesignOptions d;
  d.rate_hz = rate_hz;
  for (const auto& family : families) {
    const FamilySigma before = family_sigma(prediction.run.estimates, family);
    out.push_back({family, before.worst, before.prior, "", before.worst, false});
  }
  for (const RotationStep& st : candidate_turns(dwell)) {
    Plan longer = plan;
    longer.steps.push_back(st);
    const PlanPrediction p = predict_plan(longer, options, {}, d);
    for (auto& a : out) {
      const FamilySigma after = family_sigma(p.run.estimates, a.family);
      if (after.worst < a.sigma_after) {
        char turn[96];
        std::snprintf(turn, sizeof turn, "%s %.0f deg, then %.0f s at rest", st.axis_name.c_str(),
                      st.angle / units::deg, dwell);
        a.turn = turn;
        a.sigma_after = after.worst;
        a.observed_after = after.observed;
      }
    }
  }
  return out;
}

}  // namespace sinscal
