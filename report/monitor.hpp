// Convergence monitor records (the JSON lines of `calibrate --method kf --monitor`, see
// docs/formats.md) read back, and drawn to PNG with gnuplot: estimate and sigma over time per
// coefficient family.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "filter/kalman/kalman_run.hpp"
#include "report/result.hpp"

namespace sinscal {

/// A monitor file as time series. Values and sigmas in the coefficients' units (the result
/// files'); a coefficient missing from a record (fixed by convention) is NaN there.
struct MonitorSeries {
  std::string path;
  std::vector<double> t;            // s, log time of each record
  std::vector<double> nis_per_dof;  // running NIS per degree of freedom
  std::vector<bool> converged;
  std::string body_frame;                  // "table" | "accelerometer triad" | "" (unknown)
  std::vector<std::string> names;          // coefficients, catalog order
  std::vector<std::vector<double>> value;  // [coefficient][record]
  std::vector<std::vector<double>> sigma;  // [coefficient][record]
  /// The last line had no newline and was not a record: cut by a kill of the process writing
  /// it (a complete last line without a newline is a record); that line is skipped.
  bool cut_last_line = false;
};

/// One monitor record as a JSON line (docs/formats.md): t, NIS per dof, converged, body frame,
/// every estimated coefficient's [value, sigma] in its unit.
std::string monitor_line(const MonitorRecord& record);

/// Reads a monitor file; throws std::runtime_error naming file and line on a malformed record,
/// an unknown coefficient or time going backwards. A last line without a newline that is not
/// valid JSON is a line cut by a crash: skipped (cut_last_line), the records before it kept.
MonitorSeries read_monitor(const std::string& path);

struct ConvergencePlotOptions {
  std::vector<std::string> families;  // families to draw (empty: every family in the monitor)
  std::map<std::string, double> sigma_targets;  // by family, SI (SensorProfile::sigma_targets)
  ResultCoefficients truth;  // drawn as dashed lines over the estimates when given
  int width_px = 1400;
  int row_height_px = 260;
  std::string gnuplot = "gnuplot";  // program run (found on PATH)
};

/// What plot_convergence wrote.
struct ConvergencePlot {
  std::string png;     // the picture
  std::string script;  // the gnuplot script beside it (PNG path with .gp), data inline
  std::vector<std::string> families;
  int width_px = 0, height_px = 0;
};

/// The gnuplot script drawing `series` into `png_path`: a row per family (estimates on the
/// left, sigmas on a log scale on the right, with the target), NIS per dof on top.
std::string convergence_plot_script(const MonitorSeries& series,
                                    const ConvergencePlotOptions& options,
                                    const std::string& png_path, ConvergencePlot* layout = nullptr);

/// The gnuplot script's path beside a PNG: conv.png -> conv.gp.
std::string convergence_script_path(const std::string& png_path);

/// Writes the script beside `png_path` and runs gnuplot on it. Throws std::runtime_error if
/// gnuplot cannot be run (naming the Debian package) or fails (with the script's path).
ConvergencePlot plot_convergence(const MonitorSeries& series, const ConvergencePlotOptions& options,
                                 const std::string& png_path);

}  // namespace sinscal
