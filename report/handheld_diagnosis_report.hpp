// The diagnosis files of a hand-held session (docs/formats.md), in the table diagnosis's schema
// (report/diagnosis_report.hpp): DIR/diagnosis.json (findings, not_separable, ambiguous, rounds,
// calibration; per-pose residuals and the noise candidates in place of the dwells), DIR/report.md,
// DIR/residuals.png (per-pose gravity-magnitude residual, rate at rest and turn residual before
// and after, over the pose index and over time) and DIR/allan.png (measured Allan deviation of
// the longest pose against the white-noise model).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "filter/diagnosis/handheld_diagnosis.hpp"
#include "filter/table_free/handheld_run.hpp"
#include "report/diagnosis_common.hpp"
#include "report/diagnosis_report.hpp"

namespace sinscal {

/// The units of the residuals of a hand-held diagnosis: the accelerometers' in ug or m/s^2 and
/// the gyros' in deg/h or deg/s, chosen by the size of the calibration's noise; turns in deg.
/// Residual units of a hand-held session (turn residuals included).
using HandheldUnits = diagnosis_output::ResidualUnits;
HandheldUnits handheld_units(const TableFreeResult& calibration);

struct HandheldDiagnosisInput {
  const HandheldDiagnosis& diagnosis;
  const TableFreeResult& calibration;
  std::string session;
  /// Held-out validation records corrected with the calibration before and after the findings.
  std::vector<std::pair<HandheldValidation, HandheldValidation>> validations;
};

nlohmann::ordered_json handheld_diagnosis_json(const HandheldDiagnosisInput& in);
std::string handheld_diagnosis_markdown(const HandheldDiagnosisInput& in);
std::string handheld_residual_plot_script(const HandheldDiagnosisInput& in,
                                          const std::string& png_path);
std::string handheld_allan_plot_script(const HandheldDiagnosisInput& in,
                                       const std::string& png_path);

/// Writes diagnosis.json, report.md and (gnuplot not empty) residuals.png and allan.png; the
/// returned files' `allan_png` is empty without an Allan analysis.
struct HandheldDiagnosisFiles : DiagnosisFiles {
  std::string allan_png, allan_script;
};
HandheldDiagnosisFiles handheld_diagnosis_files(const std::string& dir);
HandheldDiagnosisFiles write_handheld_diagnosis(const HandheldDiagnosisInput& in,
                                                const std::string& dir,
                                                const std::string& gnuplot = "gnuplot");

}  // namespace sinscal
