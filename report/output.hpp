// Output files that never destroy inputs: every file is written to a temporary name beside it
// and renamed when complete (a crash or an error leaves the previous file, never a truncated
// one), and a run refuses an output path that is one of its inputs or another of its outputs.
#pragma once

#include <fstream>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace sinscal {

/// Writes `path` through `write` into a temporary file in the same directory, then renames it
/// over `path`. Throws std::runtime_error naming the file when it cannot be written; the
/// temporary file is removed and `path` left as it was. When `write` throws, the exception
/// propagates after the temporary file is removed, or, with `keep_partial`, renamed over `path`
/// (a file of rows written as they are computed keeps the rows before the error).
void write_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                      bool keep_partial = false);

/// Registers files this run reads (role, path): from then on write_atomically,
/// open_append_log and write_directory_whole refuse (std::invalid_argument naming both) to write
/// over any of them, or a directory holding one, resolved through links. check_outputs
/// registers its inputs, so a command that checks its outputs protects its inputs everywhere.
void protect_inputs(const std::vector<std::pair<std::string, std::string>>& inputs);
/// Throws std::invalid_argument when `path` is (or, for a directory, holds) a protected input.
void refuse_protected(const std::string& what, const std::string& path, bool directory = false);
/// Throws std::runtime_error naming the real cause when a file cannot be created at `path`: its
/// directory missing, not a directory, or not writable (permission denied, read-only).
void check_writable(const std::string& path);

/// Opens `path` for a log written line by line (a monitor): created or truncated, every line the
/// caller writes is flushed to the file at once, so a process killed (SIGKILL) leaves every
/// complete line before the kill. Throws std::runtime_error with the real cause.
std::ofstream open_append_log(const std::string& path);

/// Throws std::invalid_argument naming both when an output is (resolves to the same file as) an
/// input or another output. Paths that do not exist yet are compared by their absolute,
/// normalized form.
void check_outputs(const std::vector<std::pair<std::string, std::string>>& inputs,
                   const std::vector<std::pair<std::string, std::string>>& outputs);

/// A directory an earlier run wrote holds a marker file listing the files it wrote.
enum class DirectoryState {
  Absent,         // no such path
  Empty,          // an empty directory
  EarlierOutput,  // the marker, and nothing the marker does not list
  Foreign,        // anything else (a file, or a directory with other entries)
};

/// `dir`'s state against `marker` (a file name); `foreign` receives the names of its entries the
/// marker does not list (all of them without a marker).
DirectoryState directory_state(const std::string& dir, const std::string& marker,
                               std::vector<std::string>& foreign);

/// Writes a directory whole, never half: `build` fills a new temporary sibling of `dir` (its path
/// given), `marker` is written there listing its files, then it takes `dir`'s place: renamed to
/// it when `dir` is absent or an empty directory, exchanged with it in one step (Linux
/// renameat2) when `dir` is an earlier output (the old one then removed), or, with `merge` (a
/// foreign directory the user told to write into), its files renamed into `dir` one by one, the
/// other entries of `dir` kept. On any failure the temporary is removed and `dir` left as it
/// was. Throws std::runtime_error naming the path; whatever `build` throws propagates.
void write_directory_whole(const std::string& dir, const std::string& marker,
                           const std::function<void(const std::string&)>& build, bool merge);

}  // namespace sinscal
