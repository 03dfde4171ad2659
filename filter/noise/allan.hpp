// Allan deviation of static IMU records and the fit of the noise model (IEEE Std 952-1997,
// Annex C; estimator and confidence as in NIST SP 1065).
//
// Overlapping estimator on the integrated signal theta_k = tau0 * sum_{j<k} y_j (N = n + 1
// points for n rates): AVAR(m tau0) = sum_k (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2 /
// (2 (m tau0)^2 (N - 2m)). One pass of O(N) per cluster time over the cumulative sums: memory
// O(N) (the sums), time O(N x number of cluster times).
//
// Confidence: chi-square with the equivalent degrees of freedom of the overlapping estimator for
// the noise type that dominates at that cluster time (the simple approximations of Howe, Allan
// and Barnes, as tabulated in NIST SP 1065: white and flicker phase, white, flicker and random
// walk frequency), quantiles from Boost.Math.
//
// Noise model (IMU terms, each an independent process; SI):
//   AVAR(tau) = 3 Q^2 / tau^2            quantization (Q = quantum / sqrt(12)), slope -1
//             + N^2 / tau                angle / velocity random walk N, slope -1/2
//             + (2 ln 2 / pi) B^2        bias instability B (flicker floor: ADEV = 0.664 B)
//             + K^2 tau / 3              rate / acceleration random walk K, slope +1/2
// fitted by weighted least squares of the Allan variances (weights edf / (2 AVAR_model^2), the
// estimator's variance, iterated once with the model) with every term's variance non-negative
// (exact: the best of all subsets of terms). The dominant term at each cluster time then sets
// its degrees of freedom and the fit is repeated.
#pragma once

#include <Eigen/Core>
#include <array>
#include <stdexcept>
#include <string>
#include <vector>

#include "rig/imu_sample.hpp"

namespace sinscal {

class AllanError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Noise types of the model, also the power-law type used for the degrees of freedom.
enum class AllanTerm { Quantization, White, BiasInstability, RandomWalk };

struct AllanOptions {
  /// Cluster times: 0 gives octaves (m = 1, 2, 4, ...); otherwise this many per decade
  /// (log-spaced, rounded to whole samples, duplicates removed).
  int points_per_decade = 0;
  /// Largest cluster time as a fraction of the record (at most 1/2, where the estimator ends).
  double max_fraction = 0.25;
  /// Two-sided confidence of the bounds.
  double confidence = 0.683;
  /// Fit the quantization term (slope -1): for sensors whose output counts are coarse against
  /// their noise (off by default: on white noise alone the fit gives it a small spurious value).
  bool fit_quantization = false;
};

struct AllanPoint {
  double tau = 0.0;  // s
  std::size_t m = 0;
  double adev = 0.0;  // units of the rate
  double adev_low = 0.0, adev_high = 0.0;
  double edf = 0.0;
  AllanTerm dominant = AllanTerm::White;  // noise type the degrees of freedom assume
};

struct AllanFit {
  double quantization = 0.0;      // Q (rate unit x s)
  double white = 0.0;             // N (rate unit x sqrt(s))
  double bias_instability = 0.0;  // B (rate unit)
  double random_walk = 0.0;       // K (rate unit / sqrt(s))
  /// 1-sigma of each, from the weighted fit (the overlapping estimates at neighbouring cluster
  /// times are correlated, which this ignores: read them as a lower bound). 0 for a term the
  /// fit dropped (its variance would be negative).
  double quantization_sigma = 0.0, white_sigma = 0.0, bias_instability_sigma = 0.0,
         random_walk_sigma = 0.0;
  double chi2 = 0.0;  // weighted residual sum
  /// Bias instability read from the fitted curve's minimum over the cluster times, min ADEV /
  /// 0.664 (the IEEE Std 952 reading of a flat floor; datasheets' figure). Equals the fitted B for
  /// flicker noise; for a Gauss-Markov bias, whose hump the fit explains partly with its white and
  /// random-walk terms, it is the more faithful of the two. The profile fragment gives this one.
  double floor_bias_instability = 0.0;
  bool valid = false;  // false: no non-negative fit (allan_deviation then keeps white-noise edf)
  /// The model's Allan deviation at tau (s).
  double adev(double tau) const;
  /// The model's Allan variance of one term at tau.
  double term_variance(AllanTerm term, double tau) const;
};

/// The fewest samples an Allan deviation takes.
constexpr std::size_t kAllanMinSamples = 16;

/// Allan deviation of one channel of rates sampled every tau0 seconds; the fit sets each point's
/// noise type for its degrees of freedom (white noise where the model does not fit, e.g. a
/// drift). Throws AllanError for fewer than 16 samples or a non-positive tau0.
std::vector<AllanPoint> allan_deviation(const std::vector<double>& rates, double tau0,
                                        const AllanOptions& options = {}, AllanFit* fit = nullptr);

/// Fits the noise model to points (their edf and dominant noise types as given). Throws
/// AllanError when no combination of non-negative terms fits.
AllanFit fit_allan(const std::vector<AllanPoint>& points, bool fit_quantization = false);

/// Both triads of a static record of increments at a fixed rate.
struct AllanAnalysis {
  double tau0 = 0.0;  // s
  std::size_t samples = 0;
  std::array<std::vector<AllanPoint>, 3> gyro;   // rad/s
  std::array<std::vector<AllanPoint>, 3> accel;  // m/s^2
  std::array<AllanFit, 3> gyro_fit, accel_fit;   // SI
  /// The fits as a sensor-profile fragment (INI, the keys and units of docs/formats.md:
  /// arw, bias_instability, rate_random_walk, quantum; vrw, bias_instability, random_walk,
  /// quantum): the mean over the three axes, each axis in a comment; bias_instability is
  /// floor_bias_instability (the fitted flicker term in a comment); quantum only when fitted.
  std::string profile_fragment() const;
};

/// Allan analysis of a static record (increments over a constant interval; a varying interval
/// beyond 1 % is an AllanError).
AllanAnalysis analyse_allan(const std::vector<ImuSample>& samples,
                            const AllanOptions& options = {});

}  // namespace sinscal
