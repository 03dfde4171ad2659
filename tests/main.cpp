// The test runner: Catch2's, with skipped tests reported as such (tests/skip.hpp).
#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "skip.hpp"

int main(int argc, char* argv[]) {
  const int failed = Catch::Session().run(argc, argv);
  // Catch2 returns the number of failed assertions (at most 255): a failure never reads as a skip.
  if (failed != 0) return failed == sinscal::test::kSkipExitCode ? failed + 1 : failed;
  return sinscal::test::skip_count() > 0 ? sinscal::test::kSkipExitCode : 0;
}
