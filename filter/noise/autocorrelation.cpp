#include "filter/noise/autocorrelation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sinscal {

AutocorrelationSums::AutocorrelationSums(int lags) : lags_(lags) {
  if (lags < 1) throw std::invalid_argument("autocorrelation sums need at least one lag");
  const auto l = static_cast<std::size_t>(lags);
  lag_sum_.assign(l + 1, 0.0);
  first_.reserve(l);
  last_.assign(l, 0.0);
}

void AutocorrelationSums::push(double x) {
  const auto l = static_cast<std::size_t>(lags_);
  // last_[(next_ - k) mod l] holds x_(n-k) for k = 1..min(n, l).
  for (std::size_t k = 1; k <= l && k <= static_cast<std::size_t>(n_); ++k)
    lag_sum_[k] += x * last_[(next_ + l - k) % l];
  if (first_.size() < l) first_.push_back(x);
  last_[next_] = x;
  next_ = (next_ + 1) % l;
  ++n_;
  sum_ += x;
  sum2_ += x * x;
}

// sum over t = k..n-1 of (x_t - m)(x_(t-k) - m) = S_k - m (A + B) + (n - k) m^2, A the sum
// without the first k values, B without the last k.
double AutocorrelationSums::centred_product(int k, double mean) const {
  const auto l = static_cast<std::size_t>(lags_);
  const auto kk = static_cast<std::size_t>(k);
  double head = 0.0, tail = 0.0;
  for (std::size_t i = 0; i < kk; ++i) {
    head += first_[i];
    tail += last_[(next_ + l - 1 - i) % l];
  }
  const double a = sum_ - head, b = sum_ - tail;
  return lag_sum_[kk] - mean * (a + b) + static_cast<double>(n_ - k) * mean * mean;
}

bool AutocorrelationSums::varies() const {
  if (n_ < 2) return false;
  const double n = static_cast<double>(n_), mean = sum_ / n;
  return sum2_ - n * mean * mean > 1e-12 * sum2_;
}

double AutocorrelationSums::autocorrelation(int k) const {
  if (k < 1 || k > lags_ || k >= n_ || !varies()) return 0.0;
  const double n = static_cast<double>(n_), mean = sum_ / n;
  return centred_product(k, mean) / (sum2_ - n * mean * mean);
}

double AutocorrelationSums::ljung_box_q(int h) const {
  h = std::min(h, lags_);
  if (h < 1 || n_ <= h + 1) return 0.0;
  if (!varies()) return 0.0;
  const double n = static_cast<double>(n_);
  double q = 0.0;
  for (int k = 1; k <= h; ++k) {
    const double r = autocorrelation(k);
    q += r * r / (n - k);
  }
  return n * (n + 2.0) * q;
}

double autocorrelation_time(const std::vector<double>& x) {
  const std::size_t n = x.size();
  if (n < 8) return 1.0;
  double mean = 0.0;
  for (const double v : x) mean += v;
  mean /= static_cast<double>(n);
  const auto autocovariance = [&](std::size_t lag) {
    double s = 0.0;
    for (std::size_t k = 0; k + lag < n; ++k) s += (x[k] - mean) * (x[k + lag] - mean);
    return s / static_cast<double>(n);
  };
  const double c0 = autocovariance(0);
  if (!(c0 > 0.0)) return 1.0;
  // Pairs rho(2m - 1) + rho(2m), m = 1, 2, ..., summed while positive (Geyer's initial positive
  // sequence), when the first is beyond 2 sigma of white noise's (each autocorrelation's sigma
  // 1 / sqrt(n)): white noise gives 1, not 1 plus its noise's positive pairs.
  const double noise = 2.0 * std::sqrt(2.0 / static_cast<double>(n));
  const std::size_t max_lag = std::min<std::size_t>(n / 4, 2000);  // bounded cost
  double tau = 1.0;
  for (std::size_t lag = 1; lag + 1 <= max_lag; lag += 2) {
    const double pair = (autocovariance(lag) + autocovariance(lag + 1)) / c0;
    if (!(pair > (lag == 1 ? noise : 0.0))) break;
    tau += 2.0 * pair;
  }
  return tau;
}

}  // namespace sinscal
