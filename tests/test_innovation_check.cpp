// The filter's innovations against its noise model (issue 33): the streaming autocorrelation sums
// equal the stored series' formula, the per-channel NIS and Ljung-Box tests with their
// Bonferroni verdict, and the filter's verdict on a clean session and on one whose noise model is
// three times too small (docs/methods/kalman-filter.md "Innovation consistency").
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "filter/kalman/innovation_check.hpp"
#include "filter/kalman/kalman_run.hpp"
#include "filter/noise/autocorrelation.hpp"
#include "helpers.hpp"

using namespace sinscal;

namespace {

// x_t = phi x_(t-1) + sqrt(1 - phi^2) e_t: unit variance, autocorrelation phi^k.
std::vector<double> ar1(std::mt19937& rng, int n, double phi, double scale = 1.0) {
  std::normal_distribution<double> e(0.0, 1.0);
  std::vector<double> x;
  double v = e(rng);
  for (int t = 0; t < n; ++t) {
    v = phi * v + std::sqrt(1.0 - phi * phi) * e(rng);
    x.push_back(scale * v);
  }
  return x;
}

// The autocorrelation at lag k about the mean, from the stored series.
double stored_autocorrelation(const std::vector<double>& x, int k) {
  double m = 0.0;
  for (double v : x) m += v;
  m /= static_cast<double>(x.size());
  double c0 = 0.0, ck = 0.0;
  for (std::size_t t = 0; t < x.size(); ++t) {
    c0 += (x[t] - m) * (x[t] - m);
    if (t >= static_cast<std::size_t>(k))
      ck += (x[t] - m) * (x[t - static_cast<std::size_t>(k)] - m);
  }
  return ck / c0;
}

}  // namespace

TEST_CASE("Autocorrelation sums: streaming, the stored series' autocorrelations and Q",
          "[innovations]") {
  std::mt19937 rng(3);
  for (int n : {3, 12, 500}) {
    std::vector<double> x = ar1(rng, n, 0.5);
    for (double& v : x) v += 0.7;  // a mean: the sums about it need the first and last values
    AutocorrelationSums s(10);
    for (double v : x) s.push(v);
    CAPTURE(n);
    CHECK(s.count() == n);
    double q = 0.0;
    for (int k = 1; k <= 10 && k < n; ++k) {
      CAPTURE(k);
      const double r = stored_autocorrelation(x, k);
      CHECK(s.autocorrelation(k) == Approx(r).margin(1e-12));
      q += r * r / (n - k);
    }
    const double nn = n;
    if (n > 11) CHECK(s.ljung_box_q(10) == Approx(nn * (nn + 2.0) * q).epsilon(1e-10));
    if (n <= 11) CHECK(s.ljung_box_q(10) == 0.0);  // too short for 10 lags
  }
  AutocorrelationSums constant(4);
  for (int t = 0; t < 50; ++t) constant.push(2.0);
  CHECK_FALSE(constant.varies());
  CHECK(constant.ljung_box_q(4) == 0.0);
}

// An AR(1) series x_k = phi x_(k-1) + e_k has the integrated autocorrelation time
// (1 + phi) / (1 - phi); its estimate's relative sigma is about sqrt(2 (2 M + 1) / n), M the
// summation window (about 5 tau here: Sokal's estimate), so 4 of those bound the check.
TEST_CASE("Autocorrelation time: AR(1) series at (1 + phi) / (1 - phi), white noise at 1",
          "[innovation]") {
  const auto ar1 = [](double phi, std::size_t n, unsigned seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> e(0.0, 1.0);
    std::vector<double> x(n);
    double v = 0.0;
    for (auto& xk : x) xk = v = phi * v + e(rng);
    return x;
  };
  for (const double phi : {0.5, 0.8}) {
    const std::size_t n = 50000;
    const double tau = (1.0 + phi) / (1.0 - phi);
    const double rel_sigma = std::sqrt(2.0 * (2.0 * 5.0 * tau + 1.0) / static_cast<double>(n));
    const double got = autocorrelation_time(ar1(phi, n, 7u));
    INFO("phi " << phi << ": tau " << got << " against " << tau);
    CHECK(std::abs(got / tau - 1.0) < 4.0 * rel_sigma);
  }
  // White noise, and a negatively correlated series (true 1/3): at least 1 by definition.
  CHECK(autocorrelation_time(ar1(0.0, 50000, 8u)) == Approx(1.0).margin(0.05));
  CHECK(autocorrelation_time(ar1(-0.5, 50000, 9u)) == Approx(1.0));
}

TEST_CASE("Innovation check: white channels pass, an AR(1) channel and a too-wide one fail",
          "[innovations]") {
  // 3000 updates per channel; 8 tests (5 NIS, the whiteness of the 3 dwell velocity channels),
  // threshold 0.01 / 8. AR(1) with phi 0.3: Q about 3000 (0.09 + 0.0081 + ...) = 295 on 10 lags
  // against the chi-square(10) point 29 there. Innovations 1.5 times wider than their S: NIS per
  // dof 2.25 against the chi-square(3000) point 1.08 per dof.
  std::mt19937 rng(7);
  InnovationRecord rec;
  for (int axis = 0; axis < 2; ++axis)
    for (double v : ar1(rng, 3000, 0.0)) rec.add(InnovationKind::VelocityDwells, axis, v);
  for (double v : ar1(rng, 3000, 0.3)) rec.add(InnovationKind::VelocityDwells, 2, v);
  for (double v : ar1(rng, 3000, 0.0, 1.5)) rec.add(InnovationKind::Position, 2, v);
  // The attitude's sigma is a bound (the table's hold): its correlation is not tested.
  for (double v : ar1(rng, 3000, 0.3)) rec.add(InnovationKind::Attitude, 0, v);
  const InnovationCheck c = innovation_check(rec);
  REQUIRE(c.channels.size() == 5);
  CHECK(c.tests == 8);
  CHECK(c.threshold == Approx(0.01 / 8));
  CHECK_FALSE(c.consistent);
  INFO(c.verdict);
  for (const auto& k : c.channels) {
    CAPTURE(k.channel, k.nis_per_dof, k.nis_p, k.ljung_box_q, k.ljung_box_p);
    CHECK(k.updates == 3000);
    CHECK(k.lags == 10);
    CHECK(k.sigma_bound == (k.channel.rfind("velocity (dwells)", 0) != 0));
  }
  for (int i = 0; i < 2; ++i) {
    const ChannelCheck& k = c.channels[static_cast<std::size_t>(i)];
    CHECK(k.nis_holds);
    CHECK(k.white);
    CHECK(std::abs(k.nis_per_dof - 1.0) < 4.0 * std::sqrt(2.0 / 3000.0));
  }
  CHECK(c.channels[2].channel == "velocity (dwells) down");
  CHECK(c.channels[2].nis_holds);
  CHECK_FALSE(c.channels[2].white);
  CHECK(c.channels[2].largest_lag == 1);
  CHECK(c.channels[2].largest_autocorrelation == Approx(0.3).margin(4.0 / std::sqrt(3000.0)));
  CHECK(c.channels[3].channel == "position down");
  CHECK_FALSE(c.channels[3].nis_holds);
  CHECK(c.channels[4].channel == "attitude north");
  CHECK(c.channels[4].nis_holds);
  CHECK(c.channels[4].white);  // not tested
  REQUIRE(c.failures.size() == 2);
  CHECK(c.failures[0].rfind("velocity (dwells) down innovations correlated at lag 1", 0) == 0);
  CHECK(c.failures[1].rfind("position down NIS per dof", 0) == 0);
  CHECK(c.verdict.rfind("not consistent: velocity (dwells) down", 0) == 0);
}

TEST_CASE("Innovation check: white innovations' family-wise false alarms about alpha",
          "[innovations]") {
  // 400 records of the 12 channels, 300 updates each (15 tests at alpha 0.01: 12 NIS, 3
  // whiteness): at most 4 false alarms expected (Bonferroni: at or below alpha), binomial sigma 2:
  // at most 4 + 4 sigma.
  std::mt19937 rng(13);
  int alarms = 0;
  const int runs = 400;
  for (int r = 0; r < runs; ++r) {
    InnovationRecord rec;
    for (int kind = 0; kind < 4; ++kind)
      for (int axis = 0; axis < 3; ++axis)
        for (double v : ar1(rng, 300, 0.0)) rec.add(static_cast<InnovationKind>(kind), axis, v);
    const InnovationCheck c = innovation_check(rec);
    REQUIRE(c.tests == 15);
    alarms += c.consistent ? 0 : 1;
  }
  INFO("false alarms " << alarms << " of " << runs);
  CHECK(alarms <= 12);
}

namespace {
// seed8 (8 dwells of 180 s) at 20 Hz, the nav-fog unit.
Session clean_seed8(std::uint64_t seed) {
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/seed8.ini");
  spec.data_sensor_path = test::source_path("config/sensors/nav-fog.ini");
  spec.filter_sensor_path = spec.data_sensor_path;
  spec.name = "innovations";
  spec.seed = seed;
  spec.rate_hz = 20.0;
  const std::string dir = test::temp_dir("innovations");
  simulate_session(dir, spec);
  return Session::load(dir + "/session.ini");
}

void scale_noise(TriadNoise& n, double k) {
  n.white *= k;
  n.bias_instability *= k;
  n.random_walk *= k;
}
}  // namespace

TEST_CASE(
    "Kalman filter innovations: consistent on a clean session, not with a noise model "
    "three times too small",
    "[innovations][kalman]") {
  const Session s = clean_seed8(21);
  CalibratorOptions o = calibrator_options_from_profile(SensorProfile::load(s.sensor_file));
  const KalmanRun clean = run_kalman(s, o);
  INFO(clean.innovations.verdict);
  // Every update row of the dwells and turns recorded, by channel: the verdict at alpha 0.01
  // family-wise (a false alarm on 1 seed in 100 at most).
  REQUIRE(clean.innovations.tested());
  CHECK(clean.innovations.consistent);
  for (const auto& k : clean.innovations.channels) {
    CAPTURE(k.channel, k.nis_per_dof, k.ljung_box_q);
    CHECK(k.updates > 50);
    CHECK(k.lags == kInnovationLags);
  }
  // The filter told the sensor's noise is a third of what it is: the innovations are three times
  // wider than S where the noise dominates them (NIS per dof up to 9), far beyond the
  // chi-square(updates) point at alpha / tests (about 1 + 3.3 sqrt(2 / 1400) = 1.12 per dof).
  scale_noise(o.noise.gyro, 1.0 / 3.0);
  scale_noise(o.noise.accel, 1.0 / 3.0);
  const KalmanRun narrow = run_kalman(s, o);
  INFO(narrow.innovations.verdict);
  CHECK_FALSE(narrow.innovations.consistent);
  bool velocity_fails = false;
  for (const auto& k : narrow.innovations.channels)
    if (k.channel.rfind("velocity (dwells)", 0) == 0 && !k.nis_holds) velocity_fails = true;
  CHECK(velocity_fails);
}
