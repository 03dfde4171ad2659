// Writes a generated session of the APOPHIS logs' structure (tests/apophis_like.hpp) for the
// bad-input corpus (tests/bad_input_test.sh): apophis_like_writer DIR rate-test | z-turns |
// hand-tumble | hand-tumble-timed [SEED] (a Monte Carlo of the rate test:
// docs/measured/apophis/README.md).
#include <cstdio>
#include <exception>
#include <string>

#include "apophis_like.hpp"

int main(int argc, char** argv) {
  if (argc != 3 && argc != 4) {
    std::fprintf(stderr,
                 "usage: apophis_like_writer DIR rate-test|z-turns|hand-tumble|hand-tumble-timed "
                 "[SEED]\n");
    return 1;
  }
  const std::string kind = argv[2];
  if (kind != "rate-test" && kind != "z-turns" && kind != "hand-tumble" &&
      kind != "hand-tumble-timed") {
    std::fprintf(stderr, "apophis_like_writer: unknown kind '%s'\n", argv[2]);
    return 1;
  }
  try {
    auto spec = kind == "rate-test" ? sinscal::test::apophis_rate_test()
                : kind == "z-turns"
                    ? sinscal::test::apophis_z_turns()
                    : sinscal::test::apophis_hand_tumble(kind == "hand-tumble-timed");
    if (argc == 4) spec.seed = static_cast<unsigned>(std::stoul(argv[3]));
    std::printf("%s\n", sinscal::test::write_apophis_like(argv[1], spec).c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "apophis_like_writer: %s\n", e.what());
    return 1;
  }
  return 0;
}
