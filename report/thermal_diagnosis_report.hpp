// A chamber's thermal diagnosis as a file (docs/formats.md "Thermal diagnosis"): diagnosis.json
// with the model, each round's candidate tests, the findings with their coefficients and held-out
// gain, and the families the soaks cannot test, with the reason.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "filter/diagnosis/thermal_diagnosis.hpp"
#include "report/thermal_output.hpp"

namespace sinscal {

nlohmann::ordered_json thermal_diagnosis_json(const ThermalDiagnosis& d, const std::string& chamber,
                                              const std::vector<SoakRecord>& soaks);
/// Writes DIR/diagnosis.json atomically; returns its path.
std::string write_thermal_diagnosis(const ThermalDiagnosis& d, const std::string& chamber,
                                    const std::vector<SoakRecord>& soaks, const std::string& dir);

}  // namespace sinscal
