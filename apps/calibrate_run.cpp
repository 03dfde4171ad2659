// One session's calibration for sinscal calibrate: options to the library, results to files,
// tables and verdicts to the terminal.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include "apps/calibrate.hpp"
#include "apps/handheld_gate.hpp"
#include "apps/print.hpp"
#include "filter/kalman/motion_from_data.hpp"
#include "filter/plausibility/plausibility.hpp"
#include "filter/plausibility/rest_plausibility.hpp"
#include "filter/plausibility/turn_timing.hpp"
#include "models/units.hpp"
#include "report/monitor.hpp"
#include "report/output.hpp"
#include "report/provenance.hpp"

namespace sinscal::cli {

namespace {

CalibratorOptions kalman_options(const CalibrateOptions& o, const Session& session,
                                 const SensorProfile& profile) {
  CalibratorOptions ko = calibrator_options_from_profile(profile, o.prior_scale);
  ko.attitude_sigma = o.table_sigma * units::arcsec;
  ko.attitude = o.attitude;
  ko.position = !o.no_position;
  ko.zero_velocity_in_motion = !o.no_motion_zero_velocity;
  ko.time_offset = session.time_offset;
  ko.use_table_angles = !o.no_table_angles;
  ko.zero_velocity = !o.no_zero_velocity;
  ko.base_attitude = o.base != "known";
  try {
    apply_terms(ko.layout, o.terms);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--terms: ") + e.what());
  }
  if (!o.lever_arm_reference.empty()) {
    if (!ko.layout.on("accel.lever_arm"))
      throw UsageError(
          "--lever-arm-reference: the lever arms are not estimated (the profile or "
          "--terms leaves them out)");
    set_lever_arm_reference(ko.layout, o.lever_arm_reference);
  }
  ko.misalignment_frame = misalignment_frame_option(o);
  ko.static_from = o.static_from;
  ko.detector.window = o.static_window;
  ko.detector.min_duration = o.static_min;
  ko.detector.rate_threshold = o.static_rate * units::deg_per_s;
  return ko;
}

// A log without a time column: its times come from the session's rate, an assumption the
// terminal states.
void print_timing_assumption(const PlausibilityReport& report) {
  for (const auto& c : report.checks)
    if (c.name == "sample intervals" && c.passed &&
        c.detail.find("no time column") != std::string::npos)
      std::fprintf(stderr, "Assumption: %s\n", c.detail.c_str());
}

}  // namespace

namespace {

// The plausibility gate (filter/plausibility/plausibility.hpp) before any estimate: a failure stops
// with the checks' messages (exit 2) unless --force, which runs anyway and records them in the
// result. Standard input cannot be read twice: a streamed log is checked by the filter's own
// alarms.
// The Kalman filter's motion from the data gives the gate the log's offset and the dwells where the
// data are still (a foreign log's smoothed turns reach into the plan's dwells).
PlausibilityReport plausibility_gate(const CalibrateOptions& o, const Session& session,
                                     const PlausibilityLimits& limits, const SensorProfile* profile,
                                     const DataMotion* motion = nullptr) {
  if (o.stream) return {};
  const bool dwells_from_plan =
      o.method != Method::Kf || o.static_from == CalibratorOptions::StaticFrom::Plan;
  // Both methods integrate: they need a steady sample rate.
  const PlausibilityLimits l = integrating_limits(limits, session.log);
  PlausibilityReport report;
  if (motion) {
    LogReader reader(session.log);
    report = check_plausibility(reader, session.log.file, *motion->timeline, session.site,
                                motion->time_offset, l, dwells_from_plan);
  } else {
    report = check_plausibility(session, l, dwells_from_plan);
  }
  // Without a time column the turns between rests show whether the nominal rate holds.
  if (auto timing = no_time_turn_timing(session.log, profile)) report.checks.push_back(*timing);
  enforce(report, o.force);
  print_timing_assumption(report);
  return report;
}

// A log without a time column whose turns do not match its nominal rate (the gate's check, run
// with --force): a cause of a divergence the data show (APOPHIS, issue 34).
void add_timing_cause(std::string& message, const Session& session, const SensorProfile& profile) {
  try {
    const auto c = no_time_turn_timing(session.log, &profile);
    if (c && !c->passed) message += "; the cause the data show: " + c->detail;
  } catch (const std::runtime_error&) {
    // the log read once already: nothing more to say
  }
}

// A divergence's cause when the data show it: the first rest's noise against the profile's, the
// log's time against its turns. The same for a run that found fewer static intervals than the
// plan's dwells (outputs at rest beyond the noise the detector's bounds come from).
void add_divergence_cause(KalmanRun& kr, const Session& session, const SensorProfile& profile) {
  const bool too_few_static = kr.diverged.empty() && kr.detected &&
                              kr.stopped.find(" static intervals, the plan ") != std::string::npos;
  if (kr.diverged.empty() && !too_few_static) return;
  std::string& message = too_few_static ? kr.stopped : kr.diverged;
  double t0 = 0.0, t1 = 0.0;
  if (kr.detected && !kr.detected->intervals.empty()) {
    t0 = kr.detected->intervals.front().t_start;
    t1 = kr.detected->intervals.front().t_end;
  } else {
    const PlanTimeline timeline = PlanTimeline::of(session.plan, session.site);
    if (timeline.dwells.empty()) return;
    t0 = timeline.dwells.front().t_start + session.time_offset;
    t1 = timeline.dwells.front().t_end + session.time_offset;
  }
  try {
    const std::string cause =
        rest_noise_cause(session.log, t0, t1, profile.noise.gyro.white, profile.noise.accel.white);
    if (!cause.empty()) message += "; the cause the data show: " + cause;
  } catch (const std::runtime_error&) {
    // the log read once already: nothing more to say
  }
  add_timing_cause(message, session, profile);
}

SessionSummary calibrate_kf(const CalibrateOptions& o, const Session& session,
                            const std::string& out_path, const std::string& monitor_path,
                            bool verbose, bool live) {
  if (session.sensor_file.empty())
    throw UsageError(session.path +
                     ": --method kf needs the session's sensor profile ([session] sensor =)");
  const SensorProfile profile = SensorProfile::load(session.sensor_file);
  const CalibratorOptions ko = kalman_options(o, session, profile);
  // The motion from the data, once: for the gate and the filter.
  std::optional<DataMotion> motion;
  if (!o.stream && o.motion == "data" && motion_from_data_applies(ko)) try {
      motion = motion_from_data(session, ko);
    } catch (const std::runtime_error&) {
      motion.reset();  // the gate and the filter read the log again and say what is wrong
    }
  PlausibilityReport gate =
      plausibility_gate(o, session, PlausibilityLimits::from_profile(&profile), &profile,
                        motion ? &*motion : nullptr);
  KalmanRunOptions run;
  run.motion = motion ? &*motion : nullptr;
  run.skip_bad_samples = o.on_bad_sample == OnBadSample::Skip;
  run.passes = o.passes;
  run.motion_from_data = o.motion == "data";
  run.stop = &g_stop;
  run.sigma_targets = profile.sigma_targets;
  std::unique_ptr<LogReader> stdin_reader;
  if (o.stream) {
    LogFormat f = session.log;
    f.file = "<stdin>";
    stdin_reader = std::make_unique<LogReader>(std::cin, f);
  }
  KalmanRun kr;
  const auto t0 = std::chrono::steady_clock::now();
  auto calibrate = [&](std::ostream* monitor) {
    if (monitor || live) {
      run.monitor_interval = o.monitor_interval;
      run.monitor = [&](const MonitorRecord& rec) {
        // One write per line, flushed: a kill leaves every complete line (a cut last one at
        // worst, which read_monitor skips).
        if (monitor) *monitor << (monitor_line(rec) + "\n") << std::flush;
        if (live) print_live_table(rec, profile.sigma_targets);
      };
    }
    kr = run_kalman(session, ko, stdin_reader.get(), run);
  };
  if (monitor_path.empty()) {
    calibrate(nullptr);
  } else {
    std::ofstream m = open_append_log(monitor_path);
    calibrate(&m);
    if (!m.flush()) throw std::runtime_error(monitor_path + ": write failed");
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if ((!kr.diverged.empty() || !kr.stopped.empty()) && !o.stream)
    add_divergence_cause(kr, session, profile);
  if (!kr.model.vector().allFinite())
    throw std::runtime_error(session.log.file +
                             ": the filter's estimates are not finite numbers (nothing written)" +
                             (kr.diverged.empty() ? std::string() : ": " + kr.diverged));
  // The filter's linear range: a pass far from what it linearized about is refused (exit 2). A
  // run that diverged or stopped has its own verdict.
  if (kr.diverged.empty() && kr.stopped.empty()) {
    gate.checks.push_back(check_kf_linearization(kr.linearization, o.passes,
                                                 kr.passes.empty() ? 1 : kr.passes.back().pass,
                                                 session.log.file, o.stream));
    enforce(gate, o.force);
  }
  const ResultCoefficients coefficients = result_coefficients(kr);
  auto sections = result_sections(kr);
  record_gate(sections, gate);
  record_provenance(sections, session, monitor_path, o.stream);
  write_result_json(out_path, coefficients, sections);
  const ResultCoefficients truth = load_truth(session, kr.accel_triad_frame, o.lever_arm_reference);
  SessionSummary row{session.path,
                     session.name,
                     out_path,
                     "",
                     "",
                     kr.samples,
                     kr.duration,
                     kr.nis_per_dof,
                     kr.converged_at,
                     max_error_over_sigma(coefficients, truth),
                     coefficients};
  set_status(kr, row);
  if (!verbose) return row;
  std::printf("Kalman-filter calibration of '%s': %d states, %zu samples, NIS per dof %.3f\n",
              session.name.c_str(), kr.states, kr.samples, kr.nis_per_dof);
  if (kr.motion) std::printf("Motion: %s\n", kr.motion->summary().c_str());
  std::printf("Misalignment frame: %s%s\n", misalignment_frame_name(kr.misalignment_frame).c_str(),
              kr.converted_to_triad_frame ? " (estimated relative to the table, converted)" : "");
  print_coefficient_table(coefficients, truth);
  std::printf("\nResult written to %s (%.2f s, %.0fx real time)\n", out_path.c_str(), seconds,
              kr.duration / seconds);
  print_kalman_verdicts(kr, profile, truth);
  print_innovation_check(kr.innovations);
  return row;
}

SessionSummary calibrate_closed_form(const CalibrateOptions& co, const Session& session,
                                     const std::string& out_path, bool verbose) {
  std::optional<SensorProfile> profile;
  if (!session.sensor_file.empty()) profile = SensorProfile::load(session.sensor_file);
  Stage1Options o = default_stage1(profile ? &*profile : nullptr);
  o.method = co.stage1;
  o.model = co.model;
  o.channels = co.channels;
  o.min_dwell = co.min_dwell;
  const PlausibilityLimits limits = PlausibilityLimits::from_profile(profile ? &*profile : nullptr);
  PlausibilityReport gate = plausibility_gate(co, session, limits, profile ? &*profile : nullptr);
  if (co.arw > 0.0) o.arw = co.arw * units::deg_per_sqrt_h;
  if (co.vrw > 0.0) o.vrw = co.vrw * units::ug_per_sqrt_hz;
  const auto t0 = std::chrono::steady_clock::now();
  const ClosedFormReport r =
      run_closed_form_relinearized(session, o, TableAttitudeError{co.table_sigma * units::arcsec});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  gate.checks.push_back(check_stage1_fit(r.stage1, limits, session.log.file));
  gate.checks.push_back(check_linear_range(r, session.log.file));
  gate.checks.push_back(check_stage2_fit(r, limits, session.log.file));
  enforce(gate, co.force);
  const MisalignmentFrame frame = misalignment_frame_option(co) == MisalignmentFrame::Triad
                                      ? MisalignmentFrame::Triad
                                      : MisalignmentFrame::Table;
  const ResultCoefficients coefficients = result_coefficients(r, frame);
  auto sections = result_sections(r, frame);
  sections["linearization"] = {
      {"linearizations", r.linearizations},
      {"removed_gyro_bias_deg_per_s",
       {r.removed_gyro_bias.x() / units::deg_per_s, r.removed_gyro_bias.y() / units::deg_per_s,
        r.removed_gyro_bias.z() / units::deg_per_s}},
      {"largest_turn_dwell", r.largest_turn_dwell},
      {"largest_turn_deg", r.largest_turn / units::deg},
      {"linear_turn_deg", r.linear_turn / units::deg},
      {"removed_accel", r.removed_accel},
      {"largest_speed_dwell", r.largest_speed_dwell},
      {"largest_speed_m_per_s", r.largest_speed},
      {"linear_speed_m_per_s", r.linear_speed}};
  record_gate(sections, gate);
  record_provenance(sections, session);
  write_result_json(out_path, coefficients, sections);
  const ResultCoefficients truth = load_truth(session, frame == MisalignmentFrame::Triad);
  SessionSummary row{session.path, session.name,
                     out_path,     "ok",
                     "",           0,
                     0.0,          std::nullopt,
                     std::nullopt, max_error_over_sigma(coefficients, truth),
                     coefficients};
  for (const auto& e : r.stage1) row.duration += e.duration;
  if (!verbose) return row;
  std::printf(
      "Closed-form calibration of '%s': stage 1 %s, %s model, channels %s, table %.2f arcsec\n",
      session.name.c_str(), name_of(co.stage1).c_str(), name_of(co.model).c_str(),
      name_of(co.channels).c_str(), co.table_sigma);
  std::printf("Misalignment frame: %s\n", misalignment_frame_name(frame).c_str());
  print_closed_form(r, coefficients, truth);
  if (r.linearizations > 1)
    std::printf(
        "Relinearized %d times about the closed form's own gyro biases (%.4f, %.4f, %.4f deg/s "
        "removed)%s: dwell %s turns %.3f deg (stage 1's linear range %.3f deg), dwell %s "
        "reaches %.3g m/s (range %.3g m/s)\n",
        r.linearizations - 1, r.removed_gyro_bias.x() / units::deg_per_s,
        r.removed_gyro_bias.y() / units::deg_per_s, r.removed_gyro_bias.z() / units::deg_per_s,
        r.removed_accel ? " and accelerometer bias, scale and misalignment" : "",
        r.largest_turn_dwell.c_str(), r.largest_turn / units::deg, r.linear_turn / units::deg,
        r.largest_speed_dwell.c_str(), r.largest_speed, r.linear_speed);
  std::printf("\nResult written to %s (%.2f s)\n", out_path.c_str(), seconds);
  return row;
}

}  // namespace

MisalignmentFrame misalignment_frame_option(const CalibrateOptions& o) {
  if (o.misalignment_frame.empty()) return MisalignmentFrame::ByMode;
  if (o.method != Method::Kf && o.method != Method::ClosedForm)
    throw UsageError(
        "--misalignment-frame is an option of the table methods (kf, closed-form): "
        "--method " +
        name_of(o.method) + " reports in its own body frame");
  MisalignmentFrame f;
  try {
    f = parse_misalignment_frame(o.misalignment_frame);
    if (o.method == Method::Kf)
      resolve_misalignment_frame(f, o.attitude != CalibratorOptions::AttitudeUpdates::None);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--misalignment-frame: ") + e.what());
  }
  return f;
}

// The Kalman filter's option values (--method kf), checked before any session runs.
void check_kf_values(const CalibrateOptions& o) {
  misalignment_frame_option(o);
  if (o.base != "estimated" && o.base != "known")
    throw UsageError("--base must be estimated or known, not '" + o.base + "'");
  if (!(o.static_window > 0.0) || !(o.static_min >= o.static_window) || !(o.static_rate > 0.0))
    throw UsageError(
        "--static-window must be positive, --static-min at least the window, "
        "--static-rate-threshold positive");
  if (o.passes < 0 || o.passes > 20) throw UsageError("--passes must be 0 (automatic) to 20");
  if (o.motion != "data" && o.motion != "plan")
    throw UsageError("--motion must be data or plan, not '" + o.motion + "'");
  if (o.passes > 1 && o.stream) throw UsageError("--passes reads the log again: not with --stream");
  if (!o.lever_arm_reference.empty() && o.lever_arm_reference != "x" &&
      o.lever_arm_reference != "y" && o.lever_arm_reference != "z")
    throw UsageError("--lever-arm-reference must be x, y or z");
  if (!o.lever_arm_reference.empty() && !(o.no_motion_zero_velocity && o.no_position))
    throw UsageError(
        "--lever-arm-reference is for zero velocity at rest only (--no-motion-zero-velocity "
        "--no-position), where a common shift of the lever arms is unobservable; otherwise the "
        "arms are observable and fixing one would bias the others");
  if (!o.terms.empty()) try {
      StateLayoutOptions check;
      apply_terms(check, o.terms);
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--terms: ") + e.what());
    }
}

void record_gate(nlohmann::ordered_json& sections, const PlausibilityReport& report) {
  if (report.checks.empty()) return;
  nlohmann::ordered_json checks = nlohmann::ordered_json::array();
  for (const auto& c : report.checks)
    checks.push_back({{"check", c.name}, {"passed", c.passed}, {"detail", c.detail}});
  sections["plausibility"] = {{"passed", report.passed()}, {"checks", checks}};
}

void record_provenance(nlohmann::ordered_json& sections, const Session& session,
                       const std::string& monitor_path, bool stdin_log) {
  ProvenanceInput in;
  in.command_line = g_command_line;
  in.session = session.path;
  in.session_name = session.name;
  in.sensor_profile = session.sensor_file;
  if (!session.sensor_file.empty())
    in.sensor_profile_name = SensorProfile::load(session.sensor_file).name;
  in.files = session_inputs(session);
  in.stdin_log = stdin_log;
  in.monitor = monitor_path;
  sections["provenance"] = provenance_section(in);
}

SessionSummary calibrate_session(const CalibrateOptions& o, const std::string& session_path,
                                 const std::string& out_path, const std::string& monitor_path,
                                 bool verbose, bool live) {
  if (o.method == Method::TableFree)
    return calibrate_table_free_session(o, session_path, out_path, verbose);
  if (o.method == Method::SixFace)
    return calibrate_six_face_session(o, session_path, out_path, verbose);
  if (o.method == Method::RateTable)
    return calibrate_rate_table_session(o, session_path, out_path, verbose);
  const Session session = Session::load(session_path);
  refuse_overwrite(session_inputs(session), {{"--out", out_path}, {"--monitor", monitor_path}});
  return o.method == Method::Kf ? calibrate_kf(o, session, out_path, monitor_path, verbose, live)
                                : calibrate_closed_form(o, session, out_path, verbose);
}

}  // namespace sinscal::cli
