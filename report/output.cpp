#include "report/output.hpp"

#include <fcntl.h>  // AT_FDCWD
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>  // renameat2, RENAME_EXCHANGE (glibc 2.28)
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <stdexcept>
#include <system_error>

namespace sinscal {

namespace fs = std::filesystem;

namespace {
// The file a path names: its canonical form when it exists, else the normalized absolute path
// (links resolved in the part that exists).
fs::path identity(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? fs::absolute(path).lexically_normal() : p;
}

struct Protected {
  std::string what, path;
  fs::path id;
};
std::mutex g_protected_mutex;
std::vector<Protected>& protected_inputs() {
  static std::vector<Protected> inputs;
  return inputs;
}

// Whether `inner` is `outer` or lies below it.
bool within(const fs::path& inner, const fs::path& outer) {
  const fs::path rel = inner.lexically_relative(outer);
  return !rel.empty() && *rel.begin() != "..";
}
}  // namespace

void protect_inputs(const std::vector<std::pair<std::string, std::string>>& inputs) {
  const std::lock_guard<std::mutex> lock(g_protected_mutex);
  for (const auto& [what, path] : inputs)
    if (!path.empty() && path != "-" && path != "<stdin>")
      protected_inputs().push_back({what, path, identity(path)});
}

void refuse_protected(const std::string& what, const std::string& path, bool directory) {
  const fs::path out = identity(path);
  const std::lock_guard<std::mutex> lock(g_protected_mutex);
  for (const auto& in : protected_inputs()) {
    std::error_code ec;
    const bool same = in.id == out || fs::equivalent(in.path, path, ec);
    if (same || (directory && within(in.id, out)))
      throw std::invalid_argument(what + " " + path + (same ? " is the " : " holds the ") +
                                  in.what + " " + in.path + ": an output never replaces an input");
  }
}

void check_writable(const std::string& path) {
  fs::path dir = fs::path(path).parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw std::runtime_error(path + ": cannot create: it is a directory");
  if (!fs::exists(dir, ec))
    throw std::runtime_error(path + ": cannot create: its directory " + dir.string() +
                             " does not exist");
  if (!fs::is_directory(dir, ec))
    throw std::runtime_error(path + ": cannot create: " + dir.string() + " is not a directory");
  if (::access(dir.c_str(), W_OK | X_OK) != 0)
    throw std::runtime_error(path + ": cannot create: its directory " + dir.string() +
                             " is not writable (" + std::strerror(errno) + ")");
}

std::ofstream open_append_log(const std::string& path) {
  refuse_protected("the log", path);
  check_writable(path);
  std::ofstream out(path, std::ios::out | std::ios::trunc);
  if (!out) throw std::runtime_error(path + ": cannot create: " + std::strerror(errno));
  out << std::unitbuf;  // every write reaches the file at once: a kill loses no complete line
  return out;
}

void write_atomically(const std::string& path, const std::function<void(std::ostream&)>& write,
                      bool keep_partial) {
  refuse_protected("the output", path);
  const fs::path target(path);
  fs::path temp = target;
  temp += ".tmp-" + std::to_string(::getpid());
  {
    std::ofstream out(temp);
    if (!out) {
      const std::string cause = std::strerror(errno);
      check_writable(path);  // names the real cause: no directory, not writable
      throw std::runtime_error(path + ": cannot create: " + cause);
    }
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

void check_outputs(const std::vector<std::pair<std::string, std::string>>& inputs,
                   const std::vector<std::pair<std::string, std::string>>& outputs) {
  protect_inputs(inputs);
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
    for (const auto& e : fs::directory_iterator(tmp))
      refuse_protected("the output", (target / e.path().filename()).string(), true);
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
  // Every file below, by its path relative to the directory: an earlier output's own files
  // (a chamber's soak-K/imu.csv too) are listed in its marker; one it did not write is foreign.
  for (auto it = fs::recursive_directory_iterator(p); it != fs::recursive_directory_iterator();
       ++it) {
    empty = false;
    const std::string name = it->path().lexically_relative(p).generic_string();
    if (name == marker) continue;
    if (it->is_directory()) {  // own when it holds a listed file (an empty one is foreign)
      const std::string prefix = name + "/";
      if (std::none_of(listed.begin(), listed.end(), [&](const std::string& l) {
            return l.compare(0, prefix.size(), prefix) == 0;
          }))
        foreign.push_back(name + "/");
      continue;
    }
    const bool own =
        it->is_regular_file() && std::find(listed.begin(), listed.end(), name) != listed.end();
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
  // Replaced whole, it must hold no input; merged into, its files are renamed over one by one
  // (each checked below).
  refuse_protected("the output directory", target.string(), !merge);
  fs::path tmp = target;
  tmp += ".sinscal-tmp-" + std::to_string(::getpid());
  std::error_code ec;
  fs::create_directories(target.parent_path(), ec);
  fs::remove_all(tmp, ec);
  if (!fs::create_directory(tmp, ec) || ec)
    throw std::runtime_error(tmp.string() + ": cannot create: " + ec.message());
  try {
    build(tmp.string());
    std::vector<std::string> names;  // every file, relative path (docs/formats.md)
    for (const auto& e : fs::recursive_directory_iterator(tmp))
      if (!e.is_directory()) names.push_back(e.path().lexically_relative(tmp).generic_string());
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
