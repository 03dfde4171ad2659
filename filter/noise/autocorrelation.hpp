// A series' autocorrelations up to a fixed lag, streaming in bounded memory, and the Ljung-Box
// statistic of its whiteness: the running sums of x, x^2 and of the lag products x_t x_(t-k),
// with the first and the last `lags` values (the sums about the mean need them). The result is
// that of the batch formula over the whole series (docs/methods/kalman-filter.md "Innovation
// consistency"). The Kalman filter keeps one per measurement channel of its normalized
// innovations; the diagnoses' ljung_box (filter/diagnosis/diagnosis_core.hpp) is this over a
// stored series.
#pragma once

#include <cstddef>
#include <vector>

namespace sinscal {

/// The integrated autocorrelation time (in samples, at least 1) of `x`: 1 + 2 sum of its
/// autocorrelations, summed in pairs (lags 2m - 1 and 2m) while a pair is positive (Geyer's
/// initial positive sequence), when the first pair is beyond 2 sigma of white noise's (white
/// noise: 1); lags up to a quarter of the samples and at most 2000.
/// The rate table weighs each segment mean by it (var tau / n).
double autocorrelation_time(const std::vector<double>& x);

class AutocorrelationSums {
 public:
  /// Autocorrelations up to `lags` (at least 1).
  explicit AutocorrelationSums(int lags = 10);
  void push(double x);
  long count() const { return n_; }
  int lags() const { return lags_; }
  double sum() const { return sum_; }
  /// Sum of the squares (about zero, not the mean): a normalized innovation's NIS.
  double sum_squares() const { return sum2_; }
  /// Whether the series varies (sum of squares about its mean above rounding).
  bool varies() const;
  /// The sample autocorrelation at lag k (1 <= k <= lags), about the series' mean: sum over
  /// t = k..n-1 of (x_t - m)(x_(t-k) - m) over sum of (x_t - m)^2; 0 when it is not defined
  /// (k >= n, a constant series).
  double autocorrelation(int k) const;
  /// Q = n (n + 2) sum over k = 1..h of r_k^2 / (n - k) (h <= lags); 0 when n <= h + 1 or the
  /// series is constant.
  double ljung_box_q(int h) const;

 private:
  double centred_product(int k, double mean) const;
  int lags_;
  long n_ = 0;
  double sum_ = 0.0, sum2_ = 0.0;
  std::vector<double> lag_sum_;  // k = 1..lags: sum of x_t x_(t-k)
  std::vector<double> first_;    // the first `lags` values
  std::vector<double> last_;     // ring of the last `lags` values
  std::size_t next_ = 0;         // where the next value goes in last_
};

}  // namespace sinscal
