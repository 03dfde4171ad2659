// Sessions: a directory with the IMU log (imu.csv), its description (session.ini: site, rate,
// plan, log format) and, for simulations, the injected truth (truth.json). docs/formats.md.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "models/earth.hpp"
#include "models/imu_error_model.hpp"
#include "models/sensor_profile.hpp"
#include "rig/log_io.hpp"
#include "rig/plan.hpp"

namespace sinscal {

struct Session {
  std::string path;  // session.ini
  std::string dir;   // its directory
  std::string name;
  Site site;
  double rate_hz = 0.0;
  double time_offset = 0.0;  // s: log time at which the plan starts
  Plan plan;
  LogFormat log;
  std::string truth_file;   // empty if none
  std::string sensor_file;  // empty if none

  static Session load(const std::string& path);
};

/// A simulated session to write: the plan on its site, true coefficients drawn from a sensor
/// profile, that profile's noise. All random draws derive from `seed` (derive_seed(seed, 1):
/// coefficients, 2: noise); the table errors carry their own seed.
struct SessionSimulation {
  std::string plan_path;           // plan INI; needs a [site]
  std::string data_sensor_path;    // profile the truth and the noise are drawn from
  std::string filter_sensor_path;  // copied as the session's sensor.ini (empty: data_sensor_path)
  std::string name;                // session name (empty: the plan's name)
  double rate_hz = 100.0;
  std::uint64_t seed = 1;
  bool noise = true;          // false: no sensor noise (coefficients still drawn)
  bool perfect = false;       // no sensor errors at all
  bool table_angles = false;  // the log gets the table's axis-angle columns
  TableErrors table;
};

struct SimulatedSession {
  std::string session_path;  // DIR/session.ini
  ImuErrorModel truth;
  std::size_t samples = 0;
  std::size_t saturated = 0;  // samples clipped at the sensor range
  std::size_t dwells = 0;
  double duration = 0.0;  // s, of the motion
  Plan plan;
  SensorProfile profile;  // the data profile
};

/// Writes a simulated session into `out_dir` (created): imu.csv (streamed, constant memory),
/// plan.ini, sensor.ini, truth.json, session.ini. Throws naming the file on any failure.
SimulatedSession simulate_session(const std::string& out_dir, const SessionSimulation& spec);

/// One coefficient of a result file.
struct ResultCoefficient {
  double value = 0.0;
  std::optional<double> sigma;  // absent: not estimated (truth files)
  std::string unit;
  bool observable = true;            // false: the data cannot determine it; no value is given
  bool fixed_by_convention = false;  // zero by the body-frame convention, not estimated
};

/// Result / truth JSON: {"coefficients": {"gyro.bias.x": {"value": .., "sigma": .., "unit": ..}}}.
using ResultCoefficients = std::map<std::string, ResultCoefficient>;

/// Writes the coefficients of a model (engineering units) as a truth file.
void write_truth_json(const std::string& path, const ImuErrorModel& model,
                      const std::string& note = "");
/// Writes a result file; `extra` (an object) adds sections after "coefficients".
void write_result_json(const std::string& path, const ResultCoefficients& coefficients,
                       const nlohmann::ordered_json& extra = nlohmann::ordered_json::object());
/// Reads a result or truth file; throws std::runtime_error naming the file on a bad file.
ResultCoefficients read_result_json(const std::string& path);

/// The session's truth (simulations), empty when it has none. With `accel_triad_frame` the truth
/// is converted to the body frame of the accelerometer triad, as results without table attitude
/// are (docs/conventions.md).
ResultCoefficients load_truth(const Session& session, bool accel_triad_frame = false);
/// Largest |estimate - truth| / sigma over the estimated coefficients (none: nullopt).
std::optional<double> max_error_over_sigma(const ResultCoefficients& result,
                                           const ResultCoefficients& truth);

/// The session.ini files a path names: the file itself; a directory holding session.ini; or a
/// directory whose subdirectories hold session.ini (sorted by name). Throws naming the path if it
/// names none.
std::vector<std::string> find_sessions(const std::string& path);
/// A list file: one path per line (session.ini or a directory, as find_sessions; relative to the
/// list's directory), '#' comments and blank lines ignored. Throws naming file and line.
std::vector<std::string> read_session_list(const std::string& list_path);

/// One coefficient of two results side by side.
struct CoefficientComparison {
  std::string name, unit;
  std::optional<double> a, b;              // absent: not in that file, or not observable there
  std::optional<double> sigma_a, sigma_b;  //
  std::optional<double> z;                 // (a - b) / hypot(sigma_a, sigma_b), both estimated
  std::optional<double> relative;          // |a - b| / max(|a|, |b|) (0 when both are 0)
  std::optional<double> sigma_relative;    // the same for the sigmas
};
/// Every coefficient either result has, in catalog order.
std::vector<CoefficientComparison> compare_results(const ResultCoefficients& a,
                                                   const ResultCoefficients& b);

/// One row of a batch run's summary table.
struct SessionSummary {
  std::string session;  // session.ini
  std::string name;     // the session's name
  std::string result;   // result file written; empty if none
  std::string status;   // ok | stopped (bad input) | diverged | failed (no result)
  std::string message;  // why, when not ok
  std::size_t samples = 0;
  double duration = 0.0;  // s of data
  std::optional<double> nis_per_dof;
  std::optional<double> converged_at;          // s (Kalman filter with sigma targets)
  std::optional<double> max_error_over_sigma;  // sessions with truth
  ResultCoefficients coefficients;
};
/// The summary table as CSV (docs/formats.md): a row per session, the coefficients' values and
/// sigmas in the result files' units.
void write_summary_csv(const std::string& path, const std::vector<SessionSummary>& rows);

}  // namespace sinscal
