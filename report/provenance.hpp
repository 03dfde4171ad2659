// What a result file records of where it came from (docs/formats.md "provenance"): the sinscal
// version, the date, the command line and working directory, the session and its sensor profile,
// and every input file with its size and SHA-256, so that a certificate can name the data it
// certifies and tell whether the files are still the ones calibrated.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace sinscal {

/// The sinscal version this library was built as.
std::string sinscal_version();
/// The current time as ISO 8601 UTC, "2026-12-01T09:30:00Z".
std::string utc_timestamp();
/// A command line as a POSIX shell would take it back: each argument single-quoted when it holds
/// anything but letters, digits and -_./=:,+@%.
std::string shell_command_line(const std::vector<std::string>& argv);

struct ProvenanceInput {
  std::string command_line;  // shell_command_line of the run's argv
  std::string session;       // session.ini (empty: the run had none, e.g. thermal)
  std::string session_name;
  std::string sensor_profile;       // file (empty: none)
  std::string sensor_profile_name;  // its [sensor] name (empty: unknown)
  /// Input files (role, path), e.g. {"log", "s/imu.csv"}; an empty path is left out. Files whose
  /// role is "log" with `stdin_log` are recorded as read from standard input (no hash).
  std::vector<std::pair<std::string, std::string>> files;
  bool stdin_log = false;
  std::string monitor;  // the monitor file written beside the result (empty: none)
};

/// The result's "provenance" section. Every file is hashed (memory constant in its size); a file
/// that cannot be read throws std::runtime_error naming it.
nlohmann::ordered_json provenance_section(const ProvenanceInput& in);

}  // namespace sinscal
