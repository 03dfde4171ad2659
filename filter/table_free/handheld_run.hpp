// Hand-held sessions end to end (the library behind `calibrate --method table-free` and `allan`):
// a session's whole log read into memory, its static poses found, the table-free calibration
// run from the log's nominal conversion (the starting values), validation records corrected
// with the result, and the Allan deviation of a static record or pose. Throws (ConfigError,
// LogError, TableFreeError, PoseDetectorError, AllanError, std::invalid_argument); prints
// nothing.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "filter/noise/allan.hpp"
#include "filter/table_free/pose_detector.hpp"
#include "filter/table_free/table_free.hpp"
#include "rig/session.hpp"

namespace sinscal {

/// A whole log in memory.
struct HandheldRecord {
  std::string file;                  // the log (a description naming its files)
  std::vector<ImuSample> samples;    // as read (increments, SI)
  std::vector<ImuReading> readings;  // their rates (SI, through the log's nominal conversion)
  /// Triads logged as rates in raw counts (`accel_scale` / `accel_offset` given, docs/formats.md):
  /// `nominal` then holds their conversion per body axis (counts = sensitivity * SI + offset,
  /// the log's sign included); a triad not in counts has sensitivity 1 and offset 0.
  bool accel_counts = false, gyro_counts = false;
  RawScaling nominal;
  /// The log axis (0, 1, 2 for x, y, z) each body axis comes from (`accel_axes`, `gyro_axes`).
  std::array<int, 3> accel_log_axis{0, 1, 2}, gyro_log_axis{0, 1, 2};
  bool raw() const { return accel_counts || gyro_counts; }
  /// The readings in counts (raw() logs) or SI: what the pose detector and the raw-count
  /// calibration take.
  std::vector<ImuReading> detector_readings() const;
};

/// Reads the whole log (any format of docs/formats.md). Throws LogError naming file and line.
HandheldRecord read_handheld_record(const LogFormat& log);

/// A detected pose with its statistics in SI (the detector's are in the readings' units).
struct HandheldPose {
  Pose pose;                                             // indices, times, count
  Eigen::Vector3d accel_mean = Eigen::Vector3d::Zero();  // m/s^2 (the log's nominal scaling)
  Eigen::Vector3d gyro_mean = Eigen::Vector3d::Zero();   // rad/s
  Eigen::Vector3d accel_std = Eigen::Vector3d::Zero();   // per reading
  Eigen::Vector3d gyro_std = Eigen::Vector3d::Zero();
};

/// The poses of a detection with SI statistics from `record`.
std::vector<HandheldPose> handheld_poses(const HandheldRecord& record,
                                         const PoseDetection& detection);

struct TableFreeRun;

struct TableFreeRunOptions {
  /// Edge trim, shortest pose, iterations. Gravity and site are set from `gravity` and the
  /// session.
  TableFreeOptions calibration;
  PoseDetectorOptions detector;
  /// m/s^2 given (command line); 0: the session's [site] gravity, else WGS-84 normal gravity at
  /// its site.
  double gravity = 0.0;
  /// Called with the record and the run so far (poses found, readings, gravity) before the
  /// calibration: a plausibility gate that throws stops it.
  std::function<void(const HandheldRecord&, const TableFreeRun&)> before_fit;
};

/// One validation record corrected with a calibration (docs/formats.md, "validation").
struct ValidationPose {
  int index = 0;
  double t_start = 0.0, t_end = 0.0;  // s
  /// |mean specific force| - gravity (m/s^2) and |mean rate| (rad/s) at rest, with the
  /// calibration session's nominal conversion and corrected with the calibration.
  double gravity_error_nominal = 0.0, gravity_error_calibrated = 0.0;
  double rate_nominal = 0.0, rate_calibrated = 0.0;
};
struct ValidationTurn {
  int from = 0;  // the pose the turn starts from (to the next)
  /// rad: angle between the gravity direction seen in the next pose and the one the integrated
  /// gyro rates predict from this pose's, nominal and calibrated; the turn's angle (calibrated).
  double error_nominal = 0.0, error_calibrated = 0.0, angle = 0.0;
};
struct HandheldValidation {
  std::string session;  // session.ini
  std::string name;
  std::size_t samples = 0;
  double duration = 0.0;  // s
  std::vector<ValidationPose> poses;
  std::vector<ValidationTurn> turns;
  /// RMS over the poses (turns) of the figures above.
  double gravity_rms_nominal = 0.0, gravity_rms_calibrated = 0.0;  // m/s^2
  double rate_rms_nominal = 0.0, rate_rms_calibrated = 0.0;        // rad/s
  double turn_rms_nominal = 0.0, turn_rms_calibrated = 0.0;        // rad
};

struct TableFreeRun {
  std::string session;  // session.ini
  std::string name;
  std::string log;  // the log's description
  std::size_t samples = 0;
  double duration = 0.0;     // s, first to last sample
  std::string gravity_from;  // "given" | "session" | "normal gravity at the site"
  bool has_site = false;
  Site site;
  TableFreeOptions options;  // as run (gravity, site)
  PoseDetectorOptions detector;
  PoseDetection detection;  // in counts for raw() logs, else SI
  std::vector<HandheldPose> poses;
  bool accel_counts = false, gyro_counts = false;
  RawScaling nominal;
  std::array<int, 3> accel_log_axis{0, 1, 2}, gyro_log_axis{0, 1, 2};
  TableFreeResult result;
  /// The readings the calibration took (SI through the log's nominal conversion; the result is
  /// relative to it): the input of the hand-held diagnosis.
  std::vector<ImuReading> readings;
  std::vector<HandheldValidation> validations;
};

/// Table-free calibration of a session (with or without a plan; the plan is not used). Throws
/// TableFreeError for too few or too short poses and a failed solution, ConfigError when
/// neither a gravity nor a site is known.
TableFreeRun run_table_free(const Session& session, const TableFreeRunOptions& options);

/// A validation record corrected with `run`'s calibration: its poses (found with `detector`)
/// and the turns between them, nominal against calibrated. The record's triads must be logged
/// as the calibration's were (raw counts or not); counts are converted with each log's own
/// nominal conversion. Throws std::invalid_argument when they differ, PoseDetectorError when
/// the record has no pose.
HandheldValidation validate_table_free(const Session& validation, const TableFreeRun& run,
                                       const PoseDetectorOptions& detector);

/// A record read once for the Allan deviation in bounded memory: `readings` (SI) are the means
/// of `block` consecutive samples each (1 up to kAllanBlockReadings samples, doubled as the
/// record grows beyond), for the pose detector and the plausibility gate; `samples` is empty.
struct AllanRecord : HandheldRecord {
  std::size_t count = 0;               // samples read
  std::size_t block = 1;               // samples per reading
  double t_first = 0.0, t_last = 0.0;  // s, of the first and last sample
};

/// Most block means an AllanRecord holds (then pairs are merged and the block doubles).
constexpr std::size_t kAllanBlockReadings = std::size_t{1} << 19;

/// Which part of a record the Allan deviation takes.
enum class AllanSelection { All, LongestPose, Pose };

struct AllanRunOptions {
  AllanSelection selection = AllanSelection::All;
  int pose = 0;  // AllanSelection::Pose: 1-based
  /// AllanSelection::All: a record that is not static (see AllanRun::warning) is an error
  /// (std::invalid_argument) instead of a warning.
  bool require_static = false;
  PoseDetectorOptions detector;
  AllanOptions allan;
  /// Called with the record and the readings (rates, SI; block means, AllanRecord) of the
  /// stretch selected before the analysis: a plausibility gate that throws stops it.
  std::function<void(const AllanRecord&, const std::vector<ImuReading>&)> before_analysis;
};

struct AllanRun {
  std::string session, name, log;
  AllanSelection selection = AllanSelection::All;
  int pose = 0;                       // the pose analysed (0: the whole record)
  int poses_found = 0;                // by the detector (-1: it found none)
  double static_fraction = 0.0;       // of the record in its longest detected pose
  double t_start = 0.0, t_end = 0.0;  // s, the stretch analysed
  std::size_t block = 1;              // samples per reading of the pose detector and the gate
  std::size_t passes = 1;             // over the log: 1 (whole record), 2 (a pose)
  std::size_t memory_bytes = 0;       // held by the Allan estimators
  AllanAnalysis analysis;
  /// Not empty when the whole record was taken but is not static (its longest detected pose
  /// covers less than 90 % of it): says so and how to take one pose.
  std::string warning;
};

/// Allan deviation of a session's static record or one of its poses, streamed: the log is read
/// once (the whole record) or twice (a pose: found on the block means, then analysed at the
/// full rate) in memory independent of its length. Throws PoseDetectorError
/// (no pose), std::invalid_argument (no such pose; a record that is not static, or too short for
/// the detector to tell, with `require_static`), AllanError (too short, naming the log). A log of
/// rates is taken at the median sample interval of the stretch's first 2^20 intervals
/// (time-stamp jitter is the logger's, not the sensor's).
AllanRun run_allan(const Session& session, const AllanRunOptions& options);

}  // namespace sinscal
