// Drawing with gnuplot (Debian gnuplot-nox, run as a program): scripts beside their PNGs, text
// from file names made safe for gnuplot's strings.
#pragma once

#include <string>

namespace sinscal {

/// A gnuplot single-quoted string of `s`, control characters replaced by '?' (a newline in a
/// file name must not end a script line).
std::string gnuplot_quoted(const std::string& s);

/// The script's path beside a PNG: conv.png -> conv.gp.
std::string gnuplot_script_path(const std::string& png_path);

/// Runs `gnuplot` on `script_path` with `output` set to a temporary file renamed over `png_path`
/// when it succeeds. Throws std::runtime_error if gnuplot cannot be run (naming the Debian
/// package) or fails (with its messages and the script's path).
void run_gnuplot(const std::string& script_path, const std::string& png_path,
                 const std::string& gnuplot = "gnuplot");

}  // namespace sinscal
