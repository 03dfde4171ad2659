// Allan deviation and the fit of the noise model, on records made by the project's noise model
// (models/noise_model.hpp), so that the fit must recover the numbers the records were made with.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "filter/noise/allan.hpp"
#include "filter/noise/allan_sim.hpp"
#include "helpers.hpp"
#include "models/noise_model.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"

using namespace sinscal;

namespace {

/// A static record of noise only: zero increments through the noise generator.
std::vector<ImuSample> noise_record(const NoiseModel& noise, std::size_t n, double dt,
                                    std::uint64_t seed) {
  NoiseGenerator gen(noise, seed);
  std::vector<ImuSample> out(n);
  for (std::size_t k = 0; k < n; ++k) {
    out[k].dt = dt;
    out[k].t = static_cast<double>(k + 1) * dt;
    gen.apply(out[k].dtheta_b, out[k].dv_b, dt);
  }
  return out;
}

const AllanPoint& point_at(const std::vector<AllanPoint>& pts, double tau) {
  const AllanPoint* best = &pts.front();
  for (const auto& p : pts)
    if (std::abs(std::log(p.tau / tau)) < std::abs(std::log(best->tau / tau))) best = &p;
  return *best;
}

}  // namespace

TEST_CASE("Allan deviation of exact sequences", "[allan]") {
  // Alternating +-1: AVAR(tau0) = <(y2 - y1)^2> / 2 = 2; averages of pairs vanish.
  std::vector<double> alt(64);
  for (std::size_t k = 0; k < alt.size(); ++k) alt[k] = k % 2 == 0 ? 1.0 : -1.0;
  AllanOptions o;
  o.fit_quantization = true;
  const auto a = allan_deviation(alt, 1.0, o);
  CHECK(a[0].adev == Approx(std::sqrt(2.0)).epsilon(1e-12));
  CHECK(a[1].adev < 1e-12);
  // A rate ramp R: AVAR(tau) = R^2 tau^2 / 2 at every cluster time.
  std::vector<double> ramp(1000);
  const double R = 0.3, tau0 = 0.01;
  for (std::size_t k = 0; k < ramp.size(); ++k) ramp[k] = R * tau0 * static_cast<double>(k);
  for (const auto& p : allan_deviation(ramp, tau0))
    CHECK(p.adev == Approx(R * p.tau / std::sqrt(2.0)).epsilon(1e-9));
  CHECK_THROWS_AS(allan_deviation(std::vector<double>(10, 1.0), 0.01), AllanError);
  CHECK_THROWS_AS(allan_deviation(ramp, 0.0), AllanError);
}

TEST_CASE("Allan: white noise of known density gives the ARW and VRW within confidence",
          "[allan]") {
  NoiseModel noise;
  noise.gyro.white = 0.3 * units::deg_per_sqrt_h;
  noise.accel.white = 150.0 * units::ug_per_sqrt_hz;
  const auto rec = noise_record(noise, 100000, 0.01, 11);
  AllanOptions o;
  o.points_per_decade = 10;
  o.confidence = 0.99;
  const AllanAnalysis an = analyse_allan(rec, o);
  for (int i = 0; i < 3; ++i) {
    for (const bool gyro : {true, false}) {
      const auto& pts = gyro ? an.gyro[i] : an.accel[i];
      const AllanFit& fit = gyro ? an.gyro_fit[i] : an.accel_fit[i];
      const double N = gyro ? noise.gyro.white : noise.accel.white;
      // The estimate at tau = 1 s (m = 100, about 1500 degrees of freedom) brackets the truth
      // at 99 % confidence, and so does the same interval about the fit (which uses many
      // cluster times, so it is no less certain than that one point).
      const AllanPoint& p = point_at(pts, 1.0);
      CAPTURE(i, gyro, p.tau, p.adev, p.adev_low, p.adev_high, p.edf, fit.white, N);
      REQUIRE(p.tau == Approx(1.0));
      CHECK(p.dominant == AllanTerm::White);
      CHECK(N >= p.adev_low);
      CHECK(N <= p.adev_high);
      const double half_width = 0.5 * (p.adev_high - p.adev_low) / p.adev;
      CHECK(std::abs(fit.white / N - 1.0) < half_width);
      // Where white noise dominates, the slope is -1/2: the model at 100 s is the white term.
      CHECK(fit.term_variance(AllanTerm::White, 100.0) > 0.5 * fit.adev(100.0) * fit.adev(100.0));
    }
  }
}

TEST_CASE("Allan: rate random walk", "[allan]") {
  NoiseModel noise;
  noise.gyro.white = 0.3 * units::deg_per_sqrt_h;
  noise.gyro.random_walk = 100.0 * units::deg_per_h_per_sqrt_h;
  noise.accel.white = 150.0 * units::ug_per_sqrt_hz;
  noise.accel.random_walk = 1000.0 * units::ug_per_sqrt_h;
  const auto rec = noise_record(noise, 200000, 0.01, 12);
  AllanOptions o;
  o.confidence = 0.99;
  const AllanAnalysis an = analyse_allan(rec, o);
  for (int i = 0; i < 3; ++i) {
    for (const bool gyro : {true, false}) {
      const auto& pts = gyro ? an.gyro[i] : an.accel[i];
      const AllanFit& fit = gyro ? an.gyro_fit[i] : an.accel_fit[i];
      const double K = gyro ? noise.gyro.random_walk : noise.accel.random_walk;
      const double N = gyro ? noise.gyro.white : noise.accel.white;
      // At tau ~ 160 s the random walk dominates (crossing with the white noise at about 20 s)
      // with about 20 degrees of freedom: the truth lies in the point's 99 % interval, and the
      // fit within the same relative interval of the truth.
      const AllanPoint& p = point_at(pts, 160.0);
      const double truth = std::sqrt(K * K * p.tau / 3.0 + N * N / p.tau);
      CAPTURE(i, gyro, p.tau, p.adev, p.adev_low, p.adev_high, p.edf, fit.random_walk, K, fit.white,
              N);
      CHECK(p.dominant == AllanTerm::RandomWalk);
      CHECK(truth >= p.adev_low);
      CHECK(truth <= p.adev_high);
      CHECK(fit.random_walk / K > p.adev_low / p.adev);
      CHECK(fit.random_walk / K < p.adev_high / p.adev);
      CHECK(std::abs(fit.white / N - 1.0) < 0.05);  // the white part, ~1000 dof at 1 s
    }
  }
}

TEST_CASE("Allan: a Gauss-Markov bias gives a bias instability of its order", "[allan]") {
  // The mems profile's noise: ARW 0.3 deg/sqrt(h), VRW 150 ug/sqrt(Hz), Gauss-Markov biases of
  // 10 deg/h and 0.05 mg with 100 s correlation time.
  const SensorProfile mems = SensorProfile::load(test::source_path("config/sensors/mems.ini"));
  const auto rec = noise_record(mems.noise, 200000, 0.01, 13);
  const AllanAnalysis an = analyse_allan(rec);
  // A Gauss-Markov process of sigma q has an Allan deviation
  //   q T / tau * sqrt(2 tau / T - 3 + 4 exp(-tau / T) - exp(-2 tau / T)),
  // with its peak 0.617 q at tau = 1.89 T. With the white noise on top, the curve's minimum
  // (read as the floor 0.664 B) lies below that peak: for these numbers at 0.87 of it (gyros)
  // and 1.1 (accelerometers, white noise dominates up to the hump). Over 20 correlation times
  // the estimate there has about 10 degrees of freedom: order, within a factor 2.
  for (int i = 0; i < 3; ++i) {
    const double q_g = mems.noise.gyro.bias_instability, q_a = mems.noise.accel.bias_instability;
    const double rg = 0.664 * an.gyro_fit[i].floor_bias_instability / (0.617 * q_g);
    const double ra = 0.664 * an.accel_fit[i].floor_bias_instability / (0.617 * q_a);
    CAPTURE(i, rg, ra, an.gyro_fit[i].bias_instability / q_g,
            an.accel_fit[i].bias_instability / q_a);
    CHECK(rg > 0.5);
    CHECK(rg < 2.0);
    CHECK(ra > 0.5);
    CHECK(ra < 2.0);
    // The white noise is recovered as well.
    CHECK(an.gyro_fit[i].white / mems.noise.gyro.white == Approx(1.0).epsilon(0.05));
    CHECK(an.accel_fit[i].white / mems.noise.accel.white == Approx(1.0).epsilon(0.05));
  }
  // The fragment is a valid profile section: it loads and gives back the fitted numbers.
  const std::string dir = test::temp_dir("allan_fragment");
  const std::string frag = an.profile_fragment();
  test::write_file(dir + "/noise.ini", "[sensor]\nname = allan\n" + frag);
  const SensorProfile back = SensorProfile::load(dir + "/noise.ini");
  double white = 0.0;
  for (int i = 0; i < 3; ++i) white += an.gyro_fit[i].white / 3.0;
  INFO(frag);
  CHECK(back.noise.gyro.white == Approx(white).epsilon(1e-3));
  CHECK(back.noise.accel.white > 0.0);
}

namespace {

// White noise, flicker bias instability and rate random walk with crossings near 1 s and
// 300 s, at 100 Hz (the gyro of a tactical MEMS unit, in rad/s).
AllanTruth three_terms() {
  AllanTruth t;
  t.bias_instability = 1e-5;
  t.white = 0.664 * t.bias_instability;                          // crossing at tau = 1 s
  t.random_walk = t.bias_instability * std::sqrt(1.32 / 300.0);  // crossing at tau = 300 s
  return t;
}

}  // namespace

TEST_CASE("Allan: white noise, bias instability and rate random walk within their sigma",
          "[allan]") {
  // A gyro triad of 2^21 samples at 100 Hz (5.8 h), each axis its own record. The fit's sigma
  // takes the estimates' degrees of freedom and the correlation of neighbouring octaves: the
  // truth lies within 3 sigma of each fitted term (a term's sigma of about 1 % for the white
  // noise, 1 % for the flicker, 10-15 % for the random walk).
  const AllanTruth truth = three_terms();
  const double tau0 = 0.01;
  const std::size_t n = std::size_t{1} << 21;
  for (std::uint64_t axis = 1; axis <= 3; ++axis) {
    AllanNoiseSource src(truth, tau0, 10.0 * static_cast<double>(n) * tau0, axis);
    AllanAccumulator acc;
    for (std::size_t k = 0; k < n; ++k) acc.add(src.next());
    AllanFit f;
    const auto pts = allan_deviation(acc, tau0, {}, &f);
    CAPTURE(axis, f.white / truth.white, f.white_sigma / truth.white,
            f.bias_instability / truth.bias_instability,
            f.bias_instability_sigma / truth.bias_instability, f.random_walk / truth.random_walk,
            f.random_walk_sigma / truth.random_walk);
    REQUIRE(f.valid);
    CHECK(std::abs(f.white - truth.white) < 3.0 * f.white_sigma);
    CHECK(std::abs(f.bias_instability - truth.bias_instability) < 3.0 * f.bias_instability_sigma);
    CHECK(std::abs(f.random_walk - truth.random_walk) < 3.0 * f.random_walk_sigma);
    // The record resolves each term: its sigma is under half of it (the random walk's is the
    // largest, from the few degrees of freedom of the longest cluster times).
    CHECK(f.white_sigma < 0.5 * f.white);
    CHECK(f.bias_instability_sigma < 0.5 * f.bias_instability);
    CHECK(f.random_walk_sigma < 0.5 * f.random_walk);
    // The floor reading (IEEE's 0.664) agrees with the flicker term within its own sigma's
    // scale: the random walk and white noise lift the curve's minimum above 0.664 B.
    CHECK(f.floor_bias_instability > f.bias_instability - 3.0 * f.bias_instability_sigma);
    // Every cluster time above 2R = 8192 samples is strided, at most m / R.
    for (const auto& p : pts) CHECK(p.stride <= std::max<std::size_t>(1, p.m / 4096));
  }
}

TEST_CASE("Allan: the streamed estimator equals the in-memory one, in bounded memory", "[allan]") {
  AllanTruth t;
  t.white = 1.0;
  t.random_walk = 0.01;
  const std::size_t n = 100000;
  AllanNoiseSource src(t, 0.01, 1e4, 21);
  std::vector<double> y(n);
  for (int ppd : {0, 10}) {
    AllanAccumulator acc(ppd);
    for (std::size_t k = 0; k < n; ++k) {
      if (ppd == 0) y[k] = src.next();
      acc.add(y[k]);
    }
    AllanOptions o;
    o.points_per_decade = ppd;
    const auto streamed = allan_deviation(acc, 0.01, o);
    const auto memory = allan_deviation(y, 0.01, o);
    std::size_t exact = 0, below = 0;
    for (const auto& m : memory) below += m.m < AllanAccumulator::kExactClusters ? 1 : 0;
    for (const auto& s : streamed)
      for (const auto& m : memory) {
        if (s.m != m.m) continue;
        exact += s.stride == 1 ? 1 : 0;
        CAPTURE(ppd, s.m, s.stride, s.adev, m.adev, m.edf);
        if (s.stride == 1) {
          // Fully overlapping: the same sums (the phase's offset differs: rounding only).
          CHECK(s.adev == Approx(m.adev).epsilon(1e-9));
        } else {
          // Strided at most m / R: a small fraction of the estimate's own spread.
          CHECK(std::abs(s.adev / m.adev - 1.0) < 0.1 / std::sqrt(2.0 * m.edf));
        }
      }
    CHECK(exact == below);  // every cluster size below 2R, fully overlapping
  }
  // Memory: a ring of at most 4R + 1 phases per stride, strides growing as log2 of the record.
  AllanAccumulator acc;
  std::size_t at_2e5 = 0;
  for (std::size_t k = 0; k < 4000000; ++k) {
    acc.add(src.next());
    if (k == 200000) at_2e5 = acc.memory_bytes();
  }
  CAPTURE(at_2e5, acc.memory_bytes());
  CHECK(acc.memory_bytes() < 2 * at_2e5);  // 20 x the samples, under twice the memory
  CHECK(acc.memory_bytes() < 3000000);     // and under 3 MB per channel
}

TEST_CASE("Allan: the rate-ramp term when asked", "[allan]") {
  // A rate ramp on white noise: fitted within 3 sigma with --fit-rate-ramp, absent without.
  AllanTruth t;
  t.white = 1e-3;
  t.rate_ramp = 1e-7;
  const double tau0 = 0.01;
  AllanNoiseSource src(t, tau0, 1e5, 31);
  AllanAccumulator acc;
  for (std::size_t k = 0; k < 1000000; ++k) acc.add(src.next());
  AllanOptions o;
  o.fit_rate_ramp = true;
  AllanFit f, g;
  allan_deviation(acc, tau0, o, &f);
  allan_deviation(acc, tau0, {}, &g);
  CAPTURE(f.rate_ramp / t.rate_ramp, f.rate_ramp_sigma / t.rate_ramp, f.white / t.white);
  CHECK(std::abs(f.rate_ramp - t.rate_ramp) < 3.0 * f.rate_ramp_sigma);
  CHECK(std::abs(f.white - t.white) < 3.0 * f.white_sigma);
  CHECK(g.rate_ramp == 0.0);
}
