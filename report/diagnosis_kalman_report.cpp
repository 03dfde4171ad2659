#include "report/diagnosis_kalman_report.hpp"

#include <cstdio>
#include <sstream>

#include "report/result.hpp"

namespace sinscal {

namespace {

using json = nlohmann::ordered_json;

json statistic_json(const KalmanCandidateTest& c, double alpha) {
  return {{"name", "wald_kalman"},    {"value", c.statistic}, {"dof", c.dof},
          {"nis_scale", c.nis_scale}, {"p_value", c.p_value}, {"log10_p", c.log10_p},
          {"threshold", c.threshold}, {"alpha", alpha}};
}

json own_coefficients(const KalmanCandidateTest& c) {
  ResultCoefficients all = result_coefficients(c.estimates), own;
  for (int k : c.catalog) {
    const std::string& n = coefficient_catalog()[static_cast<std::size_t>(k)].name;
    own[n] = all[n];
  }
  return coefficients_json(own);
}

}  // namespace

json kalman_finding_json(const KalmanCandidateTest& c, double nis_before,
                         double log_likelihood_before, double alpha) {
  return {{"effect", c.family},
          {"method", "kalman_innovations"},
          {"coefficients", own_coefficients(c)},
          {"statistic", statistic_json(c, alpha)},
          {"nis_per_dof_before", nis_before},
          {"nis_per_dof_after", c.nis_per_dof},
          {"log_likelihood_change", c.log_likelihood - log_likelihood_before},
          {"base_shift_sigma", c.base_shift_sigma}};
}

namespace {

json candidate_json(const KalmanCandidateTest& c, double alpha) {
  json j = {{"effect", c.family}, {"separable", c.dof > 0}};
  if (!c.failed.empty()) j["failed"] = c.failed;
  if (c.dof > 0) {
    j["statistic"] = statistic_json(c, alpha);
    j["significant"] = c.significant;
  } else {
    j["separated_by"] = c.separated_by;
  }
  j["nis_per_dof"] = c.nis_per_dof;
  j["named"] = c.named;
  return j;
}

}  // namespace

void add_kalman_diagnosis(json& d, const KalmanDiagnosis& k, bool findings) {
  double nis = k.initial_nis_per_dof, ll = k.initial_log_likelihood;
  for (const auto& f : k.findings) {
    if (findings) d["findings"].push_back(kalman_finding_json(f, nis, ll, k.alpha));
    nis = f.nis_per_dof;
    ll = f.log_likelihood;
  }
  json rounds = json::array();
  for (const auto& round : k.rounds) {
    json one = json::array();
    for (const auto& c : round) one.push_back(candidate_json(c, k.alpha));
    rounds.push_back(one);
  }
  d["kalman"] = {
      {"method",
       "Kalman-filter innovations: each candidate family run in the filter, "
       "its estimate tested against zero (Wald, prior minus posterior)"},
      {"alpha", k.alpha},
      {"initial_model", k.initial_families},
      {"nis_per_dof", k.initial_nis_per_dof},
      {"rounds", rounds},
      {"calibration",
       {{"coefficients", coefficients_json(result_coefficients(k.final_run.estimates))}}}};
  // The static dwells' "not separable" entries the filter tested: what the turns tell.
  if (!d.contains("not_separable")) return;
  for (auto& entry : d["not_separable"]) {
    const std::string effect = entry.value("effect", "");
    for (const auto& round : k.rounds)
      for (const auto& c : round)
        if (c.family == effect)
          entry["kalman"] = {{"separable", c.dof > 0},
                             {"p_value", c.p_value},
                             {"significant", c.significant},
                             {"named", c.named}};
  }
}

std::string kalman_diagnosis_markdown(const KalmanDiagnosis& k) {
  std::ostringstream m;
  char line[512];
  m << "\n## The turns' test (Kalman-filter innovations)\n\n"
    << "Each candidate family is added to the filter and the session run again; its estimate is "
       "tested against zero (Wald statistic over the directions the data determine, chi-square; "
       "family-wise level "
    << k.alpha
    << ", Bonferroni over each round's tests of the dwells and the turns together). NIS per dof of "
       "the session's model: ";
  std::snprintf(line, sizeof line, "%.3f.\n\n", k.initial_nis_per_dof);
  m << line;
  if (k.findings.empty()) m << "No candidate is significant.\n\n";
  for (const auto& f : k.findings) {
    std::snprintf(line, sizeof line,
                  "- **%s**: W = %.1f on %d dof, p = %.3g; NIS per dof -> %.3f; base moved up to "
                  "%.1f sigma\n",
                  f.family.c_str(), f.statistic, f.dof, f.p_value, f.nis_per_dof,
                  f.base_shift_sigma);
    m << line;
  }
  m << "\n| round | effect | dof | W | p | significant |\n|---|---|---|---|---|---|\n";
  int round_number = 0;
  for (const auto& round : k.rounds) {
    ++round_number;
    for (const auto& c : round) {
      if (!c.failed.empty()) {
        m << "| " << round_number << " | " << c.family << " | - | - | - | not tested: " << c.failed
          << " |\n";
        continue;
      }
      if (c.dof == 0) {
        m << "| " << round_number << " | " << c.family << " | 0 | - | - | not separable ("
          << c.separated_by << ") |\n";
        continue;
      }
      std::snprintf(line, sizeof line, "| %d | %s | %d | %.2f | %.3g | %s |\n", round_number,
                    c.family.c_str(), c.dof, c.statistic, c.p_value,
                    c.named ? "named" : (c.significant ? "yes" : "no"));
      m << line;
    }
  }
  return m.str();
}

}  // namespace sinscal
