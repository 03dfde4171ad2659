// sinscal diagnose: what the calibrated model fails to explain on a table session, the missing
// effect that explains it, and the gain of adding it (filter/diagnosis.hpp); sessions without a
// plan are hand-held (apps/diagnose_handheld.cpp).
#include <cstdio>
#include <filesystem>
#include <optional>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "apps/diagnose.hpp"
#include "filter/diagnosis.hpp"
#include "filter/diagnosis_kalman.hpp"
#include "filter/plausibility.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "report/diagnosis_report.hpp"

namespace sinscal::cli {

namespace {

const std::vector<std::string> kHandheldOnly = {
    "gravity", "pose-window", "min-pose", "edge-trim", "validate", "candidates", "pose-accel-only"};

bool given(const po::variables_map& vm, const std::string& name) {
  return vm.count(name) && !vm[name].defaulted();
}

void add_handheld_options(po::options_description& d, HandheldDiagnoseOptions& h) {
  // clang-format off
  d.add_options()
      ("candidates", po::value(&h.candidates),
       "hand-held: the candidates tested, comma separated: extended families of the family "
       "table, noise (noise.bias_instability, noise.rate_random_walk), temperature (default: "
       "every family and noise)")
      ("validate", po::value(&h.validate)->composing(),
       "hand-held: a held-out validation session (repeatable), corrected before and after the "
       "findings")
      ("gravity", po::value(&h.run.gravity),
       "hand-held: local gravity [m/s^2] (default: the session's, else normal gravity)")
      ("pose-window", po::value(&h.run.detector.window)->default_value(1.0),
       "hand-held: window of the pose detector's variances [s]")
      ("min-pose", po::value(&h.run.detector.min_duration)->default_value(2.0),
       "hand-held: shortest static pose the detector takes [s]")
      ("edge-trim", po::value(&h.run.calibration.edge_trim)->default_value(0.2, "0.2"),
       "hand-held: cut from each end of a pose before its mean [s]")
      ("pose-accel-only", "hand-held: the accelerometers alone find the poses");
  // clang-format on
}

void print_diagnosis(const DiagnosisReport& r) {
  std::printf("Calibrated model: %zu coefficients, residual chi2 per dof %.3f over %zu dwells\n",
              r.initial_parameters.size(), r.initial.fit.chi2_per_dof, r.residuals.size());
  if (r.findings.empty())
    std::printf("Findings: none (no candidate significant at the family-wise level %g)\n", r.alpha);
  const FitFigures* before = &r.initial;
  for (const auto& f : r.findings) {
    std::printf(
        "Found %s: likelihood ratio %.1f on %d dof, p = %.3g; residual RMS %.2f -> %.2f ug, "
        "%.4f -> %.4f deg/h; held-out %.2f -> %.2f sigma; base moved up to %.1f sigma\n",
        f.family.c_str(), f.likelihood_ratio, f.dof, f.p_value, before->accel_rms / units::ug,
        f.with.accel_rms / units::ug, before->gyro_rms / units::deg_per_h,
        f.with.gyro_rms / units::deg_per_h, before->heldout, f.with.heldout, f.base_shift_sigma);
    before = &f.with;
  }
  for (const auto& a : r.ambiguous) {
    std::printf("Ambiguous: a significant residual (p = %.3g) that %s", a.p_value,
                a.family.c_str());
    for (const auto& b : a.ambiguous_with) std::printf(" and %s", b.family.c_str());
    std::printf(" explain equally well on this plan: neither is named\n");
  }
  for (const auto& c : r.not_separable)
    std::printf("Not separable on this plan: %s (%zu of its components); separated by %s\n",
                c.family.c_str(), c.aliased.size(), c.separated_by.c_str());
}

void print_kalman(const KalmanDiagnosis& k) {
  std::printf("Turns (Kalman-filter innovations, NIS per dof %.3f):\n", k.initial_nis_per_dof);
  for (const auto& f : k.findings)
    std::printf(
        "Found %s: W = %.1f on %d dof, p = %.3g; NIS per dof -> %.3f; base moved up to "
        "%.1f sigma\n",
        f.family.c_str(), f.wald, f.dof, f.p_value, f.nis_per_dof, f.base_shift_sigma);
  if (k.findings.empty()) std::printf("Findings: none\n");
  for (const auto& c : k.not_separable)
    std::printf("Not separable by the filter either: %s; separated by %s\n", c.family.c_str(),
                c.separated_by.c_str());
}

// The Kalman-filter test of the families the static dwells cannot separate.
std::optional<KalmanDiagnosis> diagnose_turns(const Session& session, const SensorProfile& profile,
                                              const DiagnosisReport& report, double alpha,
                                              double table_sigma) {
  CalibratorOptions ko = calibrator_options_from_profile(profile);
  ko.attitude_sigma = table_sigma;
  ko.time_offset = session.time_offset;
  // The effects the static dwells named are part of the model the filter runs with.
  for (const auto& f : report.findings)
    if (!ko.layout.on(f.family)) ko.layout.set(f.family, true);
  KalmanDiagnosisOptions ko_diag;
  ko_diag.alpha = alpha;
  for (const auto& c : report.not_separable)
    if (!ko.layout.on(c.family)) ko_diag.candidates.push_back(c.family);
  if (ko_diag.candidates.empty()) return std::nullopt;
  return diagnose_kalman(session, ko, ko_diag);
}

}  // namespace

int cmd_diagnose(const std::vector<std::string>& args) {
  po::options_description d("sinscal diagnose options");
  std::string session_path, out_dir;
  DiagnosisOptions o;
  double table_sigma = 2.5;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("session", po::value(&session_path)->required(), "session.ini of a table session")
      ("out", po::value(&out_dir)->required(),
       "directory for diagnosis.json, report.md, residuals.png (created)")
      ("alpha", po::value(&o.alpha)->default_value(0.01),
       "family-wise false-alarm level of each round of candidate tests")
      ("table-sigma", po::value(&table_sigma)->default_value(2.5),
       "table attitude error per orientation and axis, 1-sigma [arcsec]")
      ("no-plot", "write no PNG (no gnuplot needed)")
      ("no-kalman", "skip the Kalman-filter test of the effects of the turns")
      ("force", "run even when the plausibility gate fails");
  // clang-format on
  HandheldDiagnoseOptions h;
  add_handheld_options(d, h);
  const auto vm = parse(args, d,
                        "Usage: sinscal diagnose --session S --out DIR\n"
                        "Calibrates the session's static dwells (closed form), then tests every\n"
                        "extended family of the family table as a missing effect: names the\n"
                        "significant ones with their magnitude and gain, and says which the plan\n"
                        "cannot separate. The families the static dwells cannot separate\n"
                        "(effects of the turns) are then tested in the Kalman filter (needs the\n"
                        "session's sensor profile). A session without a plan is hand-held:\n"
                        "calibrated table-free, its poses and turns diagnosed, plus the noise of\n"
                        "its longest pose.");
  if (!vm) return 0;
  if (!(o.alpha > 0.0 && o.alpha < 0.5)) throw UsageError("--alpha must be in (0, 0.5)");
  const Session any = Session::load(session_path, Session::PlanNeed::Optional);
  if (!any.has_plan) {
    if (given(*vm, "table-sigma") || vm->count("force") || vm->count("no-kalman"))
      throw UsageError("--table-sigma, --force and --no-kalman act on table sessions; " +
                       session_path + " has no plan (a hand-held session)");
    if (given(*vm, "gravity") && !(h.run.gravity >= 9.7 && h.run.gravity <= 9.9))
      throw UsageError("--gravity must be within 9.7 and 9.9 m/s^2 (the Earth's surface)");
    if (!(h.run.detector.window > 0.0 && h.run.detector.window <= 60.0) ||
        !(h.run.detector.min_duration > 0.0 && h.run.detector.min_duration <= 3600.0) ||
        !(h.run.calibration.edge_trim >= 0.0 && h.run.calibration.edge_trim <= 60.0))
      throw UsageError(
          "--pose-window must be in (0, 60] s, --min-pose in (0, 3600] s, --edge-trim in "
          "[0, 60] s");
    h.run.detector.use_gyro = vm->count("pose-accel-only") == 0;
    h.out_dir = out_dir;
    h.alpha = o.alpha;
    h.plot = vm->count("no-plot") == 0;
    return diagnose_handheld_session(any, h);
  }
  for (const auto& name : kHandheldOnly)
    if (given(*vm, name))
      throw UsageError("--" + name + " acts on hand-held sessions (no plan); " + session_path +
                       " has a plan");
  if (!(table_sigma > 0.0 && table_sigma < 3600.0))
    throw UsageError("--table-sigma must be above 0 and below 3600 arcsec");
  const Session session = Session::load(session_path);
  const DiagnosisFiles files = diagnosis_files(out_dir);
  refuse_overwrite(session_inputs(session), {{"diagnosis.json", files.json},
                                             {"report.md", files.markdown},
                                             {"residuals.png", files.png},
                                             {"gnuplot script", files.script}});
  std::optional<SensorProfile> profile;
  if (!session.sensor_file.empty()) profile = SensorProfile::load(session.sensor_file);
  const Stage1Options s1 = default_stage1(profile ? &*profile : nullptr);
  const PlausibilityLimits limits = PlausibilityLimits::from_profile(profile ? &*profile : nullptr);
  const bool force = vm->count("force") > 0;
  PlausibilityReport gate = check_plausibility(session, limits);
  enforce(gate, force);
  const TableAttitudeError table{table_sigma * units::arcsec};
  const ClosedFormReport calibration = run_closed_form(session, s1, table);
  gate.checks.push_back(check_stage1_fit(calibration.stage1, limits, session.log.file));
  enforce(gate, force);
  const DiagnosisReport report =
      diagnose_static(calibration.stage1, session.site, calibration.stage2_options, o);
  print_diagnosis(report);
  std::optional<KalmanDiagnosis> turns;
  if (profile && !vm->count("no-kalman")) {
    turns = diagnose_turns(session, *profile, report, o.alpha, table.sigma);
    if (turns) print_kalman(*turns);
  }
  std::filesystem::create_directories(out_dir);
  const DiagnosisFiles written =
      write_diagnosis(report, session.path, out_dir, vm->count("no-plot") ? "" : "gnuplot",
                      turns ? &*turns : nullptr);
  std::printf("Written: %s, %s%s%s\n", written.json.c_str(), written.markdown.c_str(),
              written.png.empty() ? "" : ", ", written.png.c_str());
  return 0;
}

}  // namespace sinscal::cli
