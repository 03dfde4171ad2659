#include "report/output.hpp"

#include <fcntl.h>  // AT_FDCWD
#include <unistd.h>

#include <algorithm>
#include <cstdio>  // renameat2, RENAME_EXCHANGE (glibc 2.28)
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

namespace {

std::vector<std::string> marker_list(const fs::path& marker) {
  std::vector<std::string> names;
  std::ifstream in(marker);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) names.push_back(line);
  return names;
}

fs::path plain(const std::string& dir) {
  fs::path p = fs::absolute(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p;
}

// Puts the finished temporary `tmp` in the place of `target` per its state.
void put_in_place(const fs::path& tmp, const fs::path& target, DirectoryState state, bool merge) {
  std::error_code ec;
  if (state == DirectoryState::Absent || state == DirectoryState::Empty) {
    fs::rename(tmp, target, ec);
    if (ec) throw std::runtime_error(target.string() + ": cannot create: " + ec.message());
  } else if (state == DirectoryState::EarlierOutput) {
    if (::renameat2(AT_FDCWD, tmp.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) != 0) {
      // No exchange on this file system: the old one moved aside, the new one in, at once.
      fs::path old = target;
      old += ".sinscal-old-" + std::to_string(::getpid());
      fs::rename(target, old, ec);
      if (!ec) fs::rename(tmp, target, ec);
      if (ec) throw std::runtime_error(target.string() + ": cannot replace: " + ec.message());
      fs::remove_all(old, ec);
      return;
    }
    fs::remove_all(tmp, ec);  // the exchange left the old directory there
  } else if (merge) {
    for (const auto& e : fs::directory_iterator(tmp)) {
      fs::rename(e.path(), target / e.path().filename(), ec);
      if (ec)
        throw std::runtime_error((target / e.path().filename()).string() +
                                 ": cannot write: " + ec.message());
    }
    fs::remove_all(tmp, ec);
  } else {
    throw std::runtime_error(target.string() + ": not empty and not an earlier output");
  }
}

}  // namespace

DirectoryState directory_state(const std::string& dir, const std::string& marker,
                               std::vector<std::string>& foreign) {
  foreign.clear();
  const fs::path p = plain(dir);
  std::error_code ec;
  if (!fs::exists(p, ec)) return DirectoryState::Absent;
  if (!fs::is_directory(p, ec)) {
    foreign.push_back(p.filename().string());
    return DirectoryState::Foreign;
  }
  const bool has_marker = fs::is_regular_file(p / marker, ec);
  const std::vector<std::string> listed =
      has_marker ? marker_list(p / marker) : std::vector<std::string>{};
  bool empty = true;
  for (const auto& e : fs::directory_iterator(p)) {
    empty = false;
    const std::string name = e.path().filename().string();
    if (name == marker) continue;
    // The earlier output's own files and folders (a chamber's soak-K) are listed in its marker.
    const bool own = (e.is_regular_file() || e.is_directory()) &&
                     std::find(listed.begin(), listed.end(), name) != listed.end();
    if (!own) foreign.push_back(name);
  }
  std::sort(foreign.begin(), foreign.end());
  if (empty) return DirectoryState::Empty;
  return has_marker && foreign.empty() ? DirectoryState::EarlierOutput : DirectoryState::Foreign;
}

void write_directory_whole(const std::string& dir, const std::string& marker,
                           const std::function<void(const std::string&)>& build, bool merge) {
  std::vector<std::string> foreign;
  const DirectoryState state = directory_state(dir, marker, foreign);
  const fs::path target = plain(dir);
  fs::path tmp = target;
  tmp += ".sinscal-tmp-" + std::to_string(::getpid());
  std::error_code ec;
  fs::create_directories(target.parent_path(), ec);
  fs::remove_all(tmp, ec);
  if (!fs::create_directory(tmp, ec) || ec)
    throw std::runtime_error(tmp.string() + ": cannot create: " + ec.message());
  try {
    build(tmp.string());
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(tmp)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    write_atomically((tmp / marker).string(), [&](std::ostream& out) {
      for (const auto& n : names) out << n << "\n";
    });
    put_in_place(tmp, target, state, merge);
  } catch (...) {
    fs::remove_all(tmp, ec);
    throw;
  }
}

}  // namespace sinscal
