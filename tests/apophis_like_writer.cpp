// Writes a generated session of the APOPHIS logs' structure (tests/apophis_like.hpp) for the
// bad-input corpus (tests/bad_input_test.sh): apophis_like_writer DIR rate-test | rate-test-short
// | z-turns | tumble | tumble-step | tumble-step-face | hand-tumble | hand-tumble-timed [SEED]
// (tumble-step: gyro y's level changes by -0.3 deg/s within the last z-up rest; -face: within the
// only x-down face) (Monte Carlos of the rate test and
// the tumble: docs/measured/apophis/README.md).
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include "apophis_like.hpp"

namespace {

bool known_kind(const std::string& kind) {
  for (const char* k : {"rate-test", "rate-test-short", "z-turns", "tumble", "tumble-step",
                        "tumble-step-face", "hand-tumble", "hand-tumble-timed"})
    if (kind == k) return true;
  return false;
}

sinscal::test::ApophisLike spec_of(const std::string& kind) {
  using namespace sinscal::test;
  if (kind == "z-turns") return apophis_z_turns();
  if (kind == "tumble") return apophis_tumble();
  if (kind == "tumble-step" || kind == "tumble-step-face")
    return apophis_tumble_step(kind == "tumble-step" ? 8 : 2, -0.3 * M_PI / 180.0);
  if (kind == "rate-test-short") return apophis_rate_test_short();
  if (kind == "hand-tumble" || kind == "hand-tumble-timed")
    return apophis_hand_tumble(kind == "hand-tumble-timed");
  return apophis_rate_test();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::fprintf(
        stderr,
        "usage: apophis_like_writer DIR "
        "rate-test|rate-test-short|z-turns|tumble|tumble-step|tumble-step-face|hand-tumble|"
        "hand-tumble-timed [SEED]\n");
    return 1;
  }
  const std::string kind = argv[2];
  if (!known_kind(kind)) {
    std::fprintf(stderr, "apophis_like_writer: unknown kind '%s'\n", argv[2]);
    return 1;
  }
  try {
    auto spec = spec_of(kind);
    if (argc == 4) spec.seed = static_cast<unsigned>(std::stoul(argv[3]));
    std::printf("%s\n", sinscal::test::write_apophis_like(argv[1], spec).c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "apophis_like_writer: %s\n", e.what());
    return 1;
  }
  return 0;
}
