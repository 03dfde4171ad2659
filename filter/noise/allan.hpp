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
//             + R^2 tau^2 / 2            rate ramp R, slope +1 (opt-in, as quantization)
// fitted by generalised least squares of the log Allan variances (each estimate's log of a
// chi-square: mean psi(edf/2) - log(edf/2), variance psi'(edf/2); Gauss-Newton from a Gaussian
// fit of the variances; neighbouring octaves correlated as measured)
// with every term's variance non-negative
// (exact: the best of all subsets of terms). The dominant term at each cluster time then sets
// its degrees of freedom and the fit is repeated.
//
// Bounded memory (AllanAccumulator, AllanStream): the same estimator fed one rate at a time. Each
// cluster size m takes the phase theta at a stride d (a power of two, 1 for m < 2R with
// R = 4096): d = 2^floor(log2(m / R)) above, so m / d lies in [R, 2R] and m is rounded to a
// multiple of d. A ring of the last 2 m / d + 1 phases per stride gives the second differences
// at every d-th start: fully overlapping (exact) below 2R samples, overlapping at a stride of at
// most m / R above. Memory: O(R x strides) per channel, independent of the record's length.
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
enum class AllanTerm { Quantization, White, BiasInstability, RandomWalk, RateRamp };

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
  /// Fit the rate-ramp term R (slope +1, AVAR = R^2 tau^2 / 2): a drift over the record (off by
  /// default: with few degrees of freedom at the longest cluster times it takes part of the
  /// random walk).
  bool fit_rate_ramp = false;
  /// Fit the logarithms of the Allan variances with their chi-square's mean and variance
  /// (docs/methods/allan.md); false: the Gaussian fit of the variances (the fit before
  /// 2026-12-06, whose random-walk sigma is too small where the last octaves have few degrees of
  /// freedom; kept for comparison).
  bool log_fit = true;
};

struct AllanPoint {
  double tau = 0.0;  // s
  std::size_t m = 0;
  std::size_t stride = 1;  // of the overlapping starts (1: fully overlapping)
  double adev = 0.0;       // units of the rate
  double adev_low = 0.0, adev_high = 0.0;
  double edf = 0.0;
  AllanTerm dominant = AllanTerm::White;  // noise type the degrees of freedom assume
};

struct AllanFit {
  double quantization = 0.0;      // Q (rate unit x s)
  double white = 0.0;             // N (rate unit x sqrt(s))
  double bias_instability = 0.0;  // B (rate unit)
  double random_walk = 0.0;       // K (rate unit / sqrt(s))
  double rate_ramp = 0.0;         // R (rate unit / s)
  /// 1-sigma of each, from the weighted fit: the estimates' degrees of freedom and the
  /// correlation of neighbouring octaves (measured, docs/methods/allan.md). 0 for a term the fit
  /// dropped (its variance would be negative) or was not asked for.
  double quantization_sigma = 0.0, white_sigma = 0.0, bias_instability_sigma = 0.0,
         random_walk_sigma = 0.0, rate_ramp_sigma = 0.0;
  double chi2 = 0.0;  // weighted residual sum
  /// Bias instability read from the fitted curve's minimum over the cluster times, min ADEV /
  /// 0.664 (the IEEE Std 952 reading of a flat floor; datasheets' figure). Equals the fitted B for
  /// flicker noise; for a Gauss-Markov bias, whose hump the fit explains partly with its white and
  /// random-walk terms, it is the more faithful of the two. The profile fragment gives this one.
  double floor_bias_instability = 0.0;
  /// Its 1-sigma as the reading of one estimate: floor / sqrt(2 edf) with the degrees of freedom
  /// of the cluster time at the minimum.
  double floor_bias_instability_sigma = 0.0;
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
AllanFit fit_allan(const std::vector<AllanPoint>& points, bool fit_quantization = false,
                   bool fit_rate_ramp = false, bool log_fit = true);

/// The overlapping Allan variance of one channel, fed one rate at a time in memory independent
/// of the record's length (see the header's comment: exact below kExactClusters samples, at a
/// stride of at most m / (kExactClusters / 2) above).
class AllanAccumulator {
 public:
  /// Cluster sizes below this are fully overlapping (2R).
  static constexpr std::size_t kExactClusters = 8192;
  /// One cluster size's sum.
  struct Estimate {
    std::size_t m = 0;       // cluster size (samples)
    std::size_t stride = 1;  // of the starts
    std::size_t terms = 0;   // second differences summed
    double avar = 0.0;       // rate unit^2
  };
  /// Cluster sizes: octaves (0) or this many per decade (as AllanOptions::points_per_decade).
  explicit AllanAccumulator(int points_per_decade = 0);
  void add(double rate);
  std::size_t samples() const { return n_; }
  /// The cluster sizes up to max_fraction of the samples with at least one term, in order.
  std::vector<Estimate> estimates(double max_fraction) const;
  /// Bytes held (rings and sums).
  std::size_t memory_bytes() const;

 private:
  struct Level {
    std::size_t m = 0, r = 0;  // r = m / stride
    double sum = 0.0;
    std::size_t terms = 0;
  };
  struct Group {
    std::size_t stride = 1, mask = 0, pushed = 0;
    std::vector<double> ring;
    std::vector<Level> levels;  // ascending r
  };
  void push(Group& g);
  std::vector<Group> groups_;  // ascending stride (powers of two)
  std::size_t n_ = 0;
  double theta_ = 0.0, offset_ = 0.0;  // phase in rate x samples, the first rate removed
};

/// Allan deviation of an accumulated channel (as allan_deviation; tau0 in s).
std::vector<AllanPoint> allan_deviation(const AllanAccumulator& accumulator, double tau0,
                                        const AllanOptions& options = {}, AllanFit* fit = nullptr);

/// Both triads of a static record of increments at a fixed rate.
struct AllanAnalysis {
  double tau0 = 0.0;  // s
  std::size_t samples = 0;
  std::array<std::vector<AllanPoint>, 3> gyro;   // rad/s
  std::array<std::vector<AllanPoint>, 3> accel;  // m/s^2
  std::array<AllanFit, 3> gyro_fit, accel_fit;   // SI
  /// The largest stride of the starts (1: every cluster time fully overlapping).
  std::size_t max_stride = 1;
  /// The fits as a sensor-profile fragment (INI, the keys and units of docs/formats.md:
  /// arw, bias_instability, rate_random_walk, quantum; vrw, bias_instability, random_walk,
  /// quantum): the mean over the three axes, each axis in a comment; bias_instability is
  /// floor_bias_instability (the fitted flicker term in a comment); quantum only when fitted.
  std::string profile_fragment() const;
};

/// Both triads accumulated sample by sample (bounded memory).
class AllanStream {
 public:
  explicit AllanStream(const AllanOptions& options = {});
  /// Increments over a constant interval: one differing from the first by more than 1 % is an
  /// AllanError naming the sample.
  void add(const ImuSample& sample);
  /// Rates (SI) at the interval given to analysis().
  void add_rates(const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& f_b);
  std::size_t samples() const { return channels_[0].samples(); }
  /// The first sample's interval (add()), 0 before.
  double first_interval() const { return tau0_; }
  std::size_t memory_bytes() const;
  /// The analysis at sample interval tau0 (s). Throws AllanError when too short.
  AllanAnalysis analysis(double tau0) const;

 private:
  AllanOptions options_;
  std::array<AllanAccumulator, 6> channels_;  // gyro x y z, accel x y z
  double tau0_ = 0.0;
};

/// Allan analysis of a static record (increments over a constant interval; a varying interval
/// beyond 1 % is an AllanError), through AllanStream.
AllanAnalysis analyse_allan(const std::vector<ImuSample>& samples,
                            const AllanOptions& options = {});

}  // namespace sinscal
