#include "report/output.hpp"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace sinscal {

namespace fs = std::filesystem;

void write_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                      bool keep_partial) {
  const fs::path target(path);
  fs::path temp = target;
  temp += ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temp);
    if (!out) throw std::runtime_error(path + ": cannot create (its directory must exist)");
    try {
      write(out);
    } catch (...) {
      out.close();
      std::error_code ignored;
      if (keep_partial)
        fs::rename(temp, target, ignored);
      else
        fs::remove(temp, ignored);
      throw;
    }
    out.close();
    if (!out) {
      std::error_code ignored;
      fs::remove(temp, ignored);
      throw std::runtime_error(path + ": write failed");
    }
  }
  std::error_code ec;
  fs::rename(temp, target, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(temp, ignored);
    throw std::runtime_error(path + ": cannot replace: " + ec.message());
  }
}

namespace {
// The file a path names: its canonical form when it exists, else the normalized absolute path.
fs::path identity(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? fs::absolute(path).lexically_normal() : p;
}
}  // namespace

void check_outputs(const std::vector<std::pair<std::string, std::string>>& inputs,
                   const std::vector<std::pair<std::string, std::string>>& outputs) {
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    const auto& [what, path] = outputs[i];
    if (path.empty()) continue;
    const fs::path out = identity(path);
    for (const auto& [input_what, input] : inputs)
      if (!input.empty() && identity(input) == out)
        throw std::invalid_argument(what + " " + path + " is the " + input_what +
                                    ": an output never replaces an input");
    for (std::size_t j = 0; j < i; ++j)
      if (!outputs[j].second.empty() && identity(outputs[j].second) == out)
        throw std::invalid_argument(what + " " + path + " is also the " + outputs[j].first +
                                    ": two outputs of one run cannot share a file");
  }
}

}  // namespace sinscal
