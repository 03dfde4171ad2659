// Sessions: a directory with the IMU log (imu.csv), its description (session.ini: site, rate,
// plan, log format) and, for simulations, the injected truth (truth.json). docs/formats.md.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "models/earth.hpp"
#include "models/imu_error_model.hpp"
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

}  // namespace sinscal
