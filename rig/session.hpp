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
#include "rig/ferraris.hpp"
#include "rig/io/log_io.hpp"
#include "rig/plan.hpp"
#include "rig/thermal.hpp"

namespace sinscal {

/// [table_free]: the hand-held method's options a session carries (`calibrate --method
/// table-free`, `diagnose` and `allan` on it); each given on the command line overrides it.
struct TableFreeSettings {
  std::optional<double> pose_window, min_pose, edge_trim;  // s
  std::optional<bool> pose_accel_only;  // the accelerometers alone find the poses
};

struct Session {
  /// Whether a session must have a plan. Every table method needs one; a hand-held session
  /// (`calibrate --method table-free`, `allan`) finds its poses in the data and needs none.
  enum class PlanNeed { Required, Optional };

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
  bool has_plan = true;     // false: no [session] plan (loaded with PlanNeed::Optional)
  bool has_site = true;     // false: no site in the session or its plan (PlanNeed::Optional)
  double gravity = 0.0;     // m/s^2: [site] gravity, the local gravity magnitude (0: not given)
  /// [six_face]: the session is a six-face and known-turn procedure (its parts labelled in the
  /// log's label column).
  std::optional<FerrarisDeclaration> six_face;
  TableFreeSettings table_free;  // [table_free] (every key optional)

  /// Throws ConfigError naming the file, line and key. With PlanNeed::Required (the table
  /// methods) the plan and a site are required and [site] gravity is refused (they use the
  /// WGS-84 gravity model); with PlanNeed::Optional both may be absent and [site] may hold only
  /// `gravity`.
  static Session load(const std::string& path, PlanNeed plan = PlanNeed::Required);
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
  /// In a chamber (null: none): the sensor's temperature over the session's time (0 s: the plan
  /// starts); the log gets the temperature columns. Not owned.
  const SensorTemperature* temperature = nullptr;
  int plan_repeat = 1;             // the plan runs this many times in a row (a chamber ramp)
  std::uint64_t noise_stream = 0;  // another noise draw of the same unit (a chamber's soaks)
  std::string note;                // a comment line for session.ini (empty: none)
};

struct SimulatedSession {
  std::string session_path;  // DIR/session.ini
  ImuErrorModel truth;       // relative to the platform: the mounting included (in_platform_frame)
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

/// A chamber's sessions (simulate --chamber): soaks, one session per soak in out_dir/soak-K/ and
/// out_dir/chamber.ini listing them ([thermal] soaks); a ramp, one session in out_dir with the
/// plan repeated over the ramp. The unit (coefficients) is the same in every soak; each soak has
/// its own noise. The sensor lags the air by the data profile's [thermal] time_constant.
struct ChamberSimulation {
  std::string path;  // chamber.ini (soaks) or session.ini (ramp)
  std::vector<SimulatedSession> sessions;
  std::vector<double> soak_c;  // the air of each soak (deg C)
};
ChamberSimulation simulate_chamber(const std::string& out_dir, const SessionSimulation& spec,
                                   const ChamberProgram& chamber);

/// Writes the coefficients of a model (engineering units) as a truth file (the result-file
/// schema without sigmas, docs/formats.md); with `table`, its base and mounting errors as
/// "installation" (the coefficients are then relative to the platform, mounting included).
void write_truth_json(const std::string& path, const ImuErrorModel& model,
                      const std::string& note = "", const TableErrors* table = nullptr);

}  // namespace sinscal
