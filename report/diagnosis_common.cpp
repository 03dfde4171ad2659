#include "report/diagnosis_common.hpp"

#include <cmath>
#include <cstdio>

#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/result.hpp"

namespace sinscal::diagnosis_output {

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

std::string sci(double v) {
  if (!std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
}

std::vector<std::string> names(const std::vector<int>& catalog) {
  std::vector<std::string> out;
  out.reserve(catalog.size());
  for (int c : catalog) out.push_back(coefficient_catalog()[static_cast<std::size_t>(c)].name);
  return out;
}

std::string statistic_text(const CandidateTest& c) {
  if (c.test == "F")
    return "F(" + std::to_string(c.dof) + ", " + std::to_string(c.dof2) +
           ") = " + fixed(c.statistic, 2) + " (noise rescaled by the fit's residual)";
  return "likelihood ratio " + fixed(c.statistic, 1) + " on " + std::to_string(c.dof) + " dof";
}

json unit_json(const ResidualUnits& u) {
  json j = {{"accel", u.accel}, {"gyro", u.gyro}};
  if (u.turns) j["turn"] = "deg";
  return j;
}

json rms_json(const ResidualUnits& u, const FitFigures& f) {
  json j = {{"accel", finite_or_null(f.accel_rms / u.accel_si)},
            {"gyro", finite_or_null(f.gyro_rms / u.gyro_si)}};
  if (u.turns) j["turn"] = finite_or_null(f.turn_rms / units::deg);
  return j;
}

json heldout_json(const ResidualUnits& u, const FitFigures& f) {
  json j = {{"sigmas", finite_or_null(f.heldout)},
            {"accel", finite_or_null(f.heldout_accel / u.accel_si)},
            {"gyro", finite_or_null(f.heldout_gyro / u.gyro_si)}};
  if (u.turns) j["turn"] = finite_or_null(f.heldout_turn / units::deg);
  return j;
}

json statistic_json(const CandidateTest& c, double alpha) {
  json j = {{"name", c.test == "F" ? "F" : "likelihood_ratio"},
            {"test", c.test},
            {"value", c.statistic},
            {"dof", c.dof}};
  if (c.test == "F") j["dof2"] = c.dof2;
  j["likelihood_ratio"] = c.likelihood_ratio;
  j["p_value"] = c.p_value;
  j["log10_p"] = c.log10_p;
  j["threshold"] = c.threshold;
  j["alpha"] = alpha;
  return j;
}

json fit_json(const ResidualUnits& u, const FitFigures& f) {
  return {{"chi2_per_dof", finite_or_null(f.fit.chi2_per_dof)},
          {"dof", f.fit.dof},
          {"rank", f.fit.rank},
          {"residual_rms", rms_json(u, f)},
          {"heldout_rms", heldout_json(u, f)}};
}

namespace {
// The candidate's own coefficients from its fit.
json candidate_coefficients(const CandidateTest& c) {
  ResultCoefficients all = result_coefficients(c.with.fit), own;
  for (const auto& n : names(c.separable)) own[n] = all[n];
  return coefficients_json(own);
}

json candidate_json(const ResidualUnits& u, const CandidateTest& c, double alpha) {
  json j = {{"effect", c.family}, {"separable", names(c.separable)}};
  if (!c.aliased.empty()) j["not_separable"] = names(c.aliased);
  if (c.dof > 0) {
    j["statistic"] = statistic_json(c, alpha);
    j["significant"] = c.significant;
    j["heldout_rms_after"] = heldout_json(u, c.with);
  }
  j["named"] = c.named;
  return j;
}
}  // namespace

json finding_json(const ResidualUnits& u, const CandidateTest& c, const FitFigures& before,
                  double alpha) {
  return {{"effect", c.family},
          {"coefficients", candidate_coefficients(c)},
          {"statistic", statistic_json(c, alpha)},
          {"bic_change", c.with.bic - before.bic},
          {"log_likelihood_change", c.with.log_likelihood - before.log_likelihood},
          {"residual_unit", unit_json(u)},
          {"residual_rms_before", rms_json(u, before)},
          {"residual_rms_after", rms_json(u, c.with)},
          {"heldout_rms_before", heldout_json(u, before)},
          {"heldout_rms_after", heldout_json(u, c.with)},
          {"base_shift_sigma", c.base_shift_sigma}};
}

json findings_json(const ResidualUnits& u, const DiagnosisReport& r) {
  json findings = json::array();
  const FitFigures* before = &r.initial;
  for (const auto& f : r.findings) {
    findings.push_back(finding_json(u, f, *before, r.alpha));
    before = &f.with;
  }
  return findings;
}

json rounds_json(const ResidualUnits& u, const DiagnosisReport& r) {
  json rounds = json::array();
  for (const auto& round : r.rounds) {
    json one = json::array();
    for (const auto& c : round) one.push_back(candidate_json(u, c, r.alpha));
    rounds.push_back(one);
  }
  return rounds;
}

json not_separable_json(const DiagnosisReport& r) {
  json hidden = json::array();
  for (const auto& c : r.not_separable)
    hidden.push_back({{"effect", c.family},
                      {"components", names(c.aliased)},
                      {"aliased_with", c.aliased_with},
                      {"separated_by", c.separated_by}});
  return hidden;
}

json ambiguous_json(const DiagnosisReport& r) {
  json ambiguous = json::array();
  for (const auto& a : r.ambiguous) {
    json effects = json::array({a.family});
    json separated = json::array({a.separated_by});
    for (const auto& b : a.ambiguous_with) {
      effects.push_back(b.family);
      separated.push_back(b.separated_by);
    }
    ambiguous.push_back({{"effects", effects},
                         {"components", names(a.separable)},
                         {"statistic", statistic_json(a, r.alpha)},
                         {"separated_by", separated}});
  }
  return ambiguous;
}

void markdown_coefficients(std::ostringstream& m, const CandidateTest& f) {
  m << "| coefficient | value | sigma | unit |\n|---|---|---|---|\n";
  const ResultCoefficients all = result_coefficients(f.with.fit);
  for (const auto& n : names(f.separable)) {
    const auto& c = all.at(n);
    m << "| " << n << " | " << sci(c.value) << " | " << (c.sigma ? sci(*c.sigma) : "-") << " | "
      << c.unit << " |\n";
  }
  m << "\n";
}

void markdown_ambiguous_and_hidden(std::ostringstream& m, const DiagnosisReport& r,
                                   const std::string& what, const std::string& poses_word) {
  for (const auto& a : r.ambiguous) {
    m << "## Ambiguous\n\nA significant residual (" << statistic_text(a)
      << ", p = " << sci(a.p_value) << ") that " << a.family;
    for (const auto& b : a.ambiguous_with) m << " and " << b.family;
    m << " explain equally well on " << poses_word
      << ": neither is named. Separated by: " << a.separated_by;
    for (const auto& b : a.ambiguous_with) m << "; " << b.separated_by;
    m << ".\n\n";
  }
  m << "## Not separable on this " << what << "\n\n";
  if (r.not_separable.empty()) m << "Every candidate is separable.\n";
  for (const auto& c : r.not_separable) {
    m << "- **" << c.family << "** (";
    const auto n = names(c.aliased);
    for (std::size_t i = 0; i < n.size(); ++i) m << (i ? ", " : "") << n[i];
    // A reason (too few poses, nothing to fit) rather than the base combination it hides in.
    const bool reason =
        c.aliased_with.rfind("too few poses", 0) == 0 || c.aliased_with.rfind("nothing", 0) == 0;
    m << ")"
      << (c.aliased_with.empty() ? ""
          : reason               ? ": " + c.aliased_with
                                 : ": aliased with " + c.aliased_with)
      << ". Separated by: " << c.separated_by << ".\n";
  }
}

}  // namespace sinscal::diagnosis_output
