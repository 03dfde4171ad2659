// Rates made of the Allan noise model's terms (filter/noise/allan.hpp), for the tests and the
// bench: the fit must recover the numbers a record was made with.
//
//   white noise N: y = N / sqrt(tau0) x n_k (the mean of a white rate of density N over tau0)
//   bias instability B (flicker, S(f) = B^2 / (2 pi f) two-sided): a sum of Gauss-Markov
//     processes with correlation times T_i = T_min 2^i up to T_max, each of variance
//     q^2 = B^2 ln 2 / pi (their spectra sum to B^2 / (2 pi f) between 1 / (2 pi T_max) and
//     1 / (2 pi T_min), within a ripple of well under 1 %). Each is averaged over its step h
//     exactly (as an integrating sensor's output): with a = exp(-h / T), the end value
//     x1 = a x0 + w1 and the integral I = T (1 - a) x0 + w2, var w1 = q^2 (1 - a^2),
//     var w2 = q^2 T^2 (2 h / T - 3 + 4 a - a^2), cov = q^2 T (1 - a)^2; the step is one
//     sample up to T = 64 tau0, then T / 64 (the block's mean held over it). T_min = tau0 / 64.
//     Measured (2^21 samples): the flicker's ADEV is 0.664 B within 0.3 % from 4 tau0 on
//     (0.7 % low at tau0). `fast` (the bench): T_min = 4 tau0 and steps of T / 8, a quarter
//     of the work, with the ADEV about 2 % low up to 1000 tau0.
//   rate random walk K: b_{k+1} = b_k + K sqrt(tau0) n_k
//   rate ramp R: R t
#pragma once

#include <cstdint>
#include <random>
#include <vector>

namespace sinscal {

struct AllanTruth {
  double white = 0.0;             // N (rate x sqrt(s))
  double bias_instability = 0.0;  // B (rate; ADEV floor 0.664 B)
  double random_walk = 0.0;       // K (rate / sqrt(s))
  double rate_ramp = 0.0;         // R (rate / s)
};

/// One channel of rates sampled every tau0 seconds with the terms of `truth`; the flicker
/// spans correlation times [tau0 / 64, longest] (longest: about 10 x the record's length).
class AllanNoiseSource {
 public:
  AllanNoiseSource(const AllanTruth& truth, double tau0, double longest, std::uint64_t seed,
                   bool fast = false);
  double next();

 private:
  struct Markov {
    double T = 0.0, decay = 0.0, x = 0.0, mean = 0.0;
    double s_end = 0.0, s_int = 0.0, rho = 0.0;  // sigma of w1, of w2 / h; their correlation
    std::uint64_t hold = 1;                      // samples per step
  };
  AllanTruth truth_;
  double tau0_;
  std::vector<Markov> flicker_;
  double walk_ = 0.0;
  std::uint64_t k_ = 0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
};

}  // namespace sinscal
