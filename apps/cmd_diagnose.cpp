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
#include "filter/thermal/soak_run.hpp"
#include "models/coefficient_families.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "report/diagnosis_report.hpp"

namespace sinscal::cli {

namespace {

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

}  // namespace

TableDiagnosis diagnose_table_session(const std::string& session_path,
                                      const TableDiagnoseOptions& t) {
  const Session session = Session::load(session_path);
  const DiagnosisFiles files = diagnosis_files(t.out_dir);
  refuse_overwrite(session_inputs(session), {{"diagnosis.json", files.json},
                                             {"report.md", files.markdown},
                                             {"residuals.png", files.png},
                                             {"gnuplot script", files.script}});
  std::optional<SensorProfile> profile;
  if (!session.sensor_file.empty()) profile = SensorProfile::load(session.sensor_file);
  Stage1Options s1 = default_stage1(profile ? &*profile : nullptr);
  s1.min_dwell = t.min_dwell;
  const PlausibilityLimits limits = PlausibilityLimits::from_profile(profile ? &*profile : nullptr);
  TableDiagnosisOptions to;
  to.dwells = t.dwells;
  to.dwells.thermal = log_temperature_varies(session);
  PlausibilityReport gate = check_plausibility(session, limits);
  enforce(gate, t.force);
  const TableAttitudeError table{t.table_sigma * units::arcsec};
  std::optional<TurnModel> turns;
  std::optional<ImuErrorModel> about;
  if (profile) {
    turns = turn_model_of(session, *profile, table.sigma);
    turns->run_filter = t.kalman;
    std::string failed;
    about = linearize(*turns, t.passes, &failed);
    if (!failed.empty())
      std::printf("The filter's passes to linearize about failed (%s): diagnosed about zero\n",
                  failed.c_str());
    if (about)
      std::printf(
          "Linearized about the filter's calibration (%d passes): the session's errors "
          "are beyond one linearization about zero\n",
          t.passes == 0 ? 3 : t.passes);
  }
  const ClosedFormReport calibration =
      run_closed_form(session, s1, table, !about, about ? &*about : nullptr);
  gate.checks.push_back(check_stage1_fit(calibration.stage1, limits, session.log.file));
  enforce(gate, t.force);
  Stage2Options s2 = calibration.stage2_options;
  if (profile) s2.reference_temperature_c = profile->reference_temperature_c;
  TableDiagnosis diagnosis =
      diagnose_table(calibration.stage1, session.site, s2, to, turns ? &*turns : nullptr);
  print_diagnosis(diagnosis);
  std::filesystem::create_directories(t.out_dir);
  const DiagnosisFiles written =
      write_diagnosis(diagnosis, session.path, t.out_dir, t.plot ? "gnuplot" : "");
  std::printf("Written: %s, %s%s%s\n", written.json.c_str(), written.markdown.c_str(),
              written.png.empty() ? "" : ", ", written.png.c_str());
  return diagnosis;
}

int cmd_diagnose(const std::vector<std::string>& args) {
  po::options_description d("sinscal diagnose options");
  std::string session_path, out_dir, sensor;
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
      ("force", "run even when the plausibility gate fails")
      ("sensor", po::value(&sensor),
       "chamber: the thermal model is this profile's thermal families (default: the soaks' "
       "profile)");
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
                        "its longest pose. A chamber session ([thermal] soaks) is calibrated\n"
                        "soak by soak and the thermal families its model lacks are tested.");
  if (!vm) return 0;
  if (!(o.alpha > 0.0 && o.alpha < 0.5)) throw UsageError("--alpha must be in (0, 0.5)");
  if (!(table_sigma > 0.0 && table_sigma < 3600.0))
    throw UsageError("--table-sigma must be above 0 and below 3600 arcsec");
  if (ChamberSoaks::is_chamber(session_path)) {
    for (const auto& name : {"min-dwell", "prefer", "passes", "no-kalman", "force"})
      if (given(*vm, name))
        throw UsageError(
            std::string("--") + name + " acts on table sessions; " + session_path +
            " is a chamber (its soaks are tested with --alpha, --table-sigma, --sensor)");
    for (const auto& name : kHandheldOnly)
      if (given(*vm, name))
        throw UsageError("--" + name + " acts on hand-held sessions; " + session_path +
                         " is a chamber");
    return diagnose_chamber(session_path, {out_dir, o.alpha, table_sigma, sensor});
  }
  if (!sensor.empty())
    throw UsageError("--sensor acts on chamber sessions; " + session_path + " is not one");
  const Session any = Session::load(session_path, Session::PlanNeed::Optional);
  if (any.six_face) return diagnose_six_face_session(any, out_dir, o.alpha);
  if (!any.has_plan) {
    if (given(*vm, "table-sigma") || vm->count("no-kalman") || given(*vm, "min-dwell") ||
        vm->count("prefer") || given(*vm, "passes"))
      throw UsageError(
          "--table-sigma, --min-dwell, --prefer, --passes and --no-kalman act on table "
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
    h.force = vm->count("force") > 0;
    return diagnose_handheld_session(any, h);
  }
  for (const auto& name : kHandheldOnly)
    if (given(*vm, name))
      throw UsageError("--" + name + " acts on hand-held sessions (no plan); " + session_path +
                       " has a plan");
  if (!(min_dwell > 0.0 && min_dwell < 1e6)) throw UsageError("--min-dwell must be positive");
  if (passes < 0 || passes > 20) throw UsageError("--passes must be 0 (automatic) to 20");
  for (const auto& f : o.prefer) {
    if (!is_extended_family(f))
      throw UsageError("--prefer " + f + ": not an extended family of the family table (" +
                       extended_terms_help() + ")");
  }
  TableDiagnoseOptions t;
  t.out_dir = out_dir;
  t.dwells = o;
  t.table_sigma = table_sigma;
  t.min_dwell = min_dwell;
  t.passes = passes;
  t.kalman = vm->count("no-kalman") == 0;
  t.plot = vm->count("no-plot") == 0;
  t.force = vm->count("force") > 0;
  diagnose_table_session(session_path, t);
  return 0;
}

}  // namespace sinscal::cli
