#include "report/thermal_diagnosis_report.hpp"

#include "models/coefficient_families.hpp"
#include "report/output.hpp"

namespace sinscal {

namespace {

using json = nlohmann::ordered_json;

json heldout_json(const HeldoutSoaks& h) {
  return {{"soaks", h.soaks},
          {"sigmas", h.sigmas},
          {"per_soak", h.per_soak},
          {"soak_temperature_c", h.temperature_c}};
}

json test_json(const ThermalCandidateTest& t) {
  json j{{"family", t.family}};
  if (!t.not_testable.empty()) {
    j["not_testable"] = t.not_testable;
    return j;
  }
  j["test"] = t.test;
  j["statistic"] = t.statistic;
  j["dof"] = t.dof;
  if (t.test == "F") j["dof2"] = t.dof2;
  j["likelihood_ratio"] = t.likelihood_ratio;
  j["p_value"] = t.p_value;
  j["log10_p"] = t.log10_p;
  j["threshold"] = t.threshold;
  j["significant"] = t.significant;
  j["named"] = t.named;
  return j;
}

}  // namespace

json thermal_diagnosis_json(const ThermalDiagnosis& d, const std::string& chamber,
                            const std::vector<SoakRecord>& soaks) {
  json j;
  j["chamber"] = chamber;
  j["method"] = {{"name", "thermal soaks (per-soak Kalman filter, least squares in temperature)"},
                 {"alpha", d.alpha},
                 {"reference_temperature_c", d.reference_temperature_c},
                 {"initial_model", d.model}};
  json s = json::array();
  for (const auto& r : soaks)
    s.push_back({{"session", r.session},
                 {"accel_temperature_c", r.accel_temperature_c},
                 {"gyro_temperature_c", r.gyro_temperature_c},
                 {"nis_per_dof", r.nis_per_dof}});
  j["soaks"] = s;
  j["initial"] = {{"chi2", d.initial_chi2},
                  {"dof", d.initial_dof},
                  {"heldout", heldout_json(d.initial_heldout)}};
  json findings = json::array();
  for (const auto& f : d.findings) {
    const std::string base = thermal_family_parts(f.test.family).first;
    const CoefficientFamily& info = coefficient_family_info(f.test.family);
    const CoefficientFamily& base_info = coefficient_family_info(base);
    json c = json::object();
    for (const auto& k : f.coefficients)
      c[coefficient_catalog()[static_cast<std::size_t>(k.catalog)].name] = {
          {"value", k.value / info.si_per_unit()}, {"sigma", k.sigma / info.si_per_unit()}};
    findings.push_back({{"round", f.round},
                        {"family", f.test.family},
                        {"unit", info.unit()},
                        {"coefficients", c},
                        {"test", test_json(f.test)},
                        {"heldout_before", heldout_json(f.before)},
                        {"heldout_after", heldout_json(f.after)},
                        {"family_error",
                         {{"family", base},
                          {"unit", base_info.unit()},
                          {"before", f.family_error_before / base_info.si_per_unit()},
                          {"after", f.family_error_after / base_info.si_per_unit()}}}});
  }
  j["findings"] = findings;
  json rounds = json::array();
  for (const auto& r : d.rounds) {
    json one = json::array();
    for (const auto& t : r) one.push_back(test_json(t));
    rounds.push_back(one);
  }
  j["rounds"] = rounds;
  json untested = json::array();
  for (const auto& t : d.not_testable) untested.push_back(test_json(t));
  j["not_testable"] = untested;
  json rejected = json::array();
  for (const auto& t : d.rejected) rejected.push_back(test_json(t));
  j["unexplained"] = {
      {"present", d.unexplained}, {"sigma_scale", d.sigma_scale}, {"rejected", rejected}};
  j["stops"] = d.stops;
  j["final"] = {{"model",
                 [&] {
                   std::vector<std::string> m = d.model;
                   for (const auto& f : d.findings) m.push_back(f.test.family);
                   return m;
                 }()},
                {"chi2", d.final_fit.chi2},
                {"dof", d.final_fit.dof},
                {"p_value", d.final_fit.p_value},
                {"heldout", heldout_json(d.final_heldout)}};
  return j;
}

std::string write_thermal_diagnosis(const ThermalDiagnosis& d, const std::string& chamber,
                                    const std::vector<SoakRecord>& soaks, const std::string& dir) {
  std::string path = dir + "/diagnosis.json";
  const json j = thermal_diagnosis_json(d, chamber, soaks);
  write_atomically(path, [&](std::ostream& o) { o << j.dump(2) << "\n"; });
  return path;
}

}  // namespace sinscal
