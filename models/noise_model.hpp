// Sensor noise: white noise on the rate (angle / velocity random walk), bias instability as a
// first-order Gauss-Markov process, rate random walk, and output quantization. All SI.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <random>

namespace sinscal {

/// Noise of one triad. Gyro units in brackets first, accelerometer second.
struct TriadNoise {
  double white = 0.0;                // rad/sqrt(s) | m/s/sqrt(s): ARW | VRW (density of the rate)
  double bias_instability = 0.0;     // rad/s | m/s^2: 1-sigma of the Gauss-Markov bias
  double correlation_time = 3600.0;  // s: Gauss-Markov correlation time
  double random_walk = 0.0;  // rad/s/sqrt(s) | m/s^2/sqrt(s): rate | acceleration random walk
  double quantum = 0.0;      // rad | m/s: increment per output count (0: not quantized)
  bool any() const {
    return white > 0.0 || bias_instability > 0.0 || random_walk > 0.0 || quantum > 0.0;
  }
};

struct NoiseModel {
  TriadNoise gyro;
  TriadNoise accel;
};

/// A well-mixed 64-bit seed for stream `stream` of a user seed (SplitMix64), so that truth
/// coefficients, noise and table errors draw from independent sequences of one --seed.
std::uint64_t derive_seed(std::uint64_t seed, std::uint64_t stream);

/// Adds noise to increments, one sample at a time; state (bias processes, quantization residue)
/// carries over between samples.
class NoiseGenerator {
 public:
  NoiseGenerator(const NoiseModel& model, std::uint64_t seed);
  /// Adds noise to the increments of one interval of length dt (s), then quantizes them.
  void apply(Eigen::Vector3d& dtheta_b, Eigen::Vector3d& dv_b, double dt);

 private:
  struct TriadState {
    Eigen::Vector3d gauss_markov = Eigen::Vector3d::Zero();
    Eigen::Vector3d random_walk = Eigen::Vector3d::Zero();
    Eigen::Vector3d residue = Eigen::Vector3d::Zero();
  };
  void apply_triad(const TriadNoise& n, TriadState& s, Eigen::Vector3d& increment, double dt);
  Eigen::Vector3d normal3();
  NoiseModel model_;
  TriadState gyro_, accel_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace sinscal
