// The diagnosis files (docs/formats.md): DIR/diagnosis.json (findings, what the plan cannot
// separate, every candidate's test, the final calibration in the result schema), DIR/report.md
// (the same for a reader) and DIR/residuals.png (per-dwell residuals before and after, gnuplot).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "filter/diagnosis.hpp"
#include "filter/diagnosis_kalman.hpp"

namespace sinscal {

struct DiagnosisFiles {
  std::string json, markdown, png, script;
};

/// The paths a diagnosis writes into `dir`.
DiagnosisFiles diagnosis_files(const std::string& dir);

nlohmann::ordered_json diagnosis_json(const DiagnosisReport& report, const std::string& session);
std::string diagnosis_markdown(const DiagnosisReport& report, const std::string& session);
/// The gnuplot script drawing the per-dwell residuals before and after into `png_path`.
std::string residual_plot_script(const DiagnosisReport& report, const std::string& png_path);

/// Writes the three files (each to a temporary name, then renamed); `gnuplot` empty: no PNG.
/// With `kalman`, the Kalman-filter diagnosis of the turns joins them
/// (report/diagnosis_kalman_report.hpp).
DiagnosisFiles write_diagnosis(const DiagnosisReport& report, const std::string& session,
                               const std::string& dir, const std::string& gnuplot = "gnuplot",
                               const KalmanDiagnosis* kalman = nullptr);

}  // namespace sinscal
