#pragma once
// Skipped tests for Catch2 2.x (Debian 12 has 2.13, which has no SKIP; Catch2 3.3 does): a test
// that cannot run for want of an optional program calls test::skip(reason) and returns. The
// process then exits with kSkipExitCode unless an assertion failed (tests/main.cpp), and ctest,
// which runs each test case in its own process, reports the test as skipped (SKIP_RETURN_CODE in
// tests/CMakeLists.txt). Never for data: the recordings the tests read are in data/.

#include <catch2/catch.hpp>
#include <string>

namespace sinscal::test {

/// The exit code of a test process whose test case was skipped (Automake's convention).
constexpr int kSkipExitCode = 77;

/// How many skips this process has recorded.
inline int& skip_count() {
  static int count = 0;
  return count;
}

/// Records the current test case as skipped, with the reason in the output; the caller returns.
inline void skip(const std::string& reason) {
  WARN("SKIPPED: " << reason);
  ++skip_count();
}

}  // namespace sinscal::test
