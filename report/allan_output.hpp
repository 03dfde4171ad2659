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

/// CSV of the fitted noise terms with their 1-sigma: `channel,term,value,sigma,unit`, a row per
/// channel (gyro.x ... accel.z) and term (quantum, arw / vrw, bias_instability, flicker,
/// rate_random_walk / random_walk, rate_ramp) in the profile's units; a term the fit left out has
/// value 0 and an empty sigma. Written atomically.
void write_allan_terms_csv(const std::string& path, const AllanAnalysis& analysis);

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
