// The calibration of the Allan fit's sigmas where the longest cluster times have few degrees of
// freedom (issue 34): over many short simulated records the errors of the fitted terms, in units
// of their sigma, must have an RMS near 1.
#include <catch2/catch.hpp>
#include <cmath>

#include "filter/noise/allan.hpp"
#include "filter/noise/allan_sim.hpp"

using namespace sinscal;

namespace {

struct Calibration {
  double rms_z[3] = {0.0, 0.0, 0.0};  // N, B, K
  int count[3] = {0, 0, 0};
  int beyond3[3] = {0, 0, 0};
};

Calibration calibrate(const AllanTruth& truth, std::size_t n, int records, std::uint64_t seed0,
                      bool log_fit) {
  Calibration c;
  const double tau0 = 0.01;
  AllanOptions o;
  o.log_fit = log_fit;
  for (int r = 0; r < records; ++r) {
    AllanNoiseSource src(truth, tau0, 10.0 * static_cast<double>(n) * tau0,
                         seed0 + static_cast<std::uint64_t>(r));
    AllanAccumulator acc;
    for (std::size_t k = 0; k < n; ++k) acc.add(src.next());
    AllanFit f;
    allan_deviation(acc, tau0, o, &f);
    const double fit[3] = {f.white, f.bias_instability, f.random_walk};
    const double sig[3] = {f.white_sigma, f.bias_instability_sigma, f.random_walk_sigma};
    const double tru[3] = {truth.white, truth.bias_instability, truth.random_walk};
    for (int t = 0; t < 3; ++t) {
      if (!(sig[t] > 0.0)) continue;
      const double z = (fit[t] - tru[t]) / sig[t];
      c.rms_z[t] += z * z;
      ++c.count[t];
      if (std::abs(z) > 3.0) ++c.beyond3[t];
    }
  }
  for (int t = 0; t < 3; ++t)
    if (c.count[t] > 0) c.rms_z[t] = std::sqrt(c.rms_z[t] / c.count[t]);
  return c;
}

}  // namespace

TEST_CASE("Allan: the sigmas are calibrated where the last octaves have few degrees of freedom",
          "[allan]") {
  // 100 records of 2^16 samples at 100 Hz (11 min): white noise crossing the flicker at 1 s, the
  // flicker crossing the random walk at 30 s, so that the last three octaves (82-164 s) are the
  // random walk's with 2-9 degrees of freedom (the last, a quarter of the record: about 2). The
  // fit must give each term an error of about one sigma RMS (the standard error of an RMS of 100
  // calibrated z is 0.07). The Gaussian fit of the variances (AllanOptions::log_fit = false)
  // gave the random walk an RMS z of 2.23, 10 of 100 beyond 3 sigma.
  AllanTruth t;
  t.bias_instability = 1e-5;
  t.white = 0.664 * t.bias_instability;                         // crossing at 1 s
  t.random_walk = t.bias_instability * std::sqrt(1.32 / 30.0);  // crossing at 30 s
  const Calibration c = calibrate(t, std::size_t{1} << 16, 100, 1000, true);
  CAPTURE(c.rms_z[0], c.rms_z[1], c.rms_z[2], c.count[2], c.beyond3[0], c.beyond3[1], c.beyond3[2]);
  for (int term = 0; term < 3; ++term) {
    CHECK(c.count[term] >= 90);  // fitted, not dropped
    CHECK(c.rms_z[term] > 0.8);
    CHECK(c.rms_z[term] < 1.3);
    CHECK(c.beyond3[term] <= 2);  // 0.27 expected
  }
}
