#include "report/diagnosis_report.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "filter/strapdown/ins_error_model.hpp"
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

namespace {

json heldout_turns_json(const std::optional<HeldoutTurns>& h) {
  if (h && !h->failed.empty()) return {{"turns", 0}, {"failed", h->failed}};
  if (!h || h->turns == 0) return nullptr;
  return {{"turns", h->turns},
          {"sigmas", h->sigmas},
          {"velocity_mm_per_s", h->velocity / 1e-3},
          {"chi2", h->chi2},
          {"dof", h->dof}};
}

// The final model against its noise model, what is unexplained, the stops.
void add_verdict(json& j, const TableDiagnosis& d) {
  const ResidualCheck& c = d.check;
  j["residual_check"] = {{"dwells_chi2", c.dwells_chi2},
                         {"dwells_dof", c.dwells_dof},
                         {"dwells_quantile_99", c.dwells_quantile},
                         {"dwells_hold", c.dwells_hold},
                         {"heldout_chi2", c.heldout_chi2},
                         {"heldout_inputs", c.heldout_inputs},
                         {"heldout_quantile_99", c.heldout_quantile},
                         {"heldout_hold", c.heldout_hold},
                         {"filter", c.filter},
                         {"nis_per_dof", c.nis_per_dof},
                         {"filter_holds", c.filter_holds},
                         {"innovations", innovation_check_json(c.innovations)},
                         {"dwells_sigma_scale", c.dwells_sigma_scale},
                         {"filter_sigma_scale", c.filter_sigma_scale},
                         {"heldout_sigma_scale", c.heldout_sigma_scale},
                         {"turns_tested", c.turns_tested},
                         {"turns_chi2", c.turns_chi2},
                         {"turns_dof", c.turns_dof},
                         {"turns_hold", c.turns_hold},
                         {"turns_sigma_scale", c.turns_sigma_scale},
                         {"sigma_scale", c.sigma_scale},
                         {"sigmas_hold", c.sigmas_hold},
                         {"sigmas_note", c.sigmas_note}};
  json rejected = json::array();
  for (const auto& r : d.rejected)
    rejected.push_back({{"family", r.finding.family},
                        {"round", r.finding.round},
                        {"p_value", r.finding.p_value},
                        {"reason", r.reason}});
  j["unexplained"] = {{"present", d.unexplained.present},
                      {"signature", d.unexplained.signature},
                      {"rejected", rejected}};
  if (const auto& lib = d.unexplained.library) {
    json terms = json::array();
    for (const auto& t : lib->terms)
      terms.push_back({{"sensor", t.sensor},
                       {"axis", t.axis},
                       {"formula", t.formula},
                       {"unit", t.unit},
                       {"value", t.value},
                       {"sigma", t.sigma},
                       {"text", t.text()}});
    j["unexplained"]["library"] = {{"candidates", lib->candidates},
                                   {"heldout_chi2_before", lib->heldout_before},
                                   {"heldout_chi2_after", lib->heldout_after},
                                   {"heldout_gain_needed", lib->heldout_needed},
                                   {"terms", terms},
                                   {"how_to_add", lib->how_to_add}};
    if (lib->turn_segments > 0)
      j["unexplained"]["library"]["turns"] = {{"segments", lib->turn_segments},
                                              {"chi2", lib->turns_chi2},
                                              {"dof", lib->turns_dof},
                                              {"quantile", lib->turns_quantile},
                                              {"rejects", lib->turns_reject},
                                              {"term", lib->turns_term},
                                              {"term_z2", lib->turns_term_z2},
                                              {"term_quantile", lib->turns_term_quantile},
                                              {"term_rejects", lib->turns_term_reject}};
  }
  j["stops"] = d.stops;
}

// The extended calibration's coefficients of a finding, in the family's unit.
json finding_coefficients_json(const TableFinding& f) {
  json j = json::object();
  const auto& cat = coefficient_catalog();
  for (const auto& c : f.coefficients) {
    const CoefficientFamily& info = coefficient_family_info(f.family);
    const double unit = info.si_per_unit();
    const std::string& name = cat[static_cast<std::size_t>(c.catalog)].name;
    if (c.source.empty())
      j[name] = {
          {"value", nullptr}, {"sigma", nullptr}, {"unit", info.unit()}, {"determined", false}};
    else
      j[name] = {{"value", c.value / unit},
                 {"sigma", c.sigma / unit},
                 {"unit", info.unit()},
                 {"determined", true},
                 {"source", c.source}};
  }
  return j;
}

json combinations_json(const TableFinding& f) {
  json a = json::array();
  const CoefficientFamily& info = coefficient_family_info(f.family);
  for (const auto& c : f.combinations) {
    json w = json::object();
    for (const auto& [k, weight] : c.weights)
      w[coefficient_catalog()[static_cast<std::size_t>(k)].name] = weight;
    a.push_back({{"weights", w},
                 {"text", c.text()},
                 {"value", c.value / info.si_per_unit()},
                 {"sigma", c.sigma / info.si_per_unit()},
                 {"unit", info.unit()}});
  }
  return a;
}

json pair_separation_json(const PairSeparation& s) {
  json j = {{"plan", s.plan},
            {"families", {s.a, s.b}},
            {"correlation", s.correlation},
            {"correlations", s.correlations},
            {"expected_chi2_difference", s.expected_gap}};
  if (s.heldout()) j["expected_heldout_difference"] = s.heldout_gap();
  return j;
}

// A turns' pick's separability (TableFinding::separability): the statement, this plan's figures
// and the plan with its turns split in halves.
json separability_json(const TableFinding& f) {
  json j = {{"statement", f.separability}};
  if (f.pick_gap) j["session_heldout_difference"] = *f.pick_gap;
  if (f.separation) j["this_plan"] = pair_separation_json(*f.separation);
  if (f.separating) j["separating_plan"] = pair_separation_json(*f.separating);
  return j;
}

// The fields every finding of the story has, beside its method's own.
void add_story_fields(json& j, const TableFinding& f) {
  j["round"] = f.round;
  j["source"] = f.source == TableFinding::Source::Dwells ? "dwells" : "turns";
  j["title"] = finding_title(f);
  j["ambiguous_with"] = f.ambiguous_with;
  if (!f.picked_by.empty()) j["picked_by"] = f.picked_by;
  if (!f.pick_note.empty()) j["pick_note"] = f.pick_note;
  if (!f.separability.empty()) j["separability"] = separability_json(f);
  j["separated_by"] = f.separated_by;
  j["coefficients"] = finding_coefficients_json(f);
  j["combinations"] = combinations_json(f);
  if (f.filter) {
    j["filter"] = {{"nis_per_dof_before", f.nis_before},
                   {"nis_per_dof_after", f.nis_after},
                   {"log_likelihood_change", f.log_likelihood_after - f.log_likelihood_before}};
    j["heldout_turns_before"] = heldout_turns_json(f.turns_before);
    j["heldout_turns_after"] = heldout_turns_json(f.turns_after);
  }
  if (!f.library_alternative.empty()) j["library_alternative"] = f.library_alternative;
  if (!f.time_temperature.empty()) j["time_temperature"] = f.time_temperature;
}

}  // namespace

std::string finding_title(const TableFinding& f) {
  if (f.ambiguous_with.empty()) return f.family;
  std::string t = f.family;
  for (const auto& a : f.ambiguous_with) t += " / " + a;
  if (f.picked_by == "catalog")  // a family and a library term (TableFinding::library_alternative)
    return t + " (not separable on this plan: the data cannot choose; the model extended with " +
           f.family + ", the catalog's family)";
  return t + " (ambiguous on this plan's dwells; the model extended with " + f.family +
         (f.picked_by == "user"    ? ", the user's pick)"
          : f.picked_by == "turns" ? ", the turns' pick)"
          : f.picked_by == "temperature first (ramp)"
              ? ", temperature first: time and temperature rise together)"
              : ", the dwells' best fit)");
}

std::string finding_summary(const TableFinding& f) {
  std::ostringstream m;
  if (f.test == "wald")
    m << "W = " << fixed(f.statistic, 1) << " on " << f.dof << " dof";
  else if (f.test == "F")
    m << "F(" << f.dof << ", " << f.dof2 << ") = " << fixed(f.statistic, 2);
  else
    m << "likelihood ratio " << fixed(f.statistic, 1) << " on " << f.dof << " dof";
  m << ", p = " << sci(f.p_value) << " ("
    << (f.source == TableFinding::Source::Dwells ? "dwells" : "turns") << ")";
  if (f.dwells_before && f.dwells_after)
    m << "; held-out dwells " << fixed(f.dwells_before->heldout, 2) << " -> "
      << fixed(f.dwells_after->heldout, 2) << " sigma";
  if (f.turns_before && f.turns_after && f.turns_before->turns > 0)
    m << "; held-out turns " << fixed(f.turns_before->sigmas, 2) << " -> "
      << fixed(f.turns_after->sigmas, 2) << " sigma, " << fixed(f.turns_before->velocity / 1e-3, 3)
      << " -> " << fixed(f.turns_after->velocity / 1e-3, 3) << " mm/s";
  if (!f.library_alternative.empty())
    m << "; or, not separable on this plan: " << f.library_alternative;
  if (!f.time_temperature.empty()) m << "; time against temperature: " << f.time_temperature;
  return m.str();
}

json diagnosis_json(const TableDiagnosis& d, const std::string& session) {
  const DiagnosisReport& r = d.dwells;
  json j;
  j["session"] = session;
  j["method"] = {{"name", d.turns ? "static dwells (closed-form stage 2) and turns (Kalman-filter "
                                    "innovations), one ranking"
                                  : "static dwells (closed-form stage 2)"},
                 {"alpha", r.alpha},
                 {"equivalent_inputs", r.inputs},
                 {"rounds", d.rounds},
                 {"initial_model", names(r.initial_parameters)}};
  const ResidualUnits u = table_units();
  json findings = json::array();
  std::size_t dwell_k = 0, turn_k = 0;
  const FitFigures* before = &r.initial;
  double nis = d.turns ? d.turns->initial_nis_per_dof : 0.0;
  double ll = d.turns ? d.turns->initial_log_likelihood : 0.0;
  for (const auto& f : d.findings) {
    json one;
    if (f.source == TableFinding::Source::Dwells) {
      const CandidateTest& c = r.findings[dwell_k++];
      one = finding_json(u, c, *before, r.alpha);
      before = &c.with;
    } else {
      const KalmanCandidateTest& c = d.turns->findings[turn_k++];
      one = kalman_finding_json(c, nis, ll, r.alpha);
    }
    if (f.filter) {
      nis = f.nis_after;
      ll = f.log_likelihood_after;
    }
    add_story_fields(one, f);
    findings.push_back(one);
  }
  j["findings"] = findings;
  j["not_separable"] = not_separable_json(r);
  j["ambiguous"] = ambiguous_json(r);
  j["rounds"] = rounds_json(u, r);
  j["initial"] = fit_json(u, r.initial);
  j["calibration"] = {{"coefficients", coefficients_json(result_coefficients(r.final_fit.fit))},
                      {"fit", fit_json(u, r.final_fit)}};
  json dwells = json::array();
  for (const auto& w : r.residuals) dwells.push_back(dwell_json(w));
  j["dwells"] = dwells;
  if (d.turns) add_kalman_diagnosis(j, *d.turns, false);
  add_verdict(j, d);
  return j;
}

namespace {

void markdown_finding(std::ostringstream& m, const TableFinding& f, int number) {
  m << "### " << number << ". " << finding_title(f) << "\n\n"
    << "Round " << f.round << ", found by "
    << (f.source == TableFinding::Source::Dwells
            ? "the static dwells (closed-form stage 2 residuals)"
            : "the turns (the Kalman filter's estimate of the family against zero)")
    << ": ";
  if (f.test == "wald")
    m << "W = " << fixed(f.statistic, 1) << " on " << f.dof << " dof";
  else if (f.test == "F")
    m << "F(" << f.dof << ", " << f.dof2 << ") = " << fixed(f.statistic, 2)
      << " (noise rescaled by the fit's residual)";
  else
    m << "likelihood ratio " << fixed(f.statistic, 1) << " on " << f.dof << " dof";
  m << ", p = " << sci(f.p_value) << " (threshold " << sci(f.threshold) << ").\n\n";
  if (!f.ambiguous_with.empty()) {
    m << "This plan cannot tell " << f.family;
    for (const auto& a : f.ambiguous_with) m << " from " << a;
    m << ": each explains the dwells as well. The model was extended with " << f.family << " ("
      << (f.picked_by == "user"      ? "`--prefer`"
          : f.picked_by == "turns"   ? "the turns' pick: the best held-out turns (each member's "
                                       "model predicting turns it was not fitted to); `--prefer "
                                       "FAMILY` picks another"
          : f.picked_by == "catalog" ? "the catalog's family: the library term predicts the "
                                       "held-out dwells and turns as well, the data cannot choose"
                                     : "the best fit; `--prefer FAMILY` picks another")
      << ")" << (f.pick_note.empty() ? "" : "; " + f.pick_note)
      << (f.separability.empty() ? "" : ". " + f.separability)
      << "; later rounds test the rest against it. What separates them: " << f.family << ": "
      << f.separated_by.front();
    for (std::size_t i = 0; i < f.ambiguous_with.size(); ++i)
      m << "; " << f.ambiguous_with[i] << ": " << f.separated_by[i + 1];
    m << ".\n\n";
  }
  m << "| held-out prediction | before | after |\n|---|---|---|\n";
  if (f.dwells_before && f.dwells_after)
    m << "| dwells, leave-one-out [sigma] | " << fixed(f.dwells_before->heldout, 2) << " | "
      << fixed(f.dwells_after->heldout, 2) << " |\n"
      << "| dwells, accel [ug] | " << fixed(f.dwells_before->heldout_accel / kAccelUnit, 2) << " | "
      << fixed(f.dwells_after->heldout_accel / kAccelUnit, 2) << " |\n"
      << "| dwells, gyro [deg/h] | " << fixed(f.dwells_before->heldout_gyro / kGyroUnit, 4) << " | "
      << fixed(f.dwells_after->heldout_gyro / kGyroUnit, 4) << " |\n";
  if (f.turns_before && f.turns_after && f.turns_before->turns > 0)
    m << "| turns held out of the filter [sigma] | " << fixed(f.turns_before->sigmas, 2) << " | "
      << fixed(f.turns_after->sigmas, 2) << " |\n"
      << "| turns, velocity error [mm/s] | " << fixed(f.turns_before->velocity / 1e-3, 3) << " | "
      << fixed(f.turns_after->velocity / 1e-3, 3) << " |\n";
  if (f.filter)
    m << "| filter NIS per dof (all updates) | " << fixed(f.nis_before, 3) << " | "
      << fixed(f.nis_after, 3) << " |\n";
  m << "\nCoefficients already in the model moved by up to " << fixed(f.base_shift_sigma, 1)
    << " of their sigmas. The extended calibration's " << f.family << ":\n\n"
    << "| coefficient | value | sigma | unit | from |\n|---|---|---|---|---|\n";
  const CoefficientFamily& info = coefficient_family_info(f.family);
  for (const auto& c : f.coefficients) {
    m << "| " << coefficient_catalog()[static_cast<std::size_t>(c.catalog)].name << " | ";
    if (c.source.empty())
      m << "not determined alone | - | " << info.unit() << " | - |\n";
    else
      m << sci(c.value / info.si_per_unit()) << " | " << sci(c.sigma / info.si_per_unit()) << " | "
        << info.unit() << " | " << (c.source == "kalman" ? "filter (dwells and turns)" : "dwells")
        << " |\n";
  }
  if (!f.combinations.empty()) {
    m << "\nDetermined only in combination (the dwells' fit):\n\n"
      << "| combination | value | sigma | unit |\n|---|---|---|---|\n";
    for (const auto& c : f.combinations)
      m << "| " << c.text() << " | " << sci(c.value / info.si_per_unit()) << " | "
        << sci(c.sigma / info.si_per_unit()) << " | " << info.unit() << " |\n";
  }
  m << "\n";
}

}  // namespace

std::string diagnosis_markdown(const TableDiagnosis& d, const std::string& session) {
  const DiagnosisReport& r = d.dwells;
  std::ostringstream m;
  m << "# Diagnosis of " << session << "\n\n"
    << "Static dwells: " << r.residuals.size() << ", " << r.inputs
    << " equivalent inputs. The calibrated model (" << r.initial_parameters.size()
    << " coefficients) leaves a residual chi2 per dof of " << fixed(r.initial.fit.chi2_per_dof, 3)
    << " (1 when it explains the dwells to their sigmas); residual RMS "
    << fixed(r.initial.accel_rms / kAccelUnit, 2) << " ug (accelerometers), "
    << fixed(r.initial.gyro_rms / kGyroUnit, 4) << " deg/h (gyros).";
  if (d.turns)
    m << " The Kalman filter with the same model: NIS per dof "
      << fixed(d.turns->initial_nis_per_dof, 3) << ".";
  const ResidualCheck& c = d.check;
  m << "\n\nWith the findings, the dwells' chi2 is " << fixed(c.dwells_chi2, 1) << " on "
    << c.dwells_dof << " dof (99 % quantile " << fixed(c.dwells_quantile, 1) << ")";
  if (c.filter)
    m << ", the filter's NIS per dof " << fixed(c.nis_per_dof, 3) << " (its innovations per "
      << "channel, NIS and whiteness at alpha " << c.innovations.alpha << ": "
      << c.innovations.verdict << ")";
  m << (c.holds() ? ": the noise model holds." : ": the noise model does not hold.");
  if (d.unexplained.present) {
    m << "\n\n**Unexplained** (no family of the catalog explains it; the sigmas are scaled by the "
         "residual: dwells x"
      << fixed(c.dwells_sigma_scale, 2) << ", filter x" << fixed(c.filter_sigma_scale, 2)
      << ", held-out dwells x" << fixed(c.heldout_sigma_scale, 2) << ", turns x"
      << fixed(c.turns_sigma_scale, 2) << "; the largest, x" << fixed(c.sigma_scale, 2)
      << ", applies):\n\n";
    for (const auto& s : d.unexplained.signature) m << "- " << s << "\n";
    if (d.unexplained.library)
      for (const auto& t : d.unexplained.library->terms)
        m << "- library term: " << t.text() << "\n";
  }
  for (const auto& s : d.stops)
    m << (&s == &d.stops.front() ? "\n\n" : "\n") << "Stop: " << s << ".";
  m << "\n\nEach round tests every candidate of the dwells" << (d.turns ? " and of the turns" : "")
    << " against one model at the family-wise level " << r.alpha
    << " (Bonferroni over the round's tests); the dwells' finding comes first, the "
       "round's finding joins the model and the next round tests the rest against it.\n\n"
    << "## Findings\n\n";
  if (d.findings.empty())
    m << "None: no candidate effect is significant at the family-wise level " << r.alpha << ".\n\n";
  int number = 0;
  for (const auto& f : d.findings) markdown_finding(m, f, ++number);
  DiagnosisReport hidden = r;
  hidden.ambiguous.clear();  // ambiguous sets are findings of their own above
  markdown_ambiguous_and_hidden(m, hidden, "plan's static dwells", "this plan");
  m << "\nPer-dwell residuals before and after: `residuals.png`; every figure: `diagnosis.json`.\n";
  if (d.turns) m << kalman_diagnosis_markdown(*d.turns);
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

DiagnosisFiles write_diagnosis(const TableDiagnosis& d, const std::string& session,
                               const std::string& dir, const std::string& gnuplot) {
  const DiagnosisReport& r = d.dwells;
  DiagnosisFiles f = diagnosis_files(dir);
  const json j = diagnosis_json(d, session);
  const std::string markdown = diagnosis_markdown(d, session);
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
