#include "report/diagnosis_report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "filter/ins_error_model.hpp"
#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "report/diagnosis_kalman_report.hpp"
#include "report/gnuplot.hpp"
#include "report/output.hpp"
#include "report/result.hpp"

namespace sinscal {

namespace {

using json = nlohmann::ordered_json;

// Residual units: the accelerometers' in ug, the gyros' in deg/h.
constexpr double kAccelUnit = units::ug;
constexpr double kGyroUnit = units::deg_per_h;

json finite_or_null(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json rms_json(double accel, double gyro) {
  return {{"accel", finite_or_null(accel / kAccelUnit)},
          {"gyro", finite_or_null(gyro / kGyroUnit)}};
}

json heldout_json(const FitFigures& f) {
  return {{"sigmas", finite_or_null(f.heldout)},
          {"accel", finite_or_null(f.heldout_accel / kAccelUnit)},
          {"gyro", finite_or_null(f.heldout_gyro / kGyroUnit)}};
}

std::vector<std::string> names(const std::vector<int>& catalog) {
  std::vector<std::string> out;
  out.reserve(catalog.size());
  for (int c : catalog) out.push_back(coefficient_catalog()[static_cast<std::size_t>(c)].name);
  return out;
}

// The candidate's own coefficients from its fit.
json candidate_coefficients(const CandidateTest& c) {
  ResultCoefficients all = result_coefficients(c.with.fit), own;
  for (const auto& n : names(c.separable)) own[n] = all[n];
  return coefficients_json(own);
}

json statistic_json(const CandidateTest& c, double alpha) {
  return {{"name", "likelihood_ratio"},
          {"test", c.test},
          {"value", c.likelihood_ratio},
          {"dof", c.dof},
          {"p_value", c.p_value},
          {"threshold", c.threshold},
          {"alpha", alpha}};
}

json finding_json(const CandidateTest& c, const FitFigures& before, double alpha) {
  return {{"effect", c.family},
          {"coefficients", candidate_coefficients(c)},
          {"statistic", statistic_json(c, alpha)},
          {"bic_change", c.with.bic - before.bic},
          {"log_likelihood_change", c.with.log_likelihood - before.log_likelihood},
          {"residual_unit", {{"accel", "ug"}, {"gyro", "deg/h"}}},
          {"residual_rms_before", rms_json(before.accel_rms, before.gyro_rms)},
          {"residual_rms_after", rms_json(c.with.accel_rms, c.with.gyro_rms)},
          {"heldout_rms_before", heldout_json(before)},
          {"heldout_rms_after", heldout_json(c.with)},
          {"base_shift_sigma", c.base_shift_sigma}};
}

json candidate_json(const CandidateTest& c, double alpha) {
  json j = {{"effect", c.family}, {"separable", names(c.separable)}};
  if (!c.aliased.empty()) j["not_separable"] = names(c.aliased);
  if (c.dof > 0) {
    j["statistic"] = statistic_json(c, alpha);
    j["significant"] = c.significant;
    j["heldout_rms_after"] = heldout_json(c.with);
  }
  j["named"] = c.named;
  return j;
}

json fit_json(const FitFigures& f) {
  return {{"chi2_per_dof", f.fit.chi2_per_dof},
          {"dof", f.fit.dof},
          {"rank", f.fit.rank},
          {"residual_rms", rms_json(f.accel_rms, f.gyro_rms)},
          {"heldout_rms", heldout_json(f)}};
}

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

std::string fixed(double v, int decimals) {
  if (!std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, "%.*f", decimals, v);
  return b;
}

std::string sci(double v) {
  char b[64];
  std::snprintf(b, sizeof b, "%.3g", v);
  return b;
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
  json findings = json::array();
  const FitFigures* before = &r.initial;
  for (const auto& f : r.findings) {
    findings.push_back(finding_json(f, *before, r.alpha));
    before = &f.with;
  }
  j["findings"] = findings;
  json hidden = json::array();
  for (const auto& c : r.not_separable)
    hidden.push_back({{"effect", c.family},
                      {"components", names(c.aliased)},
                      {"aliased_with", c.aliased_with},
                      {"separated_by", c.separated_by}});
  j["not_separable"] = hidden;
  json ambiguous = json::array();
  for (const auto& a : r.ambiguous) {
    json effects = json::array({a.family});
    json separated = json::array({a.separated_by});
    for (const auto& b : a.ambiguous_with) {
      effects.push_back(b.family);
      separated.push_back(b.separated_by);
    }
    ambiguous.push_back({{"effects", effects},
                         {"components", names(a.separable)},
                         {"statistic", statistic_json(a, r.alpha)},
                         {"separated_by", separated}});
  }
  j["ambiguous"] = ambiguous;
  json rounds = json::array();
  for (const auto& round : r.rounds) {
    json one = json::array();
    for (const auto& c : round) one.push_back(candidate_json(c, r.alpha));
    rounds.push_back(one);
  }
  j["rounds"] = rounds;
  j["initial"] = fit_json(r.initial);
  j["calibration"] = {{"coefficients", coefficients_json(result_coefficients(r.final_fit.fit))},
                      {"fit", fit_json(r.final_fit)}};
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
      << " of their sigmas.\n\n| coefficient | value | sigma | unit |\n|---|---|---|---|\n";
    const ResultCoefficients all = result_coefficients(f.with.fit);
    for (const auto& n : names(f.separable)) {
      const auto& c = all.at(n);
      m << "| " << n << " | " << sci(c.value) << " | " << (c.sigma ? sci(*c.sigma) : "-") << " | "
        << c.unit << " |\n";
    }
    m << "\n";
    before = &f.with;
  }
  for (const auto& a : r.ambiguous) {
    m << "## Ambiguous\n\nA significant residual (likelihood ratio " << fixed(a.likelihood_ratio, 1)
      << ", p = " << sci(a.p_value) << ") that " << a.family;
    for (const auto& b : a.ambiguous_with) m << " and " << b.family;
    m << " explain equally well on this plan: neither is named. Separated by: " << a.separated_by;
    for (const auto& b : a.ambiguous_with) m << "; " << b.separated_by;
    m << ".\n\n";
  }
  m << "## Not separable on this plan\n\n";
  if (r.not_separable.empty()) m << "Every candidate is separable.\n";
  for (const auto& c : r.not_separable) {
    m << "- **" << c.family << "** (";
    const auto n = names(c.aliased);
    for (std::size_t i = 0; i < n.size(); ++i) m << (i ? ", " : "") << n[i];
    m << ")" << (c.aliased_with.empty() ? "" : ": aliased with " + c.aliased_with)
      << ". Separated by: " << c.separated_by << ".\n";
  }
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
