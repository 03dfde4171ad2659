// sinscal calibrate: the options shared by every session of a run, and one session's calibration
// by either method (apps/calibrate_run.cpp).
#pragma once

#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "filter/plausibility/plausibility.hpp"
#include "report/batch.hpp"

namespace sinscal::cli {

struct CalibrateOptions {
  Method method = Method::ClosedForm;
  // closed form
  Stage1Method stage1 = Stage1Method::Fit;
  ErrorModelKind model = ErrorModelKind::Coupled;
  ChannelSet channels{true, true, true, true};
  double arw = 0.0, vrw = 0.0, min_dwell = 20.0;  // deg/sqrt(h), ug/sqrt(Hz), s
  // both
  double table_sigma = 2.5;      // arcsec
  bool cross_asymmetry = false;  // rate-table: the gyros' cross-axis asymmetries in the model
  bool gyro_drift = false;       // rate-table: the gyros' bias drift over the log in the model
  bool keep_unsteady = false;    // rate-table: rests whose outputs change level kept in the fit
  /// --misalignment-frame: table | triad | empty (the method's and mode's own frame).
  std::string misalignment_frame;
  // Kalman filter
  CalibratorOptions::AttitudeUpdates attitude = CalibratorOptions::AttitudeUpdates::Every;
  CalibratorOptions::StaticFrom static_from = CalibratorOptions::StaticFrom::Plan;
  OnBadSample on_bad_sample = OnBadSample::Stop;
  double monitor_interval = 10.0, static_window = 1.0, static_min = 3.0, static_rate = 3.0;
  double prior_scale = kDefaultPriorScale;
  std::string lever_arm_reference;  // x | y | z | empty
  bool no_table_angles = false, no_zero_velocity = false, no_position = false;
  bool no_motion_zero_velocity = false, stream = false;
  bool force = false;  // run even when the plausibility gate fails (recorded in the result)
  int passes = 1;      // 0: automatic (filter/kalman/pass_linearization.hpp)
  std::string base = "estimated";  // the table base: estimated | known (the plan's)
  std::string motion = "data";     // kf: the linearization motion: data | plan
  std::string terms;
  // table-free (apps/calibrate_table_free.cpp)
  double gravity = 0.0;                      // m/s^2, 0: the session's
  double pose_window = 1.0, min_pose = 2.0;  // s: pose detector
  double edge_trim = 0.2;                    // s cut from each end of a pose
  bool pose_accel_only = false;              // the accelerometers alone find the poses
  std::vector<std::string> validate;         // validation sessions
  /// The table-free options given on the command line (they override the session's
  /// [table_free]); filled by check_table_free_options.
  std::vector<std::string> table_free_given;
};

/// The Kalman filter's option values (UsageError naming the option), before any session runs.
void check_kf_values(const CalibrateOptions& o);
/// --misalignment-frame as the estimators take it (ByMode when not given); UsageError for an
/// unknown name, for the table frame without attitude updates (the cause) and for the methods
/// that have no choice of frame.
MisalignmentFrame misalignment_frame_option(const CalibrateOptions& o);

/// The table-free options (--gravity, --pose-window, ...) added to `d`.
void add_table_free_options(po::options_description& d, CalibrateOptions& o);
/// Options of the other methods refused in --method table-free and the table-free options in
/// the others (UsageError naming the option); the table-free values checked and those given
/// recorded in o.table_free_given.
void check_table_free_options(const po::variables_map& vm, CalibrateOptions& o,
                              const std::vector<std::vector<std::string>>& table_methods_options);
/// One hand-held session by the table-free method (a session without a plan is allowed).
SessionSummary calibrate_table_free_session(const CalibrateOptions& o,
                                            const std::string& session_path,
                                            const std::string& out_path, bool verbose);

/// One session of the six-face and known-turn procedure (apps/calibrate_six_face.cpp).
SessionSummary calibrate_six_face_session(const CalibrateOptions& o,
                                          const std::string& session_path,
                                          const std::string& out_path, bool verbose);

/// One session of rate-table segments and static positions, from their means
/// (apps/calibrate_rate_table.cpp).
SessionSummary calibrate_rate_table_session(const CalibrateOptions& o,
                                            const std::string& session_path,
                                            const std::string& out_path, bool verbose);

/// The gate's report as the result's "plausibility" section (nothing when no check ran).
void record_gate(nlohmann::ordered_json& sections, const PlausibilityReport& report);

/// Where the result came from as its "provenance" section (docs/formats.md): version, date,
/// command line, the session's files with their SHA-256 (a log read from standard input: none).
void record_provenance(nlohmann::ordered_json& sections, const Session& session,
                       const std::string& monitor_path = "", bool stdin_log = false);

/// One session by the options' method: the result file, the monitor file (kf, may be empty);
/// `verbose`: tables and verdicts on standard output (a single session); `live`: the live table
/// on the terminal. Returns the session's summary row (status by the run-status rules).
SessionSummary calibrate_session(const CalibrateOptions& o, const std::string& session_path,
                                 const std::string& out_path, const std::string& monitor_path,
                                 bool verbose, bool live);

}  // namespace sinscal::cli
