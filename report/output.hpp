// Output files that never destroy inputs: every file is written to a temporary name beside it
// and renamed when complete (a crash or an error leaves the previous file, never a truncated
// one), and a run refuses an output path that is one of its inputs or another of its outputs.
#pragma once

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

/// Throws std::invalid_argument naming both when an output is (resolves to the same file as) an
/// input or another output. Paths that do not exist yet are compared by their absolute,
/// normalized form.
void check_outputs(const std::vector<std::pair<std::string, std::string>>& inputs,
                   const std::vector<std::pair<std::string, std::string>>& outputs);

}  // namespace sinscal
