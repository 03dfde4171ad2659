// sinscal diagnose: what the calibrated model fails to explain on a table session, the missing
// effect that explains it, and the gain of adding it (filter/diagnosis/diagnosis.hpp); sessions
// without a plan are hand-held (apps/diagnose_handheld.cpp).
#include <cstdio>
#include <filesystem>
#include <optional>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "apps/diagnose.hpp"
#include "filter/diagnosis/diagnosis_table.hpp"
#include "filter/plausibility/plausibility.hpp"
#include "models/coefficient_families.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "report/diagnosis_report.hpp"

namespace sinscal::cli {

namespace {

// The dwells' residual chi2 per dof above which the output cautions that the noise model does
// not hold (a clean nav-fog session: 0.7-1.2; a clean MEMS session, bias instability unmodelled
// by the dwells: 5).
constexpr double kNoiseModelCaution = 2.5;

// An extended family of the family table.
bool is_extended_family(const std::string& name) {
  for (const auto& f : coefficient_families())
    if (f.name == name) return !f.base;
  return false;
}

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

void print_diagnosis(const TableDiagnosis& d) {
  const DiagnosisReport& r = d.dwells;
  std::printf("Calibrated model: %zu coefficients, residual chi2 per dof %.3f over %zu dwells",
              r.initial_parameters.size(), r.initial.fit.chi2_per_dof, r.residuals.size());
  if (d.turns) std::printf("; the filter's NIS per dof %.3f", d.turns->initial_nis_per_dof);
  std::printf("\n");
  if (r.final_fit.fit.chi2_per_dof > kNoiseModelCaution)
    std::printf(
        "Caution: with the findings, the dwells' residual is still %.1f times its noise model "
        "(unmodelled noise such "
        "as bias instability, or errors beyond the linearization): the tests rescale by it, "
        "but a finding without a held-out gain is doubtful\n",
        r.final_fit.fit.chi2_per_dof);
  if (d.findings.empty())
    std::printf("Findings: none (no candidate significant at the family-wise level %g)\n", r.alpha);
  int number = 0;
  for (const auto& f : d.findings) {
    std::printf("%d. %s: %s\n", ++number, finding_title(f).c_str(), finding_summary(f).c_str());
    const CoefficientFamily& info = coefficient_family_info(f.family);
    int undetermined = 0;
    for (const auto& c : f.coefficients) {
      if (c.source.empty()) {
        ++undetermined;
        continue;
      }
      std::printf("     %-26s %12.4g +- %-10.3g %s\n",
                  coefficient_catalog()[static_cast<std::size_t>(c.catalog)].name.c_str(),
                  c.value / info.si_per_unit(), c.sigma / info.si_per_unit(), info.unit().c_str());
    }
    for (const auto& c : f.combinations)
      std::printf("     %s = %.4g +- %.3g %s\n", c.text().c_str(), c.value / info.si_per_unit(),
                  c.sigma / info.si_per_unit(), info.unit().c_str());
    if (undetermined > 0 && f.combinations.empty())
      std::printf("     (%d components not determined on this plan)\n", undetermined);
    if (!f.ambiguous_with.empty()) {
      std::printf("   Separated by: %s: %s", f.family.c_str(), f.separated_by.front().c_str());
      for (std::size_t i = 0; i < f.ambiguous_with.size(); ++i)
        std::printf("; %s: %s", f.ambiguous_with[i].c_str(), f.separated_by[i + 1].c_str());
      std::printf("\n");
    }
  }
  for (const auto& c : r.not_separable) {
    bool turns_tested = false;
    if (d.turns)
      for (const auto& round : d.turns->rounds)
        for (const auto& k : round)
          turns_tested = turns_tested || (k.family == c.family && k.dof > 0);
    if (turns_tested) continue;  // the turns separate it
    std::printf("Not separable on this plan: %s (%zu of its components); separated by %s\n",
                c.family.c_str(), c.aliased.size(), c.separated_by.c_str());
  }
}

}  // namespace

int cmd_diagnose(const std::vector<std::string>& args) {
  po::options_description d("sinscal diagnose options");
  std::string session_path, out_dir;
  DiagnosisOptions o;
  double table_sigma = 2.5, min_dwell = 20.0;
  int passes = 0;
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
      ("min-dwell", po::value(&min_dwell)->default_value(20.0),
       "shortest static dwell stage 1 takes [s] (as calibrate --method closed-form)")
      ("prefer", po::value(&o.prefer)->multitoken()->composing(),
       "out of an ambiguous set (effects this plan cannot tell apart), extend the model with "
       "this family (repeatable; default: the member with the best fit)")
      ("passes", po::value(&passes)->default_value(0),
       "linearize both tests about the filter's calibration after this many passes (large "
       "errors: MEMS); 0: automatic (3 when one pass's NIS per dof is above 1.5), 1: about zero")
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
  if (any.six_face) return diagnose_six_face_session(any, out_dir, o.alpha);
  if (!any.has_plan) {
    if (given(*vm, "table-sigma") || vm->count("force") || vm->count("no-kalman") ||
        given(*vm, "min-dwell") || vm->count("prefer") || given(*vm, "passes"))
      throw UsageError(
          "--table-sigma, --min-dwell, --prefer, --passes, --force and --no-kalman act on table "
          "sessions; " +
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
    apply_table_free_settings(any.table_free, *vm, h.run.detector, &h.run.calibration.edge_trim);
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
  if (!(min_dwell > 0.0 && min_dwell < 1e6)) throw UsageError("--min-dwell must be positive");
  if (passes < 0 || passes > 20) throw UsageError("--passes must be 0 (automatic) to 20");
  for (const auto& f : o.prefer) {
    if (!is_extended_family(f))
      throw UsageError("--prefer " + f + ": not an extended family of the family table (" +
                       extended_terms_help() + ")");
  }
  const Session session = Session::load(session_path);
  const DiagnosisFiles files = diagnosis_files(out_dir);
  refuse_overwrite(session_inputs(session), {{"diagnosis.json", files.json},
                                             {"report.md", files.markdown},
                                             {"residuals.png", files.png},
                                             {"gnuplot script", files.script}});
  std::optional<SensorProfile> profile;
  if (!session.sensor_file.empty()) profile = SensorProfile::load(session.sensor_file);
  Stage1Options s1 = default_stage1(profile ? &*profile : nullptr);
  s1.min_dwell = min_dwell;
  const PlausibilityLimits limits = PlausibilityLimits::from_profile(profile ? &*profile : nullptr);
  const bool force = vm->count("force") > 0;
  PlausibilityReport gate = check_plausibility(session, limits);
  enforce(gate, force);
  const TableAttitudeError table{table_sigma * units::arcsec};
  std::optional<TurnModel> turns;
  std::optional<ImuErrorModel> about;
  if (profile) {
    turns = turn_model_of(session, *profile, table.sigma);
    turns->run_filter = vm->count("no-kalman") == 0;
    std::string failed;
    about = linearize(*turns, passes, &failed);
    if (!failed.empty())
      std::printf("The filter's passes to linearize about failed (%s): diagnosed about zero\n",
                  failed.c_str());
    if (about)
      std::printf(
          "Linearized about the filter's calibration (%d passes): the session's errors "
          "are beyond one linearization about zero\n",
          passes == 0 ? 3 : passes);
  }
  const ClosedFormReport calibration =
      run_closed_form(session, s1, table, !about, about ? &*about : nullptr);
  gate.checks.push_back(check_stage1_fit(calibration.stage1, limits, session.log.file));
  enforce(gate, force);
  TableDiagnosisOptions to;
  to.dwells = o;
  const TableDiagnosis diagnosis = diagnose_table(
      calibration.stage1, session.site, calibration.stage2_options, to, turns ? &*turns : nullptr);
  print_diagnosis(diagnosis);
  std::filesystem::create_directories(out_dir);
  const DiagnosisFiles written =
      write_diagnosis(diagnosis, session.path, out_dir, vm->count("no-plot") ? "" : "gnuplot");
  std::printf("Written: %s, %s%s%s\n", written.json.c_str(), written.markdown.c_str(),
              written.png.empty() ? "" : ", ", written.png.c_str());
  return 0;
}

}  // namespace sinscal::cli
