// The Kalman-filter part of the diagnosis files (filter/diagnosis/diagnosis_kalman.hpp): its
// findings join diagnosis.json's "findings" (statistic "wald_kalman"), its every test goes under
// "kalman", and report.md gets a section (docs/formats.md).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "filter/diagnosis/diagnosis_kalman.hpp"

namespace sinscal {

/// One finding of the filter's test as a "findings" entry (its statistic "wald_kalman").
nlohmann::ordered_json kalman_finding_json(const KalmanCandidateTest& finding, double nis_before,
                                           double log_likelihood_before, double alpha);
/// Adds the Kalman-filter diagnosis to a diagnosis.json document (a "kalman" section, and on each
/// "not_separable" entry the filter tested, a "kalman" verdict); `findings` too: its findings
/// appended to "findings" (a diagnosis of the turns alone).
void add_kalman_diagnosis(nlohmann::ordered_json& diagnosis, const KalmanDiagnosis& kalman,
                          bool findings = true);
/// The report.md section of the Kalman-filter diagnosis.
std::string kalman_diagnosis_markdown(const KalmanDiagnosis& kalman);

}  // namespace sinscal
