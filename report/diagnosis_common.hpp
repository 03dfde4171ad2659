// The pieces of diagnosis.json and report.md (docs/formats.md) that the table and hand-held
// diagnoses share: statistics, fits, candidates, and what could not be separated or told apart.
#pragma once

#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "filter/diagnosis/diagnosis.hpp"

namespace sinscal::diagnosis_output {

using json = nlohmann::ordered_json;

/// The units residuals are written in.
struct ResidualUnits {
  std::string accel, gyro;               // unit names ("ug", "deg/h", ...)
  double accel_si = 1.0, gyro_si = 1.0;  // one unit in SI
  bool turns = false;                    // hand-held sessions: turn residuals too, in deg
};

json finite_or_null(double v);
/// `decimals` fixed decimals; "-" when not finite.
std::string fixed(double v, int decimals);
/// Three significant digits; "-" when not finite.
std::string sci(double v);
/// Coefficient names of catalog indices.
std::vector<std::string> names(const std::vector<int>& catalog);

/// The test's statistic as a reader takes it: "likelihood ratio 152.1 on 6 dof" or
/// "F(9, 40) = 0.41 (noise rescaled by the fit's residual)".
std::string statistic_text(const CandidateTest& c);

json unit_json(const ResidualUnits& u);
json rms_json(const ResidualUnits& u, const FitFigures& f);
json heldout_json(const ResidualUnits& u, const FitFigures& f);
json statistic_json(const CandidateTest& c, double alpha);
json fit_json(const ResidualUnits& u, const FitFigures& f);
/// A named effect: its coefficients (result schema), its test and the gain over `before`.
json finding_json(const ResidualUnits& u, const CandidateTest& c, const FitFigures& before,
                  double alpha);
json findings_json(const ResidualUnits& u, const DiagnosisReport& r);
/// Every candidate of every round.
json rounds_json(const ResidualUnits& u, const DiagnosisReport& r);
json not_separable_json(const DiagnosisReport& r);
json ambiguous_json(const DiagnosisReport& r);

/// The "| coefficient | value | sigma | unit |" table of a finding's own coefficients.
void markdown_coefficients(std::ostringstream& m, const CandidateTest& f);
/// The "Ambiguous" sections and the "Not separable on this `what`" list; `poses_word` names the
/// data ("this plan", "these poses").
void markdown_ambiguous_and_hidden(std::ostringstream& m, const DiagnosisReport& r,
                                   const std::string& what, const std::string& poses_word);

}  // namespace sinscal::diagnosis_output
