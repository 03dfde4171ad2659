// Helpers shared by the libFuzzer targets of this folder (no project headers, so a target's own
// includes are all it needs).
#pragma once

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

namespace sinscal::fuzz {

/// The fuzz input as a string.
inline std::string text_of(const std::uint8_t* data, std::size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// A directory for this process's files (fuzzers may run several processes at once); created on
/// first use, removed at exit.
inline const std::string& work_dir() {
  static const std::string dir = [] {
    const auto d = std::filesystem::temp_directory_path() /
                   ("sinscal_fuzz_" + std::to_string(static_cast<long>(::getpid())));
    std::filesystem::create_directories(d);
    static const std::string keep = d.string();
    std::atexit([] {
      std::error_code ec;
      std::filesystem::remove_all(keep, ec);
    });
    return d.string();
  }();
  return dir;
}

/// Writes `text` to `path`; aborts if it cannot (a broken harness, not a finding in the code).
inline void write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) {
    std::fprintf(stderr, "fuzz harness: cannot write %s\n", path.c_str());
    std::abort();
  }
}

/// A finding that is not a crash: an exception of the wrong type, or a message that does not name
/// the file. Printed, then abort() so that libFuzzer saves the input.
[[noreturn]] inline void finding(const char* what, const std::string& detail) {
  std::fprintf(stderr, "FINDING: %s: %s\n", what, detail.c_str());
  std::abort();
}

/// An expected error must name the input: its message starts with `name`.
inline void check_message(const std::exception& e, const std::string& name) {
  const std::string m = e.what();
  if (m.compare(0, name.size(), name) != 0)
    finding("error message does not start with the file name", m);
}

}  // namespace sinscal::fuzz
