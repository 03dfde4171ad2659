// The diagnosis files (docs/formats.md): DIR/diagnosis.json (findings, what the plan cannot
// separate, every candidate's test, the final calibration in the result schema), DIR/report.md
// (the same for a reader) and DIR/residuals.png (per-dwell residuals before and after, gnuplot).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "filter/diagnosis/diagnosis_table.hpp"

namespace sinscal {

struct DiagnosisFiles {
  std::string json, markdown, png, script;
};

/// The paths a diagnosis writes into `dir`.
DiagnosisFiles diagnosis_files(const std::string& dir);

nlohmann::ordered_json diagnosis_json(const TableDiagnosis& diagnosis, const std::string& session);
std::string diagnosis_markdown(const TableDiagnosis& diagnosis, const std::string& session);
/// The gnuplot script drawing the per-dwell residuals before and after into `png_path`.
std::string residual_plot_script(const DiagnosisReport& report, const std::string& png_path);

/// Writes the three files (each to a temporary name, then renamed); `gnuplot` empty: no PNG.
/// The turns' test, when run, joins them (report/diagnosis_kalman_report.hpp).
DiagnosisFiles write_diagnosis(const TableDiagnosis& diagnosis, const std::string& session,
                               const std::string& dir, const std::string& gnuplot = "gnuplot");

/// "accel.k2 / accel.scale_asym (ambiguous on this plan; the model extended with accel.k2, the
/// data's pick)" or the family alone: a finding's name as the user reads it.
std::string finding_title(const TableFinding& finding);
/// The gain of a finding in one line for the terminal.
std::string finding_summary(const TableFinding& finding);

}  // namespace sinscal
