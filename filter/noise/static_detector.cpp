#include "filter/noise/static_detector.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "models/units.hpp"

namespace sinscal {

StaticDetector::StaticDetector(const NoiseModel& noise, const StaticDetectorOptions& options)
    : noise_(noise), o_(options) {
  if (!(o_.window > 0.0) || !(o_.min_duration >= o_.window))
    throw std::invalid_argument(
        "static detector: the window must be positive and no longer than the minimum duration");
  rate_threshold_ = o_.rate_threshold > 0.0 ? o_.rate_threshold : 3.0 * units::deg_per_s;
}

bool StaticDetector::push(const ImuSample& s) {
  if (rate_.empty()) {
    // The window in samples, and the noise bounds of one sample's mean rate, from the rate.
    const std::size_t n =
        std::max<std::size_t>(3, static_cast<std::size_t>(std::lround(o_.window / s.dt)));
    rate_.assign(n, Eigen::Vector3d::Zero());
    force_.assign(n, Eigen::Vector3d::Zero());
    t_.assign(n, 0.0);
    // Per-sample sigma of a mean rate: white noise density / sqrt(dt), quantization q / dt
    // (uniform: / sqrt(12)); a 3-vector's deviation, max over the window: `sigmas` of them.
    auto bound = [&](const TriadNoise& tn, double floor) {
      const double white = tn.white / std::sqrt(s.dt);
      const double quant = tn.quantum / s.dt / std::sqrt(12.0);
      return std::max(floor, o_.sigmas * std::hypot(white, quant));
    };
    gyro_bound_ =
        o_.gyro_deviation > 0.0 ? o_.gyro_deviation : bound(noise_.gyro, 1e-3 * units::deg_per_s);
    accel_bound_ =
        o_.accel_deviation > 0.0 ? o_.accel_deviation : bound(noise_.accel, 10.0 * units::ug);
  }
  const std::size_t n = rate_.size();
  const Eigen::Vector3d rate = s.dtheta_b / s.dt, force = s.dv_b / s.dt;
  // Running sums over the window (about a reference value, exact recount every n samples so
  // rounding cannot accumulate): O(1) per sample.
  if (filled_ == n) {
    sum_rate_ -= rate_[next_] - ref_rate_;
    sum_force_ -= force_[next_] - ref_force_;
    sq_rate_ -= (rate_[next_] - ref_rate_).squaredNorm();
    sq_force_ -= (force_[next_] - ref_force_).squaredNorm();
  }
  rate_[next_] = rate;
  force_[next_] = force;
  t_[next_] = s.t - s.dt;
  sum_rate_ += rate - ref_rate_;
  sum_force_ += force - ref_force_;
  sq_rate_ += (rate - ref_rate_).squaredNorm();
  sq_force_ += (force - ref_force_).squaredNorm();
  next_ = (next_ + 1) % n;
  filled_ = std::min(filled_ + 1, n);
  if (++since_recount_ >= n) {
    since_recount_ = 0;
    ref_rate_ = rate;
    ref_force_ = force;
    sum_rate_.setZero();
    sum_force_.setZero();
    sq_rate_ = sq_force_ = 0.0;
    for (std::size_t k = 0; k < filled_; ++k) {
      sum_rate_ += rate_[k] - ref_rate_;
      sum_force_ += force_[k] - ref_force_;
      sq_rate_ += (rate_[k] - ref_rate_).squaredNorm();
      sq_force_ += (force_[k] - ref_force_).squaredNorm();
    }
  }
  bool still = filled_ == n;
  if (still) {
    // Static: the mean rate below the threshold, the newest sample within the bound of the
    // window's mean, and the RMS deviation over the window within half the bound (3 sigma for
    // noise-derived bounds; the RMS of a 3-vector of white noise is 1.7 sigma).
    const double inv = 1.0 / static_cast<double>(n);
    const Eigen::Vector3d d_rate = sum_rate_ * inv, d_force = sum_force_ * inv;
    const Eigen::Vector3d mean_rate = ref_rate_ + d_rate, mean_force = ref_force_ + d_force;
    const double var_rate = std::max(0.0, sq_rate_ * inv - d_rate.squaredNorm());
    const double var_force = std::max(0.0, sq_force_ * inv - d_force.squaredNorm());
    still = mean_rate.norm() < rate_threshold_ && (rate - mean_rate).norm() < gyro_bound_ &&
            (force - mean_force).norm() < accel_bound_ &&
            var_rate < 0.25 * gyro_bound_ * gyro_bound_ &&
            var_force < 0.25 * accel_bound_ * accel_bound_;
  }
  if (still && !static_) {
    static_since_ = t_[next_];  // the oldest sample of the window
    counted_ = false;
  }
  static_ = still;
  if (static_ && !counted_ && s.t - static_since_ >= o_.min_duration - 1e-9) {
    counted_ = true;
    found_.push_back({static_cast<int>(found_.size()) + 1, static_since_, s.t});
  }
  if (static_ && counted_) found_.back().t_end = s.t;
  return static_;
}

}  // namespace sinscal
