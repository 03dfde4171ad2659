// Running gnuplot safely: user text (file names, labels) reaches a script without control
// characters, the script is written beside the picture, and gnuplot draws to a temporary PNG
// renamed over the target only when it succeeded.
#pragma once

#include <sys/types.h>

#include <string>

namespace sinscal {

/// Text as gnuplot may see it: control characters (a newline would end a comment or a string and
/// start a command) shown as '?'.
std::string gnuplot_printable(const std::string& s);
/// A gnuplot single-quoted string of `s` (printable, quotes doubled).
std::string gnuplot_quoted(const std::string& s);
/// A number for inline data ("?" for NaN, gnuplot's missing value with `set datafile missing`).
std::string gnuplot_number(double v);

/// The script's path beside a PNG: conv.png -> conv.gp.
std::string gnuplot_script_path(const std::string& png_path);

/// Runs `program` on `script_path` with the variable `output` set to a temporary PNG, then
/// renames that over `png_path` (the script must draw to `output`). Throws std::runtime_error if
/// Waits for a spawned program (`what` names it in errors; EINTR retried), reads its message
/// log into `messages` and removes the log; returns waitpid's status word.
int wait_for_program(pid_t pid, const std::string& what, const std::string& log,
                     std::string& messages);
/// gnuplot cannot be run (naming the Debian package gnuplot-nox) or fails (with its messages).
void run_gnuplot(const std::string& program, const std::string& script_path,
                 const std::string& png_path);

}  // namespace sinscal
