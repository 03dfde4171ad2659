#include "report/handheld_diagnosis_report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "report/gnuplot.hpp"
#include "report/output.hpp"
#include "report/result.hpp"

namespace sinscal {

using namespace diagnosis_output;

namespace {

json pose_json(const HandheldUnits& u, const PoseResidual& p) {
  auto triple = [&](const Eigen::Vector3d& v) {
    return json::array({finite_or_null(v(0) / u.gyro_si), finite_or_null(v(1) / u.gyro_si),
                        finite_or_null(v(2) / u.gyro_si)});
  };
  return {{"pose", p.pose},
          {"t_s", p.t_mid},
          {"gravity_before", finite_or_null(p.gravity_before / u.accel_si)},
          {"gravity_after", finite_or_null(p.gravity_after / u.accel_si)},
          {"gravity_sigma", finite_or_null(p.gravity_sigma / u.accel_si)},
          {"rate_before", triple(p.rate_before)},
          {"rate_after", triple(p.rate_after)},
          {"rate_sigma", triple(p.rate_sigma)},
          {"turn_before_deg", finite_or_null(p.turn_before / units::deg)},
          {"turn_after_deg", finite_or_null(p.turn_after / units::deg)},
          {"turn_sigma_deg", finite_or_null(p.turn_sigma / units::deg)}};
}

// Noise candidates: B in the rate unit, K in the rate unit per sqrt(s) (gyros deg/h and
// deg/h/sqrt(h); accelerometers ug and ug/sqrt(s)).
json noise_json(const HandheldDiagnosis& d) {
  json arr = json::array();
  for (const auto& c : d.noise) {
    const bool gyro = c.channel.rfind("gyro", 0) == 0;
    const bool walk = c.effect == "noise.rate_random_walk";
    const double unit =
        gyro ? (walk ? units::deg_per_h / std::sqrt(units::hour) : units::deg_per_h) : units::ug;
    const std::string uname =
        gyro ? (walk ? "deg/h/sqrt(h)" : "deg/h") : (walk ? "ug/sqrt(s)" : "ug");
    arr.push_back({{"effect", c.effect},
                   {"channel", c.channel},
                   {"significant", c.significant},
                   {"value", finite_or_null(c.value / unit)},
                   {"sigma", finite_or_null(c.sigma / unit)},
                   {"unit", uname},
                   {"tau_s", c.significant ? json(c.tau) : json(nullptr)},
                   {"largest_ratio_to_white", finite_or_null(c.ratio)},
                   {"confidence", c.confidence},
                   {"cluster_times", c.points}});
  }
  return arr;
}

json validation_json(const HandheldUnits& u, const HandheldDiagnosisInput& in) {
  json arr = json::array();
  for (const auto& [before, after] : in.validations)
    arr.push_back(
        {{"session", before.session},
         {"poses", before.poses.size()},
         {"turns", before.turns.size()},
         {"gravity_rms_nominal", finite_or_null(before.gravity_rms_nominal / u.accel_si)},
         {"gravity_rms_before", finite_or_null(before.gravity_rms_calibrated / u.accel_si)},
         {"gravity_rms_after", finite_or_null(after.gravity_rms_calibrated / u.accel_si)},
         {"rate_rms_before", finite_or_null(before.rate_rms_calibrated / u.gyro_si)},
         {"rate_rms_after", finite_or_null(after.rate_rms_calibrated / u.gyro_si)},
         {"turn_rms_before_deg", before.turns.empty()
                                     ? json(nullptr)
                                     : finite_or_null(before.turn_rms_calibrated / units::deg)},
         {"turn_rms_after_deg", before.turns.empty()
                                    ? json(nullptr)
                                    : finite_or_null(after.turn_rms_calibrated / units::deg)}});
  return arr;
}

json calibration_json(const HandheldUnits& u, const DiagnosisReport& r) {
  ResultCoefficients c = result_coefficients(r.final_fit.fit);
  for (const char* n :
       {"accel.misalignment.xy", "accel.misalignment.xz", "accel.misalignment.yz"}) {
    ResultCoefficient f;
    f.unit = coefficient_info(n).unit;
    f.sigma = 0.0;
    f.fixed_by_convention = true;
    c[n] = f;
  }
  return {{"coefficients", coefficients_json(c)}, {"fit", fit_json(u, r.final_fit)}};
}

}  // namespace

HandheldUnits handheld_units(const TableFreeResult& cal) {
  HandheldUnits u;
  const bool coarse_accel = cal.accel_noise.mean() > 1e-3;  // above ~100 ug per reading
  const bool coarse_gyro = cal.gyro_noise.mean() > 10.0 * units::deg_per_h;
  u.accel = coarse_accel ? "m/s^2" : "ug";
  u.accel_si = coarse_accel ? 1.0 : units::ug;
  u.gyro = coarse_gyro ? "deg/s" : "deg/h";
  u.gyro_si = coarse_gyro ? units::deg_per_s : units::deg_per_h;
  u.turns = true;
  return u;
}

json handheld_diagnosis_json(const HandheldDiagnosisInput& in) {
  const DiagnosisReport& r = in.diagnosis.report;
  const HandheldUnits u = handheld_units(in.calibration);
  json j;
  j["session"] = in.session;
  j["method"] = {{"name", "hand-held poses (table-free, linearized refit)"},
                 {"alpha", r.alpha},
                 {"residuals", in.diagnosis.rows},
                 {"poses", in.diagnosis.poses.size()},
                 {"turns", in.diagnosis.turns},
                 {"initial_model", names(r.initial_parameters)}};
  j["residual_unit"] = unit_json(u);
  j["findings"] = findings_json(u, r);
  j["not_separable"] = not_separable_json(r);
  j["ambiguous"] = ambiguous_json(r);
  json rejected = json::array();
  for (const auto& c : r.rejected)
    rejected.push_back({{"family", c.family}, {"p_value", c.p_value}});
  j["unexplained"] = {{"rejected", rejected}, {"stops", r.stops}};
  j["noise"] = {{"pose", in.diagnosis.noise_pose}, {"candidates", noise_json(in.diagnosis)}};
  j["rounds"] = rounds_json(u, r);
  j["validation"] = validation_json(u, in);
  j["initial"] = fit_json(u, r.initial);
  j["calibration"] = calibration_json(u, r);
  json poses = json::array();
  for (const auto& p : in.diagnosis.poses) poses.push_back(pose_json(u, p));
  j["poses"] = poses;
  return j;
}

HandheldDiagnosisFiles handheld_diagnosis_files(const std::string& dir) {
  HandheldDiagnosisFiles f;
  static_cast<DiagnosisFiles&>(f) = diagnosis_files(dir);
  f.allan_png = dir + "/allan.png";
  f.allan_script = gnuplot_script_path(f.allan_png);
  return f;
}

namespace {

void markdown_fit_table(std::ostringstream& m, const HandheldUnits& u, const FitFigures& before,
                        const FitFigures& after) {
  m << "| | before | after |\n|---|---|---|\n"
    << "| gravity-magnitude residual RMS [" << u.accel << "] | "
    << fixed(before.accel_rms / u.accel_si, 5) << " | " << fixed(after.accel_rms / u.accel_si, 5)
    << " |\n"
    << "| rate at rest RMS [" << u.gyro << "] | " << fixed(before.gyro_rms / u.gyro_si, 5) << " | "
    << fixed(after.gyro_rms / u.gyro_si, 5) << " |\n"
    << "| turn residual RMS [deg] | " << fixed(before.turn_rms / units::deg, 4) << " | "
    << fixed(after.turn_rms / units::deg, 4) << " |\n"
    << "| held-out error [sigma] | " << fixed(before.heldout, 3) << " | " << fixed(after.heldout, 3)
    << " |\n"
    << "| held-out gravity magnitude [" << u.accel << "] | "
    << fixed(before.heldout_accel / u.accel_si, 5) << " | "
    << fixed(after.heldout_accel / u.accel_si, 5) << " |\n"
    << "| held-out turn [deg] | " << fixed(before.heldout_turn / units::deg, 4) << " | "
    << fixed(after.heldout_turn / units::deg, 4) << " |\n"
    << "| BIC | " << fixed(before.bic, 1) << " | " << fixed(after.bic, 1) << " |\n\n";
}

void markdown_findings(std::ostringstream& m, const HandheldUnits& u, const DiagnosisReport& r) {
  m << "## Findings\n\n";
  if (r.findings.empty()) {
    double best_p = 1.0;
    std::string best;
    for (const auto& c : r.rounds.empty() ? std::vector<CandidateTest>{} : r.rounds.front())
      if (c.dof > 0 && c.p_value < best_p) {
        best_p = c.p_value;
        best = c.family;
      }
    m << "None: no candidate effect is significant at the family-wise level " << r.alpha;
    if (!best.empty())
      m << " (the smallest p-value, " << sci(best_p) << " for " << best << ", is above its "
        << "threshold " << sci(r.rounds.front().front().threshold) << ")";
    m << ".\n\n";
  }
  const FitFigures* before = &r.initial;
  for (const auto& f : r.findings) {
    m << "### " << f.family << "\n\n"
      << "Test: " << statistic_text(f) << ", p = " << sci(f.p_value) << " (threshold "
      << sci(f.threshold) << ").\n\n";
    markdown_fit_table(m, u, *before, f.with);
    m << "Base coefficients moved by up to " << fixed(f.base_shift_sigma, 1)
      << " of their sigmas.\n\n";
    markdown_coefficients(m, f);
    before = &f.with;
  }
}

void markdown_rest(std::ostringstream& m, const HandheldDiagnosisInput& in) {
  const DiagnosisReport& r = in.diagnosis.report;
  markdown_ambiguous_and_hidden(m, r, "session", "these poses");
  m << "\n";
  if (!in.validations.empty()) {
    const HandheldUnits u = handheld_units(in.calibration);
    m << "## Held-out validation records\n\nCorrected with the calibration before and after the "
         "findings (RMS over each record's poses and turns):\n\n"
      << "| record | gravity magnitude [" << u.accel << "] | rate at rest [" << u.gyro
      << "] | turns [deg] |\n|---|---|---|---|\n";
    for (const auto& [b, a] : in.validations)
      m << "| " << b.session << " | " << fixed(b.gravity_rms_calibrated / u.accel_si, 5) << " -> "
        << fixed(a.gravity_rms_calibrated / u.accel_si, 5) << " | "
        << fixed(b.rate_rms_calibrated / u.gyro_si, 5) << " -> "
        << fixed(a.rate_rms_calibrated / u.gyro_si, 5) << " | "
        << (b.turns.empty() ? std::string("-")
                            : fixed(b.turn_rms_calibrated / units::deg, 3) + " -> " +
                                  fixed(a.turn_rms_calibrated / units::deg, 3))
        << " |\n";
    m << "\n";
  }
  m << "## Noise (Allan deviation of pose " << in.diagnosis.noise_pose << ")\n\n";
  if (in.diagnosis.noise.empty()) m << "Not analysed.\n";
  for (const auto& c : in.diagnosis.noise)
    m << "- " << c.channel << ": "
      << (c.significant ? "**" + c.effect + "** significant" : "white noise only")
      << " (largest ratio of the measured deviation to the white-noise model " << fixed(c.ratio, 2)
      << " over " << c.points << " cluster times, bounds at confidence " << fixed(c.confidence, 5)
      << ")\n";
  m << "\nPer-pose residuals before and after: `residuals.png`"
    << (in.diagnosis.has_allan ? "; Allan deviation against the white-noise model: `allan.png`"
                               : "")
    << "; every figure: `diagnosis.json`.\n";
}

}  // namespace

std::string handheld_diagnosis_markdown(const HandheldDiagnosisInput& in) {
  const DiagnosisReport& r = in.diagnosis.report;
  const HandheldUnits u = handheld_units(in.calibration);
  std::ostringstream m;
  m << "# Diagnosis of " << in.session << "\n\n"
    << "Hand-held session: " << in.diagnosis.poses.size() << " poses, " << in.diagnosis.turns
    << " turns, " << in.diagnosis.rows << " residuals. The table-free calibration ("
    << r.initial_parameters.size() << " coefficients) leaves a chi2 per dof of "
    << fixed(r.initial.fit.chi2_per_dof, 3)
    << " (1 when it explains the poses and turns to their noise); RMS over the poses of the "
       "gravity-magnitude residual "
    << fixed(r.initial.accel_rms / u.accel_si, 5) << " " << u.accel << ", of the rate at rest "
    << fixed(r.initial.gyro_rms / u.gyro_si, 5) << " " << u.gyro << ", over the turns "
    << fixed(r.initial.turn_rms / units::deg, 4) << " deg.\n\n";
  markdown_findings(m, u, r);
  markdown_rest(m, in);
  return m.str();
}

std::string handheld_residual_plot_script(const HandheldDiagnosisInput& in,
                                          const std::string& png_path) {
  const HandheldUnits u = handheld_units(in.calibration);
  std::ostringstream g;
  g << "# Written by sinscal diagnose: per-pose residuals of a hand-held session\n"
    << "if (!exists('output')) output = " << gnuplot_quoted(png_path) << "\n"
    << "set terminal pngcairo size 1200,1000\nset output output\nset datafile missing '?'\n"
    << "set multiplot layout 3,1\nset grid\nset xlabel 'time of the pose [s]'\n"
    << "set key outside right\n";
  const auto& poses = in.diagnosis.poses;
  auto block = [&](auto value) {
    for (const auto& p : poses) g << p.t_mid << " " << gnuplot_number(value(p)) << "\n";
    g << "e\n";
  };
  g << "set title 'gravity-magnitude residual |f| - g [" << u.accel << "]'\n"
    << "plot '-' using 1:2 with linespoints dt 2 title 'before', '-' using 1:2 with linespoints "
       "title 'after'\n";
  block([&](const PoseResidual& p) { return p.gravity_before / u.accel_si; });
  block([&](const PoseResidual& p) { return p.gravity_after / u.accel_si; });
  g << "set title 'rate at rest [" << u.gyro << "]'\nplot ";
  const char* axis[3] = {"x", "y", "z"};
  for (int k = 0; k < 6; ++k)
    g << (k ? ", " : "") << "'-' using 1:2 with linespoints " << (k >= 3 ? "dt 1" : "dt 2")
      << " title '" << axis[k % 3] << (k >= 3 ? " after" : " before") << "'";
  g << "\n";
  for (int k = 0; k < 6; ++k)
    block([&](const PoseResidual& p) {
      return (k >= 3 ? p.rate_after : p.rate_before)(k % 3) / u.gyro_si;
    });
  g << "set title 'turn residual into the pose [deg]'\n"
    << "plot '-' using 1:2 with linespoints dt 2 title 'before', '-' using 1:2 with linespoints "
       "title 'after'\n";
  block([&](const PoseResidual& p) { return p.turn_before / units::deg; });
  block([&](const PoseResidual& p) { return p.turn_after / units::deg; });
  g << "unset multiplot\n";
  return g.str();
}

std::string handheld_allan_plot_script(const HandheldDiagnosisInput& in,
                                       const std::string& png_path) {
  std::ostringstream g;
  g << "# Written by sinscal diagnose: Allan deviation of the longest pose against the "
       "white-noise model\n"
    << "if (!exists('output')) output = " << gnuplot_quoted(png_path) << "\n"
    << "set terminal pngcairo size 1200,600\nset output output\nset datafile missing '?'\n"
    << "set multiplot layout 1,2\nset grid\nset logscale xy\nset xlabel 'tau [s]'\n"
    << "set key bottom left\n";
  if (!in.diagnosis.has_allan) return g.str() + "unset multiplot\n";
  const AllanAnalysis& a = in.diagnosis.allan;
  for (int sensor = 0; sensor < 2; ++sensor) {
    const auto& pts = sensor == 0 ? a.gyro : a.accel;
    const double unit = sensor == 0 ? units::deg_per_h : units::ug;
    g << "set title '" << (sensor == 0 ? "gyros [deg/h]" : "accelerometers [ug]") << "'\nplot ";
    for (int k = 0; k < 6; ++k)
      g << (k ? ", " : "") << "'-' using 1:2"
        << (k < 3 ? ":3:4 with yerrorlines" : " with lines dt 2") << " title '"
        << "xyz"[k % 3] << (k < 3 ? " measured" : " white noise") << "'";
    g << "\n";
    for (int k = 0; k < 6; ++k) {
      const auto& p = pts[static_cast<std::size_t>(k % 3)];
      const double N = p.empty() ? 0.0 : white_only_deviation(p);
      for (const auto& q : p) {
        g << q.tau << " ";
        if (k < 3)
          g << gnuplot_number(q.adev / unit) << " " << gnuplot_number(q.adev_low / unit) << " "
            << gnuplot_number(q.adev_high / unit) << "\n";
        else
          g << gnuplot_number(N / std::sqrt(q.tau) / unit) << "\n";
      }
      g << "e\n";
    }
  }
  g << "unset multiplot\n";
  return g.str();
}

HandheldDiagnosisFiles write_handheld_diagnosis(const HandheldDiagnosisInput& in,
                                                const std::string& dir,
                                                const std::string& gnuplot) {
  HandheldDiagnosisFiles f = handheld_diagnosis_files(dir);
  write_atomically(f.json,
                   [&](std::ostream& o) { o << handheld_diagnosis_json(in).dump(2) << "\n"; });
  write_atomically(f.markdown, [&](std::ostream& o) { o << handheld_diagnosis_markdown(in); });
  if (gnuplot.empty()) {
    f.png.clear();
    f.script.clear();
    f.allan_png.clear();
    f.allan_script.clear();
    return f;
  }
  write_atomically(f.script,
                   [&](std::ostream& o) { o << handheld_residual_plot_script(in, f.png); });
  run_gnuplot(gnuplot, f.script, f.png);
  if (in.diagnosis.has_allan) {
    write_atomically(f.allan_script,
                     [&](std::ostream& o) { o << handheld_allan_plot_script(in, f.allan_png); });
    run_gnuplot(gnuplot, f.allan_script, f.allan_png);
  } else {
    f.allan_png.clear();
    f.allan_script.clear();
  }
  return f;
}

}  // namespace sinscal
