// sinscal calibrate --method table-free: a hand-held session's calibration without a table
// (filter/table_free/handheld_run.hpp), its options, result file and summary.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <optional>

#include "apps/calibrate.hpp"
#include "apps/handheld_gate.hpp"
#include "apps/print.hpp"
#include "filter/plausibility/rest_plausibility.hpp"
#include "filter/plausibility/turn_timing.hpp"
#include "models/earth.hpp"
#include "report/table_free_result.hpp"

namespace sinscal::cli {

TableFreeRun gated_table_free_run(const Session& session, TableFreeRunOptions ro, bool force,
                                  PlausibilityReport& gate, HandheldFitBounds* bounds) {
  // The rests before the fit, then the fit's parts: a failure stops (exit 2) unless force,
  // which records it.
  std::optional<SensorProfile> profile;
  if (!session.sensor_file.empty()) profile = SensorProfile::load(session.sensor_file);
  const RestLimits limits = RestLimits::from_profile(profile ? &*profile : nullptr);
  ro.before_fit = [&](const HandheldRecord&, const TableFreeRun& r) {
    const double g = r.options.gravity > 0.0
                         ? r.options.gravity
                         : Earth::wgs84().gravity_n(r.site.lat_rad, r.site.h_m).norm();
    gate = check_handheld(session.log, r.readings, r.detection.poses, g, limits, r.log);
    // The fit integrates the turns: a log without time has its nominal rate checked by them.
    if (auto timing = no_time_turn_timing(session.log, profile ? &*profile : nullptr))
      gate.checks.push_back(*timing);
    enforce(gate, force);
  };
  TableFreeRun run = run_table_free(session, ro);
  if (bounds) *bounds = handheld_fit_bounds(run.result, limits);
  gate.checks.push_back(check_handheld_fit(run.result, limits, run.log));
  enforce(gate, force);
  return run;
}

namespace {
const std::vector<std::string> kTableFreeOnly = {"gravity",   "pose-window",     "min-pose",
                                                 "edge-trim", "pose-accel-only", "validate"};

bool given(const po::variables_map& vm, const std::string& name) {
  return vm.count(name) && !vm[name].defaulted();
}
}  // namespace

void add_table_free_options(po::options_description& d, CalibrateOptions& o) {
  // clang-format off
  d.add_options()
      ("gravity", po::value(&o.gravity),
       "table-free: local gravity magnitude [m/s^2] (default: the session's [site] gravity, else "
       "WGS-84 normal gravity at its site)")
      ("pose-window", po::value(&o.pose_window)->default_value(1.0),
       "table-free: window of the pose detector's variances [s]")
      ("min-pose", po::value(&o.min_pose)->default_value(2.0),
       "table-free: shortest static pose the detector takes [s]")
      ("edge-trim", po::value(&o.edge_trim)->default_value(0.2, "0.2"),
       "table-free: cut from each end of a pose before its mean [s]")
      ("pose-accel-only", po::bool_switch(&o.pose_accel_only), "table-free: the accelerometers alone find the poses (a unit held in "
       "the hand, whose gyros see the tremor)")
      ("validate", po::value(&o.validate)->composing(),
       "table-free: a validation session (repeatable): its poses and turns corrected with the "
       "calibration, nominal against calibrated, in the result");
  // clang-format on
}

void check_table_free_options(const po::variables_map& vm, CalibrateOptions& o,
                              const std::vector<std::vector<std::string>>& table_methods_options) {
  if (o.method != Method::TableFree) {
    for (const auto& name : kTableFreeOnly)
      if (given(vm, name) && !(o.method == Method::SixFace && name == "gravity"))
        throw UsageError("--" + name + " acts in --method table-free only, not in --method " +
                         name_of(o.method));
    if (o.method != Method::SixFace) return;
  }
  for (const auto& list : table_methods_options)
    for (const auto& name : list)
      if (given(vm, name))
        throw UsageError("--" + name +
                         " is an option of the table methods (closed-form, kf), not of --method " +
                         name_of(o.method));
  for (const auto& name : kTableFreeOnly)
    if (given(vm, name)) o.table_free_given.push_back(name);
  if (given(vm, "gravity") && !(o.gravity >= 9.7 && o.gravity <= 9.9))
    throw UsageError("--gravity must be within 9.7 and 9.9 m/s^2 (the Earth's surface)");
  if (!(o.pose_window > 0.0 && o.pose_window <= 60.0))
    throw UsageError("--pose-window must be above 0 and at most 60 s");
  if (!(o.min_pose > 0.0 && o.min_pose <= 3600.0))
    throw UsageError("--min-pose must be above 0 and at most 3600 s");
  if (!(o.edge_trim >= 0.0 && o.edge_trim <= 60.0))
    throw UsageError("--edge-trim must be 0 to 60 s");
}

SessionSummary calibrate_table_free_session(const CalibrateOptions& o,
                                            const std::string& session_path,
                                            const std::string& out_path, bool verbose) {
  const Session session = Session::load(session_path, Session::PlanNeed::Optional);
  std::vector<Session> validations;
  auto inputs = session_inputs(session);
  for (const auto& path : o.validate) {
    validations.push_back(Session::load(path, Session::PlanNeed::Optional));
    const auto more = session_inputs(validations.back());
    inputs.insert(inputs.end(), more.begin(), more.end());
  }
  refuse_overwrite(inputs, {{"--out", out_path}});
  // The session's [table_free] where the command line does not give the option.
  auto pick = [&](const char* name, const auto& from_session, auto from_line) {
    const bool on_line = std::find(o.table_free_given.begin(), o.table_free_given.end(), name) !=
                         o.table_free_given.end();
    return !on_line && from_session ? *from_session : from_line;
  };
  const TableFreeSettings& st = session.table_free;
  TableFreeRunOptions ro;
  ro.gravity = o.gravity;
  ro.detector.window = pick("pose-window", st.pose_window, o.pose_window);
  ro.detector.min_duration = pick("min-pose", st.min_pose, o.min_pose);
  ro.detector.use_gyro = !pick("pose-accel-only", st.pose_accel_only, o.pose_accel_only);
  ro.calibration.edge_trim = pick("edge-trim", st.edge_trim, o.edge_trim);
  PlausibilityReport gate;
  const auto t0 = std::chrono::steady_clock::now();
  HandheldFitBounds bounds;
  TableFreeRun run = gated_table_free_run(session, ro, o.force, gate, &bounds);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  // A validation record that cannot be used still leaves the calibration written.
  std::string validation_error;
  for (const auto& v : validations) try {
      run.validations.push_back(validate_table_free(v, run, ro.detector));
    } catch (const std::exception& e) {
      validation_error = "validation session " + v.path + ": " + e.what();
      break;
    }
  const ResultCoefficients coefficients = result_coefficients(run);
  auto sections = result_sections(run);
  record_gate(sections, gate);
  record_provenance(sections, session);
  write_result_json(out_path, coefficients, sections);
  if (!validation_error.empty()) throw std::runtime_error(validation_error);
  const ResultCoefficients truth = load_truth(session, true);
  SessionSummary row{session.path, session.name,
                     out_path,     "ok",
                     "",           run.samples,
                     run.duration, std::nullopt,
                     std::nullopt, max_error_over_sigma(coefficients, truth),
                     coefficients};
  if (!verbose) return row;
  print_table_free(run, bounds, coefficients, truth);
  std::printf("\nResult written to %s (%.2f s: reading, pose detection and calibration)\n",
              out_path.c_str(), seconds);
  return row;
}

}  // namespace sinscal::cli
