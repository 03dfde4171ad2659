#include <catch2/catch.hpp>
#include <cmath>
#include <vector>

#include "models/noise_model.hpp"
#include "models/units.hpp"

using namespace sinscal;
using Eigen::Vector3d;

// Statistical tests: fixed seeds, tolerances of 4-5 standard errors of the estimate.

TEST_CASE("Noise: white noise has the density given (ARW, VRW)", "[noise]") {
  NoiseModel m;
  m.gyro.white = 0.001 * units::deg_per_sqrt_h;
  m.accel.white = 10 * units::ug_per_sqrt_hz;
  NoiseGenerator gen(m, 11);
  const double dt = 0.01;
  const int N = 200000;
  double sg = 0, sa = 0, mg = 0;
  for (int k = 0; k < N; ++k) {
    Vector3d dth = Vector3d::Zero(), dv = Vector3d::Zero();
    gen.apply(dth, dv, dt);
    sg += dth.squaredNorm();
    sa += dv.squaredNorm();
    mg += dth.x();
  }
  const double n = 3.0 * N;
  const double rel = 4.0 / std::sqrt(2.0 * n);  // 4 standard errors of a standard deviation
  CHECK(std::sqrt(sg / n) == Approx(m.gyro.white * std::sqrt(dt)).epsilon(rel));
  CHECK(std::sqrt(sa / n) == Approx(m.accel.white * std::sqrt(dt)).epsilon(rel));
  CHECK(std::abs(mg / N) < 4.0 * m.gyro.white * std::sqrt(dt) / std::sqrt(N));
}

TEST_CASE("Noise: Gauss-Markov bias has its sigma and correlation time", "[noise]") {
  NoiseModel m;
  m.gyro.bias_instability = 0.01 * units::deg_per_h;
  m.gyro.correlation_time = 1.0;
  NoiseGenerator gen(m, 5);
  const double dt = 0.01;
  const int N = 1000000;  // 10^4 s = 5000 correlation times (2 T per independent sample)
  std::vector<double> b(N);
  for (int k = 0; k < N; ++k) {
    Vector3d dth = Vector3d::Zero(), dv = Vector3d::Zero();
    gen.apply(dth, dv, dt);
    b[k] = dth.x() / dt;
  }
  double var = 0, lag = 0;
  for (int k = 0; k < N; ++k) var += b[k] * b[k];
  const int L = 100;  // one correlation time
  for (int k = L; k < N; ++k) lag += b[k] * b[k - L];
  var /= N;
  lag /= (N - L);
  const double n_eff = N * dt / (2.0 * m.gyro.correlation_time);
  CHECK(std::sqrt(var) == Approx(m.gyro.bias_instability).epsilon(4.0 / std::sqrt(2.0 * n_eff)));
  CHECK(lag / var == Approx(std::exp(-1.0)).margin(4.0 / std::sqrt(n_eff)));
}

TEST_CASE("Noise: rate random walk grows as K^2 t", "[noise]") {
  NoiseModel m;
  m.gyro.random_walk = 0.01 * units::deg_per_h_per_sqrt_h;
  const int runs = 2000, steps = 100;
  const double dt = 0.01;
  double sum2 = 0;
  for (int r = 0; r < runs; ++r) {
    NoiseGenerator gen(m, 1000 + r);
    Vector3d dth, dv;
    for (int k = 0; k < steps; ++k) {
      dth.setZero();
      dv.setZero();
      gen.apply(dth, dv, dt);
    }
    sum2 += (dth / dt).squaredNorm();
  }
  const double expected = m.gyro.random_walk * m.gyro.random_walk * steps * dt;
  CHECK(sum2 / (3.0 * runs) == Approx(expected).epsilon(4.0 * std::sqrt(2.0 / (3.0 * runs))));
}

TEST_CASE("Noise: quantization outputs whole counts and loses nothing", "[noise]") {
  NoiseModel m;
  m.gyro.quantum = 0.1 * units::arcsec;
  m.accel.quantum = 1e-4;
  NoiseGenerator gen(m, 1);
  Vector3d true_sum = Vector3d::Zero(), out_sum = Vector3d::Zero();
  for (int k = 0; k < 10000; ++k) {
    const Vector3d truth(3.3e-7, -1.234e-6, 7.7e-8);
    Vector3d dth = truth, dv = Vector3d(0.098, 0.001, -0.0003);
    gen.apply(dth, dv, 0.01);
    for (int i = 0; i < 3; ++i) {
      CHECK(std::abs(dth(i) / m.gyro.quantum - std::round(dth(i) / m.gyro.quantum)) < 1e-6);
    }
    true_sum += truth;
    out_sum += dth;
  }
  CHECK((out_sum - true_sum).cwiseAbs().maxCoeff() <= 0.5 * m.gyro.quantum * (1 + 1e-9));
}
