// A chamber's soaks calibrated one by one (filter/thermal/soak_fit.hpp fits them against
// temperature): the chamber file listing the soaks' sessions (docs/formats.md "Chamber
// sessions"), each soak's Kalman-filter calibration at its temperature, and the checks that a
// soak is one temperature.
// docs/methods/thermal.md "From soaks".
#pragma once

#include <string>
#include <vector>

#include "filter/kalman/kalman_run.hpp"
#include "filter/thermal/soak_fit.hpp"
#include "models/units.hpp"

namespace sinscal {

/// A chamber session file: `[thermal] soaks = DIR/session.ini, ...` (relative to the file),
/// `soak_tolerance` (deg C: how far a soak's temperature may move during its log).
struct ChamberSoaks {
  std::string path;
  std::vector<std::string> sessions;
  double tolerance_c = 1.0;
  /// The table's attitude error per dwell and axis the soaks' filters take (rad; `thermal
  /// --table-sigma`, docs/conventions.md).
  double table_sigma = 2.5 * units::arcsec;
  /// Throws ConfigError naming file, line and key.
  static ChamberSoaks load(const std::string& path);
  /// Whether a file is a chamber session (has [thermal] soaks).
  static bool is_chamber(const std::string& path);
};

struct SoakRun {
  Session session;
  KalmanRun run;
  SoakTemperature temperature;
  SoakEstimate estimate;
  double reference_temperature_c = 25.0;  // T0 of the soak's sensor profile
};

/// Calibrates one soak by the Kalman filter with its session's sensor profile: the thermal
/// families are left out (a soak is one temperature: the fit finds them), and each coefficient's
/// prior widened by its thermal families' ranges at the soak's temperature (the coefficient
/// there may lie that far from its value at T0). Throws LogError when the soak's temperature
/// moves by more than the tolerance (a soak shorter than its settling time), or the log has no
/// temperature.
SoakRun calibrate_soak(const std::string& session_path, const ChamberSoaks& chamber,
                       const KalmanRunOptions& run = {});

}  // namespace sinscal
