// A chamber's soaks calibrated one by one (filter/thermal/soak_fit.hpp fits them against
// temperature): the chamber file listing the soaks' sessions (docs/formats.md "Chamber
// sessions"), each soak's Kalman-filter calibration at its temperature, and the checks that a
// soak is one temperature.
// docs/methods/thermal.md "From soaks".
#pragma once

#include <stdexcept>
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
  /// Families (not thermal) each soak's filter adds to its sensor profile's model: what a
  /// chamber diagnosis found on one soak (they act at every temperature; a soak calibrated
  /// without them absorbs them into its coefficients, differently at each temperature).
  std::vector<std::string> extra_families;
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

/// Throws LogError (naming the line) when a soak's temperature `T` moves by more than the
/// chamber's tolerance: the soak had not settled.
void check_soak_settled(const SoakTemperature& T, const ChamberSoaks& chamber);

/// A soak's calibration that the filter itself stopped (diverging, or a stop of its run): the
/// soak's data do not follow the filter's model at that temperature. Input errors are other
/// exceptions.
class SoakStopped : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Calibrates one soak by the Kalman filter with its session's sensor profile: the thermal
/// families are left out (a soak is one temperature: the fit finds them), and each coefficient's
/// prior widened by its thermal families' ranges at the soak's temperature (the coefficient
/// there may lie that far from its value at T0). Throws LogError when the soak's temperature
/// moves by more than the tolerance (a soak shorter than its settling time), or the log has no
/// temperature; SoakStopped when the filter stops or diverges.
SoakRun calibrate_soak(const std::string& session_path, const ChamberSoaks& chamber,
                       const KalmanRunOptions& run = {});

/// A soak set aside: its index in the chamber (0-based), its session and the filter's cause.
struct SoakFailure {
  std::size_t index = 0;
  std::string session;
  std::string cause;
};

/// Every soak of a chamber calibrated; a soak whose filter stops (SoakStopped) is set aside with
/// its cause and the others go on (a diagnosis states it: one diverging soak must not hide what
/// the others show). Input errors still throw.
struct ChamberRuns {
  std::vector<SoakRun> runs;
  std::vector<std::size_t> index;  // each run's soak in the chamber (0-based)
  std::vector<SoakFailure> failed;
};
ChamberRuns calibrate_soaks_keep_going(const ChamberSoaks& chamber,
                                       const KalmanRunOptions& run = {});

/// The statement of a soak set aside: which soak, its cause, and that the fit has the others.
std::string soak_failure_stop(const SoakFailure& f, std::size_t soaks);

}  // namespace sinscal
