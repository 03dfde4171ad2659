#include "filter/table_free/pose_detector.hpp"

#include <algorithm>
#include <array>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <limits>
#include <string>

namespace sinscal {
namespace {

double quantile_of(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const auto k = static_cast<std::size_t>(
      std::clamp(q * static_cast<double>(v.size() - 1), 0.0, static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

double channel(const ImuReading& r, int c) { return c < 3 ? r.accel(c) : r.gyro(c - 3); }

}  // namespace

void reading_statistics(const std::vector<ImuReading>& readings, std::size_t first,
                        std::size_t last, Eigen::Vector3d& accel_mean, Eigen::Vector3d& gyro_mean,
                        Eigen::Vector3d& accel_std, Eigen::Vector3d& gyro_std) {
  if (last < first || last >= readings.size())
    throw PoseDetectorError("reading statistics: bad range");
  const double n = static_cast<double>(last - first + 1);
  Eigen::Vector3d sa = Eigen::Vector3d::Zero(), sg = Eigen::Vector3d::Zero();
  for (std::size_t k = first; k <= last; ++k) {
    sa += readings[k].accel;
    sg += readings[k].gyro;
  }
  accel_mean = sa / n;
  gyro_mean = sg / n;
  Eigen::Vector3d qa = Eigen::Vector3d::Zero(), qg = Eigen::Vector3d::Zero();
  for (std::size_t k = first; k <= last; ++k) {
    qa += (readings[k].accel - accel_mean).cwiseAbs2();
    qg += (readings[k].gyro - gyro_mean).cwiseAbs2();
  }
  const double dof = std::max(1.0, n - 1.0);
  accel_std = (qa / dof).cwiseSqrt();
  gyro_std = (qg / dof).cwiseSqrt();
}

namespace {

constexpr int kChannels = 6;
constexpr double kAxisRise = 3.0;  // an accelerometer's noise over its reference it may rise to
using ChannelValues = std::array<double, kChannels>;

void check_options(const PoseDetectorOptions& o) {
  if (!(o.window > 0.0) || !(o.min_duration >= 0.0) || !(o.reference_quantile > 0.0) ||
      !(o.reference_quantile < 1.0) || !(o.false_alarm > 0.0) || !(o.false_alarm < 1.0) ||
      !(o.margin >= 1.0) || !(o.edge_sigmas > 0.0))
    throw PoseDetectorError("pose detector: options out of range");
}

// The median interval between readings; times must increase.
double median_interval(const std::vector<ImuReading>& r) {
  std::vector<double> dts(r.size() - 1);
  for (std::size_t k = 1; k < r.size(); ++k) {
    dts[k - 1] = r[k].t - r[k - 1].t;
    if (!(dts[k - 1] > 0.0))
      throw PoseDetectorError("pose detector: times do not increase at reading " +
                              std::to_string(k + 1) + " (t = " + std::to_string(r[k].t) + " s)");
  }
  return quantile_of(dts, 0.5);
}

// Each channel's variance over the window of w = 2h + 1 readings centred on reading i + h, from
// cumulative sums of the channel minus its first reading (keeps the sums of squares small against
// their differences); `floor` is the rounding level of those variances.
struct WindowedVariances {
  std::array<std::vector<double>, kChannels> var;
  /// Half the mean square of consecutive differences over the window: the white noise's
  /// variance, which a smooth motion barely moves (the window's own noise estimate).
  std::array<std::vector<double>, kChannels> white;
  ChannelValues floor{};
};

WindowedVariances windowed_variances(const std::vector<ImuReading>& r, std::size_t w) {
  const std::size_t n = r.size(), h = w / 2;
  const double wd = static_cast<double>(w);
  WindowedVariances out;
  std::vector<double> s(n + 1), s2(n + 1), d2(n + 1);
  for (int c = 0; c < kChannels; ++c) {
    const double x0 = channel(r[0], c);
    s[0] = s2[0] = d2[0] = d2[1] = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double x = channel(r[k], c) - x0;
      s[k + 1] = s[k] + x;
      s2[k + 1] = s2[k] + x * x;
      if (k > 0) d2[k + 1] = d2[k] + std::pow(channel(r[k], c) - channel(r[k - 1], c), 2);
    }
    out.var[c].resize(n - 2 * h);
    out.white[c].resize(n - 2 * h);
    for (std::size_t i = h; i + h < n; ++i) {
      const double sum = s[i + h + 1] - s[i - h], sum2 = s2[i + h + 1] - s2[i - h];
      out.var[c][i - h] = std::max(0.0, (sum2 - sum * sum / wd) / (wd - 1.0));
      // Differences of readings i-h .. i+h: d2 terms i-h+1 .. i+h.
      out.white[c][i - h] = (d2[i + h + 1] - d2[i - h + 1]) / (2.0 * (wd - 1.0));
    }
    out.floor[c] = 100.0 * std::numeric_limits<double>::epsilon() * s2[n] / (wd - 1.0);
  }
  return out;
}

// Which window centres are at rest: the accelerometer (and, with use_gyro, the gyro) variances,
// each divided by its channel's noise reference, summed over the triad, below the threshold.
class RestClassifier {
 public:
  RestClassifier(const WindowedVariances& v, const PoseDetectorOptions& o, double dof)
      : v_(v), o_(o), dof_(dof) {
    is_static.assign(v.var[0].size(), 0);
    threshold = o.margin *
                boost::math::quantile(boost::math::chi_squared(3.0 * dof), 1.0 - o.false_alarm) /
                dof;
  }

  // Two passes: a low quantile of each channel's windowed variances as its noise reference, then
  // the median variance of the windows found at rest (noise-free simulated data rest with zero
  // variance: the floor keeps the ratios finite).
  void run() {
    for (int c = 0; c < kChannels; ++c) {
      if (!(quantile_of(v_.var[c], 0.9) > v_.floor[c]))
        throw PoseDetectorError("pose detector: a channel is constant over the record");
      ref[c] = std::max(quantile_of(v_.var[c], o_.reference_quantile), v_.floor[c]);
    }
    classify();
    const double median_ratio =
        boost::math::quantile(boost::math::chi_squared(dof_), 0.5) / dof_;  // median of chi2/dof
    for (int c = 0; c < kChannels; ++c) {
      std::vector<double> quiet;
      for (std::size_t i = 0; i < is_static.size(); ++i)
        if (is_static[i]) quiet.push_back(v_.var[c][i]);
      ref[c] = std::max(quantile_of(quiet, 0.5) / median_ratio, v_.floor[c]);
    }
    classify();
  }

  double threshold = 0.0;
  ChannelValues ref{};  // noise variance per channel
  std::vector<char> is_static;

 private:
  void classify() {
    std::size_t count = 0;
    for (std::size_t i = 0; i < is_static.size(); ++i) {
      double sa = 0.0, sg = 0.0;
      for (int c = 0; c < 3; ++c) {
        // An accelerometer's noise may rise 2-3x in some orientations (an ADXL355, on one axis
        // or all three): each axis against its reference or, up to kAxisRise^2 times it, the
        // window's own white noise (consecutive differences), which a hand's smooth motion
        // hardly raises while it raises the variance by orders of magnitude.
        const double own = std::clamp(v_.white[c][i], ref[c], kAxisRise * kAxisRise * ref[c]);
        sa += v_.var[c][i] / own;
        sg += v_.var[c + 3][i] / ref[c + 3];
      }
      is_static[i] = sa <= threshold && (!o_.use_gyro || sg <= threshold);
      count += is_static[i] ? 1 : 0;
    }
    if (count == 0)
      throw PoseDetectorError("pose detector: no window is quiet enough to be at rest");
  }

  const WindowedVariances& v_;
  const PoseDetectorOptions& o_;
  double dof_;
};

// Runs of static centres. A pose is the run's centre readings, extended reading by reading
// towards its windows' edges while every channel stays within `edge_sigmas` noise sigmas of the
// run's mean (a window may be static with a slow settling of the hand at its edge). Neighbouring
// runs split by a short disturbance overlap: they are cut at the middle.
std::vector<std::pair<std::size_t, std::size_t>> static_runs(const std::vector<ImuReading>& r,
                                                             const RestClassifier& rest,
                                                             std::size_t h,
                                                             const PoseDetectorOptions& o) {
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  const std::size_t centres = rest.is_static.size();
  for (std::size_t i = 0; i < centres;) {
    if (!rest.is_static[i]) {
      ++i;
      continue;
    }
    std::size_t j = i;
    while (j + 1 < centres && rest.is_static[j + 1]) ++j;
    // Reading indices: centres i + h .. j + h; their windows cover i .. j + 2h.
    std::size_t first = i + h, last = j + h;
    ChannelValues mean{};
    for (std::size_t k = first; k <= last; ++k)
      for (int c = 0; c < kChannels; ++c) mean[c] += channel(r[k], c);
    for (auto& m : mean) m /= static_cast<double>(last - first + 1);
    // Each channel's noise: the record's reference or the run's own, whichever is larger (a
    // pose whose noise rose on one axis keeps its edges).
    ChannelValues noise{};
    for (std::size_t k = first; k <= last; ++k)
      for (int c = 0; c < kChannels; ++c) noise[c] += std::pow(channel(r[k], c) - mean[c], 2);
    for (int c = 0; c < kChannels; ++c)
      noise[c] = std::max(rest.ref[c],
                          noise[c] / static_cast<double>(std::max<std::size_t>(1, last - first)));
    auto quiet = [&](std::size_t k) {
      for (int c = 0; c < (o.use_gyro ? kChannels : 3); ++c)
        if (std::abs(channel(r[k], c) - mean[c]) > o.edge_sigmas * std::sqrt(noise[c]))
          return false;
      return true;
    };
    while (first > i && quiet(first - 1)) --first;
    while (last < j + 2 * h && quiet(last + 1)) ++last;
    runs.emplace_back(first, last);
    i = j + 1;
  }
  for (std::size_t k = 1; k < runs.size(); ++k)
    if (runs[k].first <= runs[k - 1].second) {
      const std::size_t mid = (runs[k].first + runs[k - 1].second) / 2;
      runs[k - 1].second = mid;
      runs[k].first = mid + 1;
    }
  return runs;
}

}  // namespace

PoseDetection detect_poses(const std::vector<ImuReading>& r, const PoseDetectorOptions& o) {
  check_options(o);
  const std::size_t n = r.size();
  if (n < 16)
    throw PoseDetectorError("pose detector: record of " + std::to_string(n) +
                            " readings is too short");
  PoseDetection out;
  out.sample_interval = median_interval(r);
  std::size_t w = std::max<std::size_t>(
      5, static_cast<std::size_t>(std::lround(o.window / out.sample_interval)));
  if (w % 2 == 0) ++w;
  out.window_samples = w;
  if (n < 3 * w)
    throw PoseDetectorError("pose detector: record of " + std::to_string(n) +
                            " readings is shorter than three windows of " + std::to_string(w));

  const WindowedVariances variances = windowed_variances(r, w);
  RestClassifier rest(variances, o, static_cast<double>(w - 1));
  rest.run();
  out.threshold = rest.threshold;
  for (int c = 0; c < 3; ++c) {
    out.accel_noise_variance(c) = rest.ref[c];
    out.gyro_noise_variance(c) = rest.ref[c + 3];
  }
  for (const auto& [first, last] : static_runs(r, rest, w / 2, o)) {
    if (last <= first || r[last].t - r[first].t < o.min_duration) continue;
    Pose p;
    p.index = static_cast<int>(out.poses.size()) + 1;
    p.first = first;
    p.last = last;
    p.t_start = r[first].t;
    p.t_end = r[last].t;
    p.count = last - first + 1;
    reading_statistics(r, first, last, p.accel_mean, p.gyro_mean, p.accel_std, p.gyro_std);
    out.poses.push_back(p);
  }
  return out;
}

}  // namespace sinscal
