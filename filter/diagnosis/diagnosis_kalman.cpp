#include "filter/diagnosis/diagnosis_kalman.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

#include "filter/diagnosis/diagnosis.hpp"
#include "models/coefficient_families.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

namespace {

KalmanRun run_checked(const Session& session, const CalibratorOptions& options,
                      const std::string& what) {
  // The divergence alarm is off: a missing effect of the turns trips it, and the diagnosis wants
  // the innovations of the whole session.
  KalmanRunOptions run;
  run.nis_alarm_z = std::numeric_limits<double>::infinity();
  // A model to start from (filter/diagnosis/diagnosis_table.hpp: linearize) carries the mounting
  // already.
  run.align = !options.initial_model.has_value();
  KalmanRun r = run_kalman(session, options, nullptr, run);
  if (!r.stopped.empty())
    throw std::runtime_error("Kalman filter " + what + " stopped: " + r.stopped);
  if (!r.diverged.empty())
    throw std::runtime_error("Kalman filter " + what + " diverged: " + r.diverged);
  return r;
}

// W and its degrees of freedom for the coefficients `catalog` of run `r`. With prior-normalized
// coefficients u = x / sigma0 and posterior covariance M = D P D (D = 1 / sigma0), the estimate
// of an effect that is absent (true value zero) has covariance M - M^2 (the filter's gain times
// the measurement noise: P H^T R^-1 H P = P - P P0^-1 P); along an eigenvector of M with
// eigenvalue mu (the fraction of the prior variance the data left) that is mu (1 - mu).
void wald(const KalmanRun& r, double separable_remaining, KalmanCandidateTest& c) {
  const auto m = static_cast<Eigen::Index>(c.catalog.size());
  std::vector<Eigen::Index> at;
  for (int k : c.catalog) {
    const auto it = std::find(r.covariance_catalog.begin(), r.covariance_catalog.end(), k);
    if (it == r.covariance_catalog.end())
      throw std::logic_error("diagnose_kalman: candidate coefficient not in the filter's state");
    at.push_back(it - r.covariance_catalog.begin());
  }
  Eigen::VectorXd u(m), d(m);
  for (Eigen::Index i = 0; i < m; ++i) {
    const auto& e = r.estimates[static_cast<std::size_t>(c.catalog[static_cast<std::size_t>(i)])];
    d(i) = 1.0 / e.prior_sigma;
    u(i) = e.value * d(i);
  }
  Eigen::MatrixXd M(m, m);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < m; ++j)
      M(i, j) = r.coefficient_covariance(at[static_cast<std::size_t>(i)],
                                         at[static_cast<std::size_t>(j)]) *
                d(i) * d(j);
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(M);
  c.dof = 0;
  double w = 0.0;
  for (Eigen::Index k = 0; k < m; ++k) {
    const double mu = std::max(es.eigenvalues()(k), 0.0);
    if (mu > separable_remaining) continue;
    const double p = es.eigenvectors().col(k).dot(u);
    w += p * p / std::max(mu * (1.0 - mu), std::numeric_limits<double>::min());
    ++c.dof;
  }
  c.nis_scale = std::max(1.0, r.nis_per_dof);
  w /= c.nis_scale;
  c.test = "wald";
  c.statistic = w;
  if (c.dof > 0) chi2_verdict(c, "wald", w);
}

// Largest move of an estimated coefficient of `before` (other than the candidate's), in sigma.
double base_shift(const KalmanRun& before, const KalmanRun& with) {
  double shift = 0.0;
  for (std::size_t k = 0; k < before.estimates.size(); ++k) {
    const auto& a = before.estimates[k];
    if (a.status != CoefficientEstimate::Status::Estimated || !(a.sigma > 0.0)) continue;
    shift = std::max(shift, std::abs(with.estimates[k].value - a.value) / a.sigma);
  }
  return shift;
}

KalmanCandidateTest test_candidate(const Session& session, const CalibratorOptions& current,
                                   const KalmanRun& before, const std::string& family,
                                   const KalmanDiagnosisOptions& o, KalmanRun& r) {
  KalmanCandidateTest c;
  c.family = family;
  c.separated_by = coefficient_family_info(family).separated_by;
  CalibratorOptions with = current;
  with.layout.set(family, true);
  try {
    r = run_checked(session, with, "with " + family);
  } catch (const std::runtime_error& e) {
    c.failed = e.what();
    return c;
  }
  const auto& cat = coefficient_catalog();
  for (std::size_t k = 0; k < cat.size(); ++k)
    if (cat[k].family == family && r.estimates[k].status == CoefficientEstimate::Status::Estimated)
      c.catalog.push_back(static_cast<int>(k));
  c.estimates = r.estimates;
  c.nis_per_dof = r.nis_per_dof;
  c.log_likelihood = r.log_likelihood;
  c.base_shift_sigma = base_shift(before, r);
  wald(r, o.separable_remaining, c);
  return c;
}

void check_candidates(const CalibratorOptions& base, const std::vector<std::string>& candidates) {
  for (const auto& f : candidates) {
    const CoefficientFamily& info = coefficient_family_info(f);  // throws for unknown
    if (info.base)
      throw std::invalid_argument("diagnose_kalman: " + f + " is a base family, not a candidate");
    if (base.layout.on(f))
      throw std::invalid_argument("diagnose_kalman: " + f + " is already in the model");
  }
}

}  // namespace

HeldoutTurns heldout_turns(const Session& session, const CalibratorOptions& options) {
  return heldout_turns(session, options, [&session](const CalibratorOptions& o) {
    return run_checked(session, o, "with turns held out");
  });
}

HeldoutTurns heldout_turns(const Session& session, const CalibratorOptions& options,
                           const std::function<KalmanRun(const CalibratorOptions&)>& run) {
  const PlanTimeline timeline = PlanTimeline::of(session.plan, session.site);
  // The turns: from inside the end margin of a dwell to inside the start margin of the next.
  std::vector<std::pair<double, double>> turns;
  for (std::size_t k = 1; k < timeline.dwells.size(); ++k) {
    const double t0 = timeline.dwells[k - 1].t_end - options.static_margin;
    const double t1 = timeline.dwells[k].t_start + options.static_margin;
    if (t1 > t0) turns.emplace_back(t0, t1);
  }
  HeldoutTurns h;
  if (turns.size() < 2) return h;
  double nis = 0.0, vel = 0.0;
  int scored = 0;
  for (std::size_t fold = 0; fold < 2; ++fold) {
    CalibratorOptions o = options;
    for (std::size_t k = fold; k < turns.size(); k += 2) o.holdout.push_back(turns[k]);
    KalmanRun r;
    try {
      r = run(o);
    } catch (const std::runtime_error& e) {
      HeldoutTurns failed;
      failed.failed = e.what();
      return failed;
    }
    for (const auto& p : r.holdout) {
      if (p.dof == 0) continue;
      nis += p.nis / p.dof;
      h.chi2 += p.nis;
      h.dof += p.dof;
      vel += p.velocity_innovation.squaredNorm();
      ++scored;
    }
  }
  if (scored > 0) {
    h.turns = scored;
    h.sigmas = std::sqrt(nis / scored);
    h.velocity = std::sqrt(vel / scored);
  }
  return h;
}

TurnTests::TurnTests(const Session& session, const CalibratorOptions& base,
                     const KalmanDiagnosisOptions& options)
    : session_(session),
      options_(options),
      model_(base),
      now_(run_checked(session, base, "with the session's model")) {}

std::vector<KalmanCandidateTest> TurnTests::round(const std::vector<std::string>& families) {
  check_candidates(model_, families);
  last_round_.clear();
  std::vector<KalmanCandidateTest> out;
  for (const auto& f : families) {
    KalmanRun r;
    out.push_back(test_candidate(session_, model_, now_, f, options_, r));
    last_round_.emplace_back(f, std::move(r));
  }
  return out;
}

void TurnTests::extend(const std::string& family) {
  if (model_.layout.on(family)) return;
  model_.layout.set(family, true);
  for (auto& [f, r] : last_round_)
    if (f == family && !r.estimates.empty()) {
      now_ = std::move(r);
      last_round_.clear();
      return;
    }
  last_round_.clear();
  now_ = run_checked(session_, model_, "with " + family);
}

KalmanCandidateTest* most_significant(std::vector<KalmanCandidateTest>& round, double threshold) {
  return most_significant_of(round, threshold);
}

KalmanDiagnosis diagnose_kalman(const Session& session, const CalibratorOptions& base,
                                const KalmanDiagnosisOptions& o) {
  check_candidates(base, o.candidates);
  KalmanDiagnosis d;
  d.alpha = o.alpha;
  d.initial_families.assign(base.layout.extended.begin(), base.layout.extended.end());
  TurnTests tests(session, base, o);
  d.initial_nis_per_dof = tests.now().nis_per_dof;
  d.initial_log_likelihood = tests.now().log_likelihood;
  std::vector<std::string> remaining = o.candidates;
  while (!remaining.empty() && static_cast<int>(d.findings.size()) < o.max_findings) {
    std::vector<KalmanCandidateTest> round = tests.round(remaining);
    const double threshold = o.alpha / static_cast<double>(round.size());
    KalmanCandidateTest* best = most_significant(round, threshold);
    if (!best) {
      for (const auto& c : round)
        if (c.dof == 0) d.not_separable.push_back(c);
      d.rounds.push_back(round);
      break;
    }
    best->named = true;
    d.findings.push_back(*best);
    tests.extend(best->family);
    remaining.erase(std::find(remaining.begin(), remaining.end(), best->family));
    d.rounds.push_back(round);
  }
  d.final_run = tests.now();
  return d;
}

}  // namespace sinscal
