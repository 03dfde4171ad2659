// Allan deviation and the fit of the noise model, on records made by the project's noise model
// (models/noise_model.hpp), so that the fit must recover the numbers the records were made with.
#include <catch2/catch.hpp>
#include <cmath>
#include <string>

#include "filter/noise/allan.hpp"
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
