#include "filter/diagnosis/thermal_diagnosis.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <set>
#include <stdexcept>

#include "filter/diagnosis/diagnosis.hpp"
#include "models/coefficient_families.hpp"

namespace sinscal {

namespace {

bool contains(const std::vector<std::string>& v, const std::string& x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

bool is_thermal_family(const std::string& name) {
  const auto& all = coefficient_families();
  return std::any_of(all.begin(), all.end(),
                     [&](const auto& f) { return f.name == name && f.thermal(); });
}

// The fit's coefficients at T0 (not thermal ones).
std::vector<int> base_catalog(const ThermalFit& fit) {
  std::vector<int> out;
  for (int c : fit.catalog)
    if (!coefficient_family_info(coefficient_catalog()[static_cast<std::size_t>(c)].family)
             .thermal())
      out.push_back(c);
  return out;
}

// Held-out soaks, and the RMS prediction error (SI) of the coefficients of `family` at T0.
HeldoutSoaks heldout(const std::vector<SoakEstimate>& soaks,
                     const std::vector<std::string>& families, double t0, const std::string& family,
                     double* family_error) {
  HeldoutSoaks out;
  if (family_error != nullptr) *family_error = 0.0;
  // The fit to the other soaks must be determined: at most soaks - 1 terms per coefficient.
  std::map<std::string, int> terms;
  for (const auto& f : families) ++terms[thermal_family_parts(f).first];
  for (const auto& [base, n] : terms)
    if (n + 1 > static_cast<int>(soaks.size()) - 1) return out;
  if (soaks.size() < 3) return out;
  double sum = 0.0, error = 0.0;
  int errors = 0;
  for (std::size_t k = 0; k < soaks.size(); ++k) {
    std::vector<SoakEstimate> others;
    for (std::size_t j = 0; j < soaks.size(); ++j)
      if (j != k) others.push_back(soaks[j]);
    const ThermalFit fit = fit_soaks_with(others, families, t0);
    const std::vector<int> catalog = base_catalog(fit);
    const auto [predicted, predicted_cov] = fit.predict(soaks[k], catalog);
    const auto m = static_cast<Eigen::Index>(catalog.size());
    Eigen::VectorXd r(m);
    Eigen::MatrixXd S = predicted_cov;
    const SoakEstimate& e = soaks[k];
    std::vector<Eigen::Index> at(catalog.size());
    for (Eigen::Index i = 0; i < m; ++i) {
      const auto it =
          std::find(e.catalog.begin(), e.catalog.end(), catalog[static_cast<std::size_t>(i)]);
      if (it == e.catalog.end()) throw std::invalid_argument("a soak lacks a fitted coefficient");
      at[static_cast<std::size_t>(i)] = it - e.catalog.begin();
    }
    for (Eigen::Index i = 0; i < m; ++i) {
      r(i) = e.value(at[static_cast<std::size_t>(i)]) - predicted(i);
      for (Eigen::Index j = 0; j < m; ++j)
        S(i, j) += e.covariance(at[static_cast<std::size_t>(i)], at[static_cast<std::size_t>(j)]);
      if (coefficient_catalog()[static_cast<std::size_t>(catalog[static_cast<std::size_t>(i)])]
              .family == family) {
        error += r(i) * r(i);
        ++errors;
      }
    }
    // Scaled to unit diagonal so that coefficients of very different units solve well.
    const Eigen::VectorXd d = S.diagonal().cwiseSqrt().cwiseInverse();
    const Eigen::MatrixXd Sn = d.asDiagonal() * S * d.asDiagonal();
    const Eigen::VectorXd rn = r.cwiseProduct(d);
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(Sn);
    const double d2 = rn.dot(ldlt.solve(rn));
    const double per = std::sqrt(std::max(0.0, d2) / static_cast<double>(m));
    out.per_soak.push_back(per);
    out.temperature_c.push_back(e.gyro_temperature_c);
    sum += per * per;
    out.chi2 += std::max(0.0, d2);
  }
  out.soaks = static_cast<int>(soaks.size());
  out.sigmas = std::sqrt(sum / static_cast<double>(soaks.size()));
  if (family_error != nullptr && errors > 0)
    *family_error = std::sqrt(error / static_cast<double>(errors));
  return out;
}

// The family of the same coefficient one degree lower in the temperature ("accel.bias_temp2" for
// "accel.bias_temp3"), or "" for degree 1 and the rate's. Without the hierarchy a degree-3 term
// alone fits the linear part of an all-hidden chamber about as well as degree 1 (T - T0 and its
// cube are nearly collinear over the soaks' span) and can be named first with a zero truth.
std::string lower_degree(const std::string& candidate) {
  const auto [family, degree] = thermal_family_parts(candidate);
  if (degree < 2) return "";
  for (const auto& f : coefficient_families())
    if (f.thermal() && thermal_family_parts(f.name) == std::make_pair(family, degree - 1))
      return f.name;
  return "";
}

// Why the soaks cannot test `candidate` against `model` (empty: they can).
std::string not_testable(const std::string& candidate, const std::vector<std::string>& model,
                         const std::set<std::string>& estimated, std::size_t soaks) {
  const auto [family, degree] = thermal_family_parts(candidate);
  if (degree == 0)
    return "a soak holds its temperature (dT/dt near 0): the rate of temperature change needs "
           "a ramp";
  if (estimated.count(family) == 0)
    return "the soaks do not estimate " + family + " (its coefficient at T0)";
  const std::string lower = lower_degree(candidate);
  if (!lower.empty() && !contains(model, lower))
    return "a polynomial in the temperature is extended degree by degree: " + lower +
           " is not in the model";
  int terms = 2;  // the coefficient at T0 and the candidate
  for (const auto& m : model)
    if (thermal_family_parts(m).first == family) ++terms;
  if (terms > static_cast<int>(soaks) - 1)
    return std::to_string(soaks) + " soaks determine at most " + std::to_string(soaks - 2) +
           " thermal terms of " + family + " with one degree of freedom left";
  return "";
}

ThermalCandidateTest test_candidate(const std::string& candidate, const ThermalFit& now,
                                    const ThermalFit& with, double alpha) {
  ThermalCandidateTest t;
  t.family = candidate;
  t.dof = static_cast<int>(with.value.size() - now.value.size());
  t.likelihood_ratio = std::max(0.0, now.chi2 - with.chi2);
  if (with.dof > 0 && with.p_value < alpha)
    // The extended fit's residual rejects the soaks' covariance: tested against its scale.
    f_verdict(t, t.likelihood_ratio, with.chi2 / with.dof, with.dof);
  else
    chi2_verdict(t, "chi2", t.likelihood_ratio);
  t.p_value = std::pow(10.0, t.log10_p);
  return t;
}

std::vector<std::string> candidate_families(const ThermalDiagnosisOptions& o) {
  for (const auto& m : o.model)
    if (!is_thermal_family(m))
      throw std::invalid_argument(m + " is not a thermal family of the family table");
  std::vector<std::string> out;
  for (const auto& c : o.candidates) {
    if (!is_thermal_family(c))
      throw std::invalid_argument(c + " is not a thermal family of the family table");
    if (!contains(o.model, c)) out.push_back(c);
  }
  if (o.candidates.empty())
    for (const auto& f : coefficient_families())
      if (f.thermal() && !contains(o.model, f.name)) out.push_back(f.name);
  return out;
}

// One round: every remaining candidate against the model, the most significant (-1: none).
struct ThermalRound {
  std::vector<ThermalCandidateTest> tests, not_testable;
  std::vector<ThermalFit> fits;
  int best = -1;
};

ThermalRound test_round(const std::vector<SoakEstimate>& soaks,
                        const std::vector<std::string>& model,
                        const std::set<std::string>& estimated,
                        const std::vector<std::string>& remaining, const ThermalFit& now, double t0,
                        double alpha) {
  ThermalRound r;
  for (const auto& c : remaining) {
    const std::string why = not_testable(c, model, estimated, soaks.size());
    if (!why.empty()) {
      ThermalCandidateTest t;
      t.family = c;
      t.not_testable = why;
      r.not_testable.push_back(t);
      continue;
    }
    std::vector<std::string> extended = model;
    extended.push_back(c);
    r.fits.push_back(fit_soaks_with(soaks, extended, t0));
    r.tests.push_back(test_candidate(c, now, r.fits.back(), alpha));
  }
  const double threshold = alpha / static_cast<double>(std::max<std::size_t>(1, r.tests.size()));
  const ThermalCandidateTest* best = most_significant_of(r.tests, threshold);
  r.best = best ? static_cast<int>(best - r.tests.data()) : -1;
  return r;
}

}  // namespace

HeldoutSoaks heldout_soaks(const std::vector<SoakEstimate>& soaks,
                           const std::vector<std::string>& families, double t0) {
  return heldout(soaks, families, t0, "", nullptr);
}

ThermalDiagnosis diagnose_soaks(const std::vector<SoakEstimate>& soaks, double t0,
                                const ThermalDiagnosisOptions& options) {
  ThermalDiagnosis d;
  d.alpha = options.alpha;
  d.reference_temperature_c = t0;
  d.model = options.model;
  std::vector<std::string> remaining = candidate_families(options);
  // The model's families with a signature on soaks (not the gyro bias in dT/dt: a soak holds its
  // temperature).
  std::vector<std::string> model;
  for (const auto& m : options.model)
    if (thermal_family_parts(m).second > 0) model.push_back(m);
  ThermalFit now = fit_soaks_with(soaks, model, t0);
  std::set<std::string> estimated;
  for (int c : base_catalog(now))
    estimated.insert(coefficient_catalog()[static_cast<std::size_t>(c)].family);
  d.initial_chi2 = now.chi2;
  d.initial_dof = now.dof;
  d.initial_heldout = heldout_soaks(soaks, model, t0);
  HeldoutSoaks current = d.initial_heldout;
  for (int round = 1;; ++round) {
    ThermalRound r = test_round(soaks, model, estimated, remaining, now, t0, options.alpha);
    d.not_testable = r.not_testable;
    if (round > options.max_findings) {  // one more round: what the cap leaves significant
      if (r.best >= 0)
        d.stops.push_back(findings_cap_stop(options.max_findings, "",
                                            r.tests[static_cast<std::size_t>(r.best)].family));
      break;
    }
    if (r.tests.empty()) break;
    if (r.best < 0) {
      d.rounds.push_back(r.tests);
      break;
    }
    const auto best = static_cast<std::size_t>(r.best);
    ThermalFinding f;
    f.round = round;
    f.test = r.tests[best];
    const std::string family = thermal_family_parts(f.test.family).first;
    f.before = heldout(soaks, model, t0, family, &f.family_error_before);
    std::vector<std::string> extended = model;
    extended.push_back(f.test.family);
    f.after = heldout(soaks, extended, t0, family, &f.family_error_after);
    if (f.before.soaks > 0 && f.after.soaks > 0 && f.after.chi2 >= f.before.chi2) {
      d.rounds.push_back(r.tests);
      d.rejected.push_back(f.test);
      char b[200];
      std::snprintf(b, sizeof b, "the held-out soaks' chi-square goes from %.4g to %.4g",
                    f.before.chi2, f.after.chi2);
      d.stops.push_back(refused_stop(round, f.test.family, f.test.p_value, b, "the search stops"));
      break;
    }
    r.tests[best].named = true;
    f.test.named = true;
    d.rounds.push_back(r.tests);
    model = extended;
    now = r.fits[best];
    current = f.after;
    d.findings.push_back(f);
    remaining.erase(std::find(remaining.begin(), remaining.end(), f.test.family));
  }
  d.final_fit = now;
  d.final_heldout = current;
  d.unexplained = now.dof > 0 && now.p_value < options.alpha;
  if (d.unexplained) d.sigma_scale = std::sqrt(now.chi2 / now.dof);
  if (!options.non_thermal_elsewhere)
    d.stops.emplace_back(
        "only thermal families tested: the non-thermal families (K2, g-sensitivity, scale "
        "asymmetry, lever arms, time delay, ...) are fitted soak by soak, not tested; diagnose a "
        "soak's session (soak-K/session.ini) as a table session to test them");
  for (auto& f : d.findings)
    for (std::size_t i = 0; i < now.catalog.size(); ++i)
      if (coefficient_catalog()[static_cast<std::size_t>(now.catalog[i])].family == f.test.family)
        f.coefficients.push_back(
            {now.catalog[i], now.value(static_cast<Eigen::Index>(i)),
             d.sigma_scale * std::sqrt(now.covariance(static_cast<Eigen::Index>(i),
                                                      static_cast<Eigen::Index>(i)))});
  return d;
}

}  // namespace sinscal
