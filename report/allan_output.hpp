// Outputs of `sinscal allan` (docs/formats.md, "Allan deviation"): the deviations per axis as CSV,
// the fitted noise model as a sensor-profile fragment, and a PNG of measured against fitted
// (gnuplot, the script kept beside it).
#pragma once

#include <string>

#include "filter/noise/allan.hpp"

namespace sinscal {

/// CSV: `tau [s]`, then per axis (gyro x y z in deg/h, accel x y z in ug) the Allan deviation,
/// its lower and upper confidence bound and the fitted model's value. Written atomically.
void write_allan_csv(const std::string& path, const AllanAnalysis& analysis);

/// The gnuplot script drawing `analysis` into the variable `output` (default `png_path`): gyros
/// and accelerometers side by side, log-log, measured with bounds and the fitted model dashed.
std::string allan_plot_script(const AllanAnalysis& analysis, const std::string& title,
                              const std::string& png_path);

/// Writes the script to `script_path` and runs gnuplot (report/gnuplot.hpp). Throws
/// std::runtime_error when gnuplot cannot be run or fails.
void plot_allan(const AllanAnalysis& analysis, const std::string& title,
                const std::string& png_path, const std::string& script_path,
                const std::string& gnuplot = "gnuplot");

}  // namespace sinscal
