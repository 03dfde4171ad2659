#include "report/diagnosis_report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "filter/ins_error_model.hpp"
#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "report/diagnosis_common.hpp"
#include "report/diagnosis_kalman_report.hpp"
#include "report/gnuplot.hpp"
#include "report/output.hpp"
#include "report/result.hpp"

namespace sinscal {

using namespace diagnosis_output;

namespace {

// Residual units: the accelerometers' in ug, the gyros' in deg/h.
constexpr double kAccelUnit = units::ug;
constexpr double kGyroUnit = units::deg_per_h;

// The table diagnosis' residual units.
ResidualUnits table_units() { return {"ug", "deg/h", kAccelUnit, kGyroUnit, false}; }

json dwell_json(const DwellResidual& d) {
  auto triple = [](const Eigen::Matrix<double, 6, 1>& v, int at, double unit) {
    json a = json::array();
    for (int i = 0; i < 3; ++i) a.push_back(finite_or_null(v(at + i) / unit));
    return a;
  };
  const int A = ins_input::kAccel.index, G = ins_input::kGyro.index;
  return {{"dwell", d.dwell},
          {"label", d.label},
          {"accel_before_ug", triple(d.before, A, kAccelUnit)},
          {"accel_after_ug", triple(d.after, A, kAccelUnit)},
          {"accel_sigma_ug", triple(d.sigma, A, kAccelUnit)},
          {"gyro_before_deg_per_h", triple(d.before, G, kGyroUnit)},
          {"gyro_after_deg_per_h", triple(d.after, G, kGyroUnit)},
          {"gyro_sigma_deg_per_h", triple(d.sigma, G, kGyroUnit)}};
}

}  // namespace

DiagnosisFiles diagnosis_files(const std::string& dir) {
  DiagnosisFiles f;
  f.json = dir + "/diagnosis.json";
  f.markdown = dir + "/report.md";
  f.png = dir + "/residuals.png";
  f.script = gnuplot_script_path(f.png);
  return f;
}

json diagnosis_json(const DiagnosisReport& r, const std::string& session) {
  json j;
  j["session"] = session;
  j["method"] = {{"name", "static dwells (closed-form stage 2)"},
                 {"alpha", r.alpha},
                 {"equivalent_inputs", r.inputs},
                 {"initial_model", names(r.initial_parameters)}};
  const ResidualUnits u = table_units();
  j["findings"] = findings_json(u, r);
  j["not_separable"] = not_separable_json(r);
  j["ambiguous"] = ambiguous_json(r);
  j["rounds"] = rounds_json(u, r);
  j["initial"] = fit_json(u, r.initial);
  j["calibration"] = {{"coefficients", coefficients_json(result_coefficients(r.final_fit.fit))},
                      {"fit", fit_json(u, r.final_fit)}};
  json dwells = json::array();
  for (const auto& d : r.residuals) dwells.push_back(dwell_json(d));
  j["dwells"] = dwells;
  return j;
}

std::string diagnosis_markdown(const DiagnosisReport& r, const std::string& session) {
  std::ostringstream m;
  m << "# Diagnosis of " << session << "\n\n"
    << "Static dwells: " << r.residuals.size() << ", " << r.inputs
    << " equivalent inputs. The calibrated model (" << r.initial_parameters.size()
    << " coefficients) leaves a residual chi2 per dof of " << fixed(r.initial.fit.chi2_per_dof, 3)
    << " (1 when it explains the dwells to their sigmas); residual RMS "
    << fixed(r.initial.accel_rms / kAccelUnit, 2) << " ug (accelerometers), "
    << fixed(r.initial.gyro_rms / kGyroUnit, 4) << " deg/h (gyros).\n\n"
    << "## Findings\n\n";
  if (r.findings.empty())
    m << "None: no candidate effect is significant at the family-wise level " << r.alpha << ".\n\n";
  const FitFigures* before = &r.initial;
  for (const auto& f : r.findings) {
    m << "### " << f.family << "\n\n"
      << "Likelihood ratio " << fixed(f.likelihood_ratio, 1) << " on " << f.dof
      << " dof, p = " << sci(f.p_value) << " (threshold " << sci(f.threshold) << ").\n\n"
      << "| | before | after |\n|---|---|---|\n"
      << "| residual RMS accel [ug] | " << fixed(before->accel_rms / kAccelUnit, 2) << " | "
      << fixed(f.with.accel_rms / kAccelUnit, 2) << " |\n"
      << "| residual RMS gyro [deg/h] | " << fixed(before->gyro_rms / kGyroUnit, 4) << " | "
      << fixed(f.with.gyro_rms / kGyroUnit, 4) << " |\n"
      << "| held-out error [sigma] | " << fixed(before->heldout, 2) << " | "
      << fixed(f.with.heldout, 2) << " |\n"
      << "| BIC | " << fixed(before->bic, 1) << " | " << fixed(f.with.bic, 1) << " |\n\n"
      << "Base coefficients moved by up to " << fixed(f.base_shift_sigma, 1)
      << " of their sigmas.\n\n";
    markdown_coefficients(m, f);
    before = &f.with;
  }
  markdown_ambiguous_and_hidden(m, r, "plan", "this plan");
  m << "\nPer-dwell residuals before and after: `residuals.png`; every figure: `diagnosis.json`.\n";
  return m.str();
}

std::string residual_plot_script(const DiagnosisReport& r, const std::string& png_path) {
  std::ostringstream g;
  g << "# Written by sinscal diagnose: per-dwell residuals (measured minus model)\n"
    << "if (!exists('output')) output = " << gnuplot_quoted(png_path) << "\n"
    << "set terminal pngcairo size 1200,800\nset output output\n"
    << "set multiplot layout 2,1\nset grid\nset xlabel 'dwell'\nset key outside right\n";
  const char* axis[3] = {"N", "E", "D"};
  for (int sensor = 0; sensor < 2; ++sensor) {
    const int at = sensor == 0 ? ins_input::kAccel.index : ins_input::kGyro.index;
    const double unit = sensor == 0 ? kAccelUnit : kGyroUnit;
    g << "set title '" << (sensor == 0 ? "accelerometers [ug]" : "gyros [deg/h]") << "'\nplot ";
    for (int k = 0; k < 6; ++k) {
      const bool after = k >= 3;
      g << (k ? ", " : "") << "'-' using 1:2 with linespoints " << (after ? "dt 1" : "dt 2")
        << " title '" << axis[k % 3] << (after ? " after" : " before") << "'";
    }
    g << "\n";
    for (int k = 0; k < 6; ++k) {
      for (const auto& d : r.residuals) {
        const double v = (k >= 3 ? d.after : d.before)(at + k % 3) / unit;
        g << d.dwell << " " << (std::isfinite(v) ? fixed(v, 6) : std::string("NaN")) << "\n";
      }
      g << "e\n";
    }
  }
  g << "unset multiplot\n";
  return g.str();
}

DiagnosisFiles write_diagnosis(const DiagnosisReport& r, const std::string& session,
                               const std::string& dir, const std::string& gnuplot,
                               const KalmanDiagnosis* kalman) {
  DiagnosisFiles f = diagnosis_files(dir);
  json j = diagnosis_json(r, session);
  std::string markdown = diagnosis_markdown(r, session);
  if (kalman) {
    add_kalman_diagnosis(j, *kalman);
    markdown += kalman_diagnosis_markdown(*kalman);
  }
  write_atomically(f.json, [&](std::ostream& o) { o << j.dump(2) << "\n"; });
  write_atomically(f.markdown, [&](std::ostream& o) { o << markdown; });
  if (!gnuplot.empty()) {
    write_atomically(f.script, [&](std::ostream& o) { o << residual_plot_script(r, f.png); });
    run_gnuplot(gnuplot, f.script, f.png);
  } else {
    f.png.clear();
    f.script.clear();
  }
  return f;
}

}  // namespace sinscal
