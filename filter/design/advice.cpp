#include "filter/design/advice.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "rig/table.hpp"

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

// One candidate: the plan with something appended, and its text.
struct Candidate {
  Plan plan;
  std::string text;
};

std::vector<Candidate> candidate_turns(const Plan& plan, double dwell) {
  std::vector<Candidate> out;
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
        Candidate c{plan, ""};
        c.plan.steps.push_back(st);
        char text[96];
        std::snprintf(text, sizeof text, "%s %.0f deg, then %.0f s at rest", st.axis_name.c_str(),
                      angle / units::deg, dwell);
        c.text = text;
        out.push_back(std::move(c));
      }
  return out;
}

// The 24 orientations with a body axis up and another north (ned-frd: C_b_n = B^T, B the body
// axes that point north, east, down), those the plan's table reaches, appended with the plan's
// median dwell.
std::vector<Candidate> candidate_orientations(const Plan& plan) {
  std::vector<double> dwells;
  for (const auto& o : plan.orientations) dwells.push_back(o.dwell);
  std::nth_element(dwells.begin(), dwells.begin() + static_cast<std::ptrdiff_t>(dwells.size() / 2),
                   dwells.end());
  const double dwell = dwells[dwells.size() / 2];
  const Table table(plan.table);
  const char* names[3] = {"x", "y", "z"};
  std::vector<Candidate> out;
  for (int up = 0; up < 6; ++up)
    for (int north = 0; north < 6; ++north) {
      if (north / 2 == up / 2) continue;
      const Eigen::Vector3d u = (up % 2 ? -1.0 : 1.0) * Eigen::Vector3d::Unit(up / 2);
      const Eigen::Vector3d v = (north % 2 ? -1.0 : 1.0) * Eigen::Vector3d::Unit(north / 2);
      Eigen::Matrix3d B;
      B.col(0) = v;
      B.col(2) = -u;
      B.col(1) = B.col(2).cross(B.col(0));
      // Axis-aligned: the angles are multiples of 90 deg in every convention; rounded, so that
      // the plan's angles give the orientation exactly (near pitch 90 deg the inverse is not).
      EulerAngles e = euler_from_C_b_n(plan.convention, B.transpose());
      for (double* a : {&e.heading, &e.pitch, &e.roll})
        *a = std::round(*a / (90.0 * units::deg)) * (90.0 * units::deg);
      const Eigen::Matrix3d C_b_n = C_b_n_from_euler(plan.convention, e);
      if ((C_b_n - B.transpose()).cwiseAbs().maxCoeff() > 1e-9) continue;
      try {
        (void)table.angles_for(C_b_n);
      } catch (const UnreachableOrientation&) {
        continue;
      }
      PlanOrientation o;
      o.angles = e;
      o.dwell = dwell;
      o.label = "advice";
      Candidate c{plan, ""};
      c.plan.orientations.push_back(o);
      // The axis that points up and the one that points north, each named with a + sign.
      char text[160];
      std::snprintf(text, sizeof text,
                    "body +%s %s, +%s %s (heading %.0f, pitch %.0f, roll %.0f deg), %.0f s",
                    names[up / 2], up % 2 ? "down" : "up", names[north / 2],
                    north % 2 ? "south" : "north", e.heading / units::deg + 0.0,
                    e.pitch / units::deg + 0.0, e.roll / units::deg + 0.0, dwell);
      c.text = text;
      out.push_back(std::move(c));
    }
  return out;
}

}  // namespace

std::vector<SeparationAdvice> separation_advice(const Plan& plan, const CalibratorOptions& options,
                                                const PlanPrediction& prediction, double rate_hz,
                                                double dwell) {
  std::vector<SeparationAdvice> out;
  const bool rotations = plan.type == Plan::Type::Rotations;
  for (const auto& f : prediction.families) {
    const FamilySigma before = family_sigma(prediction.run.estimates, f.family);
    if (!before.observed)
      out.push_back({f.family, before.worst, before.prior, rotations ? "turn" : "orientation", "",
                     before.worst, false});
  }
  if (out.empty()) return out;
  DesignOptions d;
  d.rate_hz = rate_hz;
  for (const Candidate& c :
       rotations ? candidate_turns(plan, dwell) : candidate_orientations(plan)) {
    const PlanPrediction p = predict_plan(c.plan, options, {}, d);
    for (auto& a : out) {
      const FamilySigma after = family_sigma(p.run.estimates, a.family);
      // An improvement of at least 1 % counts (not the rounding of an unchanged sigma).
      if (after.worst < a.sigma_after && after.worst < 0.99 * a.sigma_before) {
        a.turn = c.text;
        a.sigma_after = after.worst;
        a.observed_after = after.observed;
      }
    }
  }
  return out;
}

}  // namespace sinscal
