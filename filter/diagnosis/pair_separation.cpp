#include "filter/diagnosis/pair_separation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "filter/design/prediction.hpp"
#include "filter/diagnosis/diagnosis_kalman.hpp"
#include "models/coefficient_families.hpp"
#include "rig/imu_sim.hpp"
#include "rig/motion.hpp"

namespace sinscal {

namespace {

std::vector<int> components_of(const std::string& family) {
  std::vector<int> out;
  const auto& cat = coefficient_catalog();
  for (std::size_t k = 0; k < cat.size(); ++k)
    if (cat[k].family == family) out.push_back(static_cast<int>(k));
  return out;
}

// The filter's options with both families estimated, their priors widened.
CalibratorOptions with_pair(const CalibratorOptions& model, const std::vector<int>& ca,
                            const std::vector<int>& cb) {
  CalibratorOptions o = model;
  const auto& cat = coefficient_catalog();
  o.layout.set(cat[static_cast<std::size_t>(ca.front())].family, true);
  o.layout.set(cat[static_cast<std::size_t>(cb.front())].family, true);
  if (o.initial_sigma.size() < cat.size()) o.initial_sigma.resize(cat.size(), 0.0);
  for (const auto& set : {ca, cb})
    for (int k : set) {
      double& s = o.initial_sigma[static_cast<std::size_t>(k)];
      if (!(s > 0.0))
        s = coefficient_family_info(cat[static_cast<std::size_t>(k)].family).default_prior;
      s *= kPairPriorWidening;
    }
  return o;
}

// The rows of `catalog` (the run's covariance_catalog) of the components `c`.
std::vector<Eigen::Index> rows_of(const std::vector<int>& catalog, const std::vector<int>& c) {
  std::vector<Eigen::Index> rows;
  for (int k : c) {
    const auto it = std::find(catalog.begin(), catalog.end(), k);
    if (it == catalog.end())
      throw std::runtime_error(
          "pair_separation: " + coefficient_catalog()[static_cast<std::size_t>(k)].name +
          " is not among the filter's estimated coefficients");
    rows.push_back(static_cast<Eigen::Index>(it - catalog.begin()));
  }
  return rows;
}

// The held-out turns' chi-square of `model` on `plan` over an ideal IMU with the errors `truth`
// and no noise (negative: no turns to hold out).
double noise_free_heldout(const Plan& plan, const CalibratorOptions& model,
                          const ImuErrorModel& truth, double rate_hz) {
  const Session session = design_session(plan, rate_hz);
  const Motion motion = build_motion(plan, plan.site);
  const auto run = [&](const CalibratorOptions& o) {
    SimulatorOptions sim;
    sim.rate_hz = rate_hz;
    sim.noise = false;
    ImuSimulator ideal(motion, truth, NoiseModel{}, sim);
    KalmanRunOptions ro;
    ro.align = false;
    ro.nis_alarm_z = std::numeric_limits<double>::infinity();
    KalmanRun r = run_kalman(session, o, &ideal, ro);
    if (!r.stopped.empty()) throw std::runtime_error("pair_separation: " + r.stopped);
    return r;
  };
  const HeldoutTurns h = heldout_turns(session, design_filter_options(model), run);
  return h.turns > 0 ? h.chi2 : -1.0;
}

// The held-out turns' figures of `s` (pair_separation).
void heldout_figures(PairSeparation& s, const Plan& plan, const CalibratorOptions& model,
                     const std::vector<int>& ca, const std::vector<double>& size, double rate_hz) {
  ImuErrorModel truth;
  auto refs = truth.coefficient_refs();
  for (std::size_t i = 0; i < ca.size(); ++i)
    *refs[static_cast<std::size_t>(ca[i])].second = size[i];
  // Each member alone: the diagnosis's model may hold the pick already.
  for (const auto& [family, out] :
       {std::make_pair(s.a, &s.heldout_a), std::make_pair(s.b, &s.heldout_b)}) {
    CalibratorOptions m = model;
    m.layout.set(s.a, false);
    m.layout.set(s.b, false);
    m.layout.set(family, true);
    *out = noise_free_heldout(plan, m, truth, rate_hz);
  }
}

}  // namespace

// `model` without its thermal families: the plan's ideal IMU has no temperature (a chamber's
// soak, each at one temperature, diagnosed as a table session).
static CalibratorOptions without_thermal(const CalibratorOptions& model) {
  CalibratorOptions o = model;
  for (const auto& fam : coefficient_families())
    if (fam.thermal() && o.layout.on(fam.name)) o.layout.set(fam.name, false);
  return o;
}

PairSeparation pair_separation(const Plan& plan, const CalibratorOptions& with_thermal,
                               const std::string& a, const std::string& b,
                               const std::vector<double>& size, bool heldout, double rate_hz) {
  const CalibratorOptions model = without_thermal(with_thermal);
  const std::vector<int> ca = components_of(a), cb = components_of(b);
  if (ca.empty() || ca.size() != cb.size() || size.size() != ca.size())
    throw std::invalid_argument("pair_separation: " + a + " and " + b +
                                " need the same number of components and a size for each");
  DesignOptions d;
  d.rate_hz = rate_hz;
  d.history_interval = 1e9;  // no history needed
  const PlanPrediction p = predict_plan(plan, with_pair(model, ca, cb), {}, d);
  const Eigen::MatrixXd& P = p.run.coefficient_covariance;
  const std::vector<Eigen::Index> ra = rows_of(p.run.covariance_catalog, ca),
                                  rb = rows_of(p.run.covariance_catalog, cb);
  PairSeparation s;
  s.plan = plan.name;
  s.a = a;
  s.b = b;
  const auto n = static_cast<Eigen::Index>(ca.size());
  Eigen::MatrixXd Paa(n, n);
  Eigen::VectorXd x(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    x(i) = size[static_cast<std::size_t>(i)];
    for (Eigen::Index j = 0; j < n; ++j)
      Paa(i, j) = P(ra[static_cast<std::size_t>(i)], ra[static_cast<std::size_t>(j)]);
    const double r = P(ra[static_cast<std::size_t>(i)], rb[static_cast<std::size_t>(i)]) /
                     std::sqrt(P(ra[static_cast<std::size_t>(i)], ra[static_cast<std::size_t>(i)]) *
                               P(rb[static_cast<std::size_t>(i)], rb[static_cast<std::size_t>(i)]));
    s.correlations.push_back(r);
    s.correlation = std::max(s.correlation, std::abs(r));
  }
  s.expected_gap = x.dot(Paa.ldlt().solve(x));
  if (heldout) heldout_figures(s, plan, model, ca, size, rate_hz);
  return s;
}

Plan split_turns(const Plan& plan) {
  Plan out = plan;
  if (plan.type != Plan::Type::Rotations) return out;
  out.steps.clear();
  for (const RotationStep& s : plan.steps) {
    if (s.kind != RotationStep::Axis::Body || s.constant_rate) {
      out.steps.push_back(s);
      continue;
    }
    RotationStep half = s;
    half.angle = 0.5 * s.angle;
    // Half the time, or the shortest the table's acceleration allows (a triangle of rate).
    if (s.duration > 0.0 && plan.move_accel > 0.0)
      half.duration = std::max(0.5 * s.duration, 2.02 * std::sqrt(half.angle / plan.move_accel));
    out.steps.push_back(half);
    out.steps.push_back(half);
  }
  out.name = plan.name + " with its turns split in halves";
  return out;
}

std::string separation_statement(const PairSeparation& here, const PairSeparation* other,
                                 double need, double session_gap) {
  // The figure the pick needs: the held-out turns' expected difference, else all the data's.
  const double gap = here.heldout() ? here.heldout_gap() : here.expected_gap;
  char figures[300];
  std::snprintf(figures, sizeof figures,
                "%s: correlation %.4f of their estimates on the dwells and turns; expected "
                "held-out turns' chi2 difference %.3g at the size found, %.3g needed; %.3g over "
                "all the plan's data",
                here.plan.c_str(), here.correlation, gap, need, here.expected_gap);
  char b[900];
  if (gap >= need) {
    std::snprintf(b, sizeof b, "%s or %s: separable on this plan in expectation (%s)%s",
                  here.a.c_str(), here.b.c_str(), figures,
                  session_gap < need ? "; close on this session by the noise" : "");
    return b;
  }
  char noise[200] = "";
  if (session_gap >= need)
    std::snprintf(noise, sizeof noise,
                  "; this session's held-out difference of %.3g is the noise's, not the plan's",
                  session_gap);
  int n = std::snprintf(b, sizeof b, "%s or %s: not separable on this plan (%s)%s", here.a.c_str(),
                        here.b.c_str(), figures, noise);
  if (n < 0 || n >= static_cast<int>(sizeof b)) return b;
  if (other)
    std::snprintf(b + n, sizeof b - static_cast<std::size_t>(n),
                  "; a plan with tilted dwells separates them: e.g. %s (correlation %.4f, "
                  "expected chi2 difference %.3g over its dwells and turns)",
                  other->plan.c_str(), other->correlation, other->expected_gap);
  else
    std::snprintf(b + n, sizeof b - static_cast<std::size_t>(n),
                  "; a plan with tilted dwells separates them: e.g. turns split in 45 deg halves "
                  "with a dwell between (an axis at 45 deg to gravity: f^2 = g^2 / 2 against "
                  "|f| = 0.707 g)");
  return b;
}

}  // namespace sinscal
