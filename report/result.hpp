// Result and truth files (JSON, docs/formats.md): the coefficients in engineering units with their
// sigma, and the sections each method adds. The estimators return typed results (SI); this is
// where they become the files users script against.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "filter/closed_form/closed_form.hpp"
#include "filter/kalman/kalman_run.hpp"
#include "rig/session.hpp"

namespace sinscal {

/// One coefficient of a result file.
struct ResultCoefficient {
  double value = 0.0;
  std::optional<double> sigma;  // absent: not estimated (truth files)
  std::string unit;
  bool observable = true;            // false: the data cannot determine it; no value is given
  bool fixed_by_convention = false;  // zero by the body-frame convention, not estimated
};

/// Result / truth JSON: {"coefficients": {"gyro.bias.x": {"value": .., "sigma": .., "unit": ..}}}.
using ResultCoefficients = std::map<std::string, ResultCoefficient>;

/// One estimate in SI units (rad/s, m/s^2, ...) as a result coefficient in its family's
/// engineering unit.
ResultCoefficient result_coefficient(const CoefficientInfo& info, double value_si, double sigma_si);

/// The coefficients of the blocks an estimator had on (status not Off), in engineering units.
ResultCoefficients result_coefficients(const std::vector<CoefficientEstimate>& estimates);
/// The Kalman filter's and the closed form's coefficients.
ResultCoefficients result_coefficients(const KalmanRun& run);
ResultCoefficients result_coefficients(const ClosedFormReport& report);
/// The closed form's coefficients in a misalignment frame: the table's (its own), or the triad
/// frame, converted with the full covariance (filter/kalman/misalignment_frame.hpp); a
/// coefficient the conversion mixes with one the data did not determine is not determined.
ResultCoefficients result_coefficients(const ClosedFormReport& report, MisalignmentFrame frame);
/// A stage-2 solution's coefficients (any parameter set, e.g. a diagnosis's extended model).
ResultCoefficients result_coefficients(const Stage2Result& stage2);
/// The "coefficients" object of a result file.
nlohmann::ordered_json coefficients_json(const ResultCoefficients& coefficients);

/// The sections after "coefficients" of each method's result file.
nlohmann::ordered_json result_sections(const KalmanRun& run);
/// The filter's innovation tests (docs/formats.md "consistency"): alpha, tests, threshold,
/// verdict, and per channel its NIS with p-value and its Ljung-Box Q with p-value.
nlohmann::ordered_json innovation_check_json(const InnovationCheck& check);
nlohmann::ordered_json result_sections(const ClosedFormReport& report,
                                       MisalignmentFrame frame = MisalignmentFrame::Table);

/// Writes a result file; `extra` (an object) adds sections after "coefficients". Written to a
/// temporary name beside `path` and renamed when complete.
void write_result_json(const std::string& path, const ResultCoefficients& coefficients,
                       const nlohmann::ordered_json& extra = nlohmann::ordered_json::object());
/// A result or truth file read whole by the one reader of results (report/result_read.cpp):
/// export, report, compare, the truth of simulations.
struct ResultFile {
  nlohmann::json json;  // the document (every section)
  ResultCoefficients coefficients;
  /// With `force`: each implausible coefficient and why, the override the output must record.
  std::vector<std::string> forced;
  /// The frame of the misalignments, "table" or "triad" (docs/formats.md "misalignment_frame"):
  /// the field when the result has it, else the default of its method and mode (results written
  /// before the field: the accelerometer triad without table-attitude updates and for the
  /// table-free method, the table otherwise); empty for truth files and for methods without
  /// such a frame (six-face: the box's faces).
  std::string misalignment_frame;
};

/// Reads a result or truth file and checks every coefficient; throws std::runtime_error naming the
/// file, the coefficient and the cause.
/// - Always refused (malformed): not JSON, no "coefficients" object, an unknown coefficient name,
///   a unit other than the one results give it in (docs/conventions.md), a value that is not a
///   finite number, a sigma that is not a finite number >= 0.
/// - Refused unless `force` (implausible, check_plausible): a value or sigma beyond the family's
///   physical range, a sigma of 0, an estimate without a sigma in a calibration result (a file
///   with a "method"; truth files have none).
ResultFile read_result_file(const std::string& path, bool force = false);
/// read_result_file(path).coefficients: every check, no override.
ResultCoefficients read_result_json(const std::string& path);

/// Why a coefficient cannot be a calibration's (empty: plausible): its value or its sigma beyond
/// the physical range of its family (CoefficientFamily::plausible_max), a sigma of 0, or no
/// sigma when `sigma_required` (an estimate of a calibration result). `c` is in the unit results
/// give `name` in.
std::string check_plausible(const std::string& name, const ResultCoefficient& c,
                            bool sigma_required);

/// The session's truth (simulations), empty when it has none. With `accel_triad_frame` the truth
/// is converted to the body frame of the accelerometer triad, as results without table attitude
/// are (docs/conventions.md).
/// With a lever-arm reference ("x", "y", "z"), the truth's arms are relative to that
/// accelerometer's.
ResultCoefficients load_truth(const Session& session, bool accel_triad_frame = false,
                              const std::string& lever_arm_reference = "");
/// Largest |estimate - truth| / sigma over the estimated coefficients (none: nullopt).
std::optional<double> max_error_over_sigma(const ResultCoefficients& result,
                                           const ResultCoefficients& truth);

}  // namespace sinscal
