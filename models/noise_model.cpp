#include "models/noise_model.hpp"

#include <cmath>

namespace sinscal {

std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

NoiseGenerator::NoiseGenerator(const NoiseModel& model, std::uint64_t seed)
    : model_(model), rng_(seed) {
  // Gauss-Markov biases start in their stationary distribution.
  gyro_.gauss_markov = model_.gyro.bias_instability * normal3();
  accel_.gauss_markov = model_.accel.bias_instability * normal3();
}

Eigen::Vector3d NoiseGenerator::normal3() {
  const double a = normal_(rng_), b = normal_(rng_), c = normal_(rng_);
  return {a, b, c};
}

void NoiseGenerator::apply_triad(const TriadNoise& n, TriadState& s, Eigen::Vector3d& inc,
                                 double dt) {
  if (n.white > 0.0) inc += n.white * std::sqrt(dt) * normal3();
  if (n.bias_instability > 0.0) {
    // Exact discretisation of db/dt = -b/T + w: stationary sigma stays bias_instability.
    const double phi = std::exp(-dt / n.correlation_time);
    s.gauss_markov =
        phi * s.gauss_markov + n.bias_instability * std::sqrt(1.0 - phi * phi) * normal3();
    inc += s.gauss_markov * dt;
  }
  if (n.random_walk > 0.0) {
    s.random_walk += n.random_walk * std::sqrt(dt) * normal3();
    inc += s.random_walk * dt;
  }
  if (n.quantum > 0.0) {
    // Output whole counts; the remainder is carried, so no increment is lost.
    const Eigen::Vector3d total = inc + s.residue;
    const Eigen::Vector3d counts = (total / n.quantum).array().round();
    inc = counts * n.quantum;
    s.residue = total - inc;
  }
}

void NoiseGenerator::apply(Eigen::Vector3d& dtheta_b, Eigen::Vector3d& dv_b, double dt) {
  apply_triad(model_.gyro, gyro_, dtheta_b, dt);
  apply_triad(model_.accel, accel_, dv_b, dt);
}

}  // namespace sinscal
