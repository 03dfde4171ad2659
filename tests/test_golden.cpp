// Golden-output regression of the command line: a bundled case through `sinscal simulate` and
// `sinscal calibrate`, its result file compared with the committed one. A change of any estimate
// by more than 1e-3 of its sigma (or of a sigma by 1e-6 relative, or of observability) fails.
// After an intended change, regenerate with SINSCAL_UPDATE_GOLDEN=1 and explain it in the commit.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>

#include "helpers.hpp"
#include "report/result.hpp"

using namespace sinscal;

namespace {
int run(const std::string& command) { return std::system((command + " > /dev/null").c_str()); }
}  // namespace

TEST_CASE("Golden: seed8 closed-form calibration result", "[golden][cli]") {
  const std::string bin = SINSCAL_BINARY;
  const std::string dir = test::temp_dir("golden_seed8");
  REQUIRE(run(bin + " simulate --plan " + test::source_path("config/plans/seed8.ini") +
              " --sensor " + test::source_path("config/sensors/nav-fog.ini") + " --out " + dir +
              " --seed 1 --table-angle-sigma 2.5") == 0);
  REQUIRE(run(bin + " calibrate --session " + dir + "/session.ini --method closed-form --out " +
              dir + "/result.json") == 0);
  const std::string golden = test::source_path("tests/golden/seed8-closed-form.json");
  if (std::getenv("SINSCAL_UPDATE_GOLDEN")) {
    std::filesystem::copy_file(dir + "/result.json", golden,
                               std::filesystem::copy_options::overwrite_existing);
    WARN("golden file rewritten: " << golden);
  }
  const ResultCoefficients want = read_result_json(golden),
                           got = read_result_json(dir + "/result.json");
  REQUIRE(got.size() == want.size());
  for (const auto& [name, w] : want) {
    CAPTURE(name);
    REQUIRE(got.count(name) == 1);
    const ResultCoefficient& g = got.at(name);
    CHECK(g.observable == w.observable);
    CHECK(g.unit == w.unit);
    if (!w.observable) continue;
    CHECK(std::abs(g.value - w.value) <= 1e-3 * *w.sigma);
    CHECK(std::abs(*g.sigma - *w.sigma) <= 1e-6 * *w.sigma);
  }
}
