#include "filter/kalman/motion_from_data.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "models/attitude.hpp"
#include "rig/io/log_io.hpp"
#include "rig/plan.hpp"

namespace sinscal {

namespace {

// How far a move's window reaches into the dwells around it (at most to their middles): slow
// turns of a table below the plan's rate ended up to 11 s late on seed8; the samples held grow
// with it, not with the dwells.
constexpr double kReach = 20.0;             // s
constexpr double kBin = 0.1;                // s, bins of the offset search
constexpr double kCorrelationSpan = 600.0;  // s of plan the offset search compares
constexpr double kOffsetCorrelation = 0.8;  // the least correlation of a shift taken
constexpr double kOffsetGain = 0.05;        // over the correlation without a shift
constexpr int kOffsetMoves = 3;             // the plan\'s moves the shifted log must hold

// A measured profile: angle, rate and angular acceleration at nodes (s from the commanded
// start), interpolated by cubic Hermite (angle from angle and rate, rate from rate and
// acceleration); 0 before the first node, the total after the last.
class SampledProfile : public ProfileRealization {
 public:
  SampledProfile(std::vector<double> t, std::vector<double> angle, std::vector<double> rate,
                 std::vector<double> accel, double total)
      : t_(std::move(t)),
        angle_(std::move(angle)),
        rate_(std::move(rate)),
        accel_(std::move(accel)),
        total_(total) {}
  void eval(double t, double& angle, double& rate, double& accel) const override {
    if (t <= t_.front()) {
      angle = rate = accel = 0.0;
      return;
    }
    if (t >= t_.back()) {
      angle = total_;
      rate = accel = 0.0;
      return;
    }
    const auto i =
        static_cast<std::size_t>(std::upper_bound(t_.begin(), t_.end(), t) - t_.begin()) - 1;
    const double h = t_[i + 1] - t_[i], s = (t - t_[i]) / h;
    const double h00 = (1 + 2 * s) * (1 - s) * (1 - s), h10 = s * (1 - s) * (1 - s);
    const double h01 = s * s * (3 - 2 * s), h11 = s * s * (s - 1);
    angle = h00 * angle_[i] + h10 * h * rate_[i] + h01 * angle_[i + 1] + h11 * h * rate_[i + 1];
    rate = h00 * rate_[i] + h10 * h * accel_[i] + h01 * rate_[i + 1] + h11 * h * accel_[i + 1];
    accel = (1 - s) * accel_[i] + s * accel_[i + 1];
  }
  double begin() const override { return t_.front(); }
  double end() const override { return t_.back(); }
  std::vector<double> knots() const override { return {t_.front(), t_.back()}; }

 private:
  std::vector<double> t_, angle_, rate_, accel_;
  double total_;
};

// Zero-phase Gaussian smoothing of samples at (nearly) uniform spacing dt, sigma in s.
std::vector<double> smooth(const std::vector<double>& x, double dt, double sigma) {
  const int half = std::max(1, static_cast<int>(std::ceil(4.0 * sigma / dt)));
  std::vector<double> w(static_cast<std::size_t>(half) + 1);
  for (int k = 0; k <= half; ++k)
    w[static_cast<std::size_t>(k)] = std::exp(-0.5 * std::pow(k * dt / sigma, 2));
  std::vector<double> out(x.size());
  const int n = static_cast<int>(x.size());
  for (int i = 0; i < n; ++i) {
    double sum = 0.0, norm = 0.0;
    for (int k = -half; k <= half; ++k) {
      const int j = i + k;
      if (j < 0 || j >= n) continue;
      const double wk = w[static_cast<std::size_t>(std::abs(k))];
      sum += wk * x[static_cast<std::size_t>(j)];
      norm += wk;
    }
    out[static_cast<std::size_t>(i)] = sum / norm;
  }
  return out;
}

struct Sample {
  double t = 0.0;  // plan time at the middle of the interval
  double dt = 0.0;
  Eigen::Vector3d omega_ib_b = Eigen::Vector3d::Zero();  // compensated with the start model
};

// Reads the log, calling `take(sample)` with the plan time of each (under `offset`).
template <typename F>
void read_log(const Session& session, const ImuErrorModel& model, double offset, F take) {
  LogReader reader(session.log);
  reader.skip_bad_samples([](const BadSampleError&) {});
  ImuSample s;
  const ImuErrorModel::LinearInverses inv = model.linear_inverses();
  while (reader.next(s)) {
    if (!(s.dt > 0.0)) continue;
    Sample x;
    x.t = s.t - 0.5 * s.dt - offset;
    x.dt = s.dt;
    Eigen::Vector3d f;
    model.compensate(s.dtheta_b / s.dt, s.dv_b / s.dt, Eigen::Vector3d::Zero(), x.omega_ib_b, f,
                     x.t, nullptr, &inv);
    take(x);
  }
}

// The rotation rate of the motion relative to the navigation frame, its magnitude.
double plan_rate(const Motion& m, double t) { return m.at(t).omega_nb_b.norm(); }

// The start-time offset: the rate magnitudes' cross-correlation over +-kOffsetSearch.
void find_offset(const Session& session, const CalibratorOptions& o, const Motion& plan,
                 DataMotion& out) {
  const double span = std::min(plan.duration(), kCorrelationSpan);
  const auto bins = static_cast<std::size_t>(std::ceil((span + 2.0 * kOffsetSearch) / kBin));
  std::vector<double> sum(bins, 0.0), count(bins, 0.0);
  const double first = -kOffsetSearch;  // plan time of bin 0
  const ImuErrorModel model = o.initial_model.value_or(ImuErrorModel{});
  double log_first = 1e300, log_last = -1e300;  // plan time the log covers (unshifted)
  read_log(session, model, o.time_offset, [&](const Sample& x) {
    log_first = std::min(log_first, x.t);
    log_last = std::max(log_last, x.t);
    const double k = std::floor((x.t - first) / kBin);
    if (k < 0.0 || k >= static_cast<double>(bins)) return;
    sum[static_cast<std::size_t>(k)] += x.omega_ib_b.norm();
    count[static_cast<std::size_t>(k)] += 1.0;
  });
  std::vector<double> data(bins, 0.0);
  std::vector<double> present;
  for (std::size_t k = 0; k < bins; ++k)
    if (count[k] > 0.0) {
      data[k] = sum[k] / count[k];
      present.push_back(data[k]);
    }
  if (present.empty()) return;
  std::nth_element(present.begin(),
                   present.begin() + static_cast<std::ptrdiff_t>(present.size() / 2),
                   present.end());
  const double floor_rate = present[present.size() / 2];  // at rest: Earth rate and biases
  for (std::size_t k = 0; k < bins; ++k) data[k] = count[k] > 0.0 ? data[k] - floor_rate : 0.0;
  const auto n_plan = static_cast<std::size_t>(std::floor(span / kBin));
  std::vector<double> p(n_plan);
  double pp = 0.0;
  for (std::size_t k = 0; k < n_plan; ++k) {
    p[k] = plan_rate(plan, (static_cast<double>(k) + 0.5) * kBin);
    pp += p[k] * p[k];
  }
  if (!(pp > 0.0)) return;
  const auto lags = static_cast<std::ptrdiff_t>(std::round(kOffsetSearch / kBin));
  const auto zero = static_cast<std::size_t>(lags);  // bin of plan time 0
  std::vector<double> score(static_cast<std::size_t>(2 * lags + 1), 0.0);
  std::ptrdiff_t best = 0;
  double best_score = -1e300;
  for (std::ptrdiff_t lag = -lags; lag <= lags; ++lag) {
    double s = 0.0, dd = 0.0;
    for (std::size_t k = 0; k < n_plan; ++k) {
      const double d = data[zero + k + static_cast<std::size_t>(lag + lags) - zero];
      s += p[k] * d;
      dd += d * d;
    }
    const double c = dd > 0.0 ? s / std::sqrt(pp * dd) : 0.0;
    score[static_cast<std::size_t>(lag + lags)] = c;
    if (c > best_score) {
      best_score = c;
      best = lag;
    }
  }
  // Parabolic refinement between the neighbours of the best bin.
  double shift = static_cast<double>(best);
  if (best > -lags && best < lags) {
    const double a = score[static_cast<std::size_t>(best - 1 + lags)];
    const double b = score[static_cast<std::size_t>(best + lags)];
    const double c = score[static_cast<std::size_t>(best + 1 + lags)];
    const double den = a - 2.0 * b + c;
    if (den < 0.0) shift += 0.5 * (a - c) / den;
  }
  out.correlation = best_score;
  // A shift must match the plan well and clearly better than none (a log that ends early, with
  // one turn, matches any turn of the plan as well as its own).
  const double at_zero = score[static_cast<std::size_t>(lags)];
  if (best_score < kOffsetCorrelation || best_score < at_zero + kOffsetGain) return;
  // ... and hold enough of the plan's moves for the match to mean anything.
  int covered = 0;
  for (const auto& seg : plan.segments())
    if (!seg.is_static() && seg.t0 >= log_first - shift * kBin && seg.t1 <= log_last - shift * kBin)
      ++covered;
  if (covered < kOffsetMoves) return;
  if (std::abs(shift * kBin) > kOffsetResolution) out.time_offset = o.time_offset + shift * kBin;
}

// What one move's window holds.
struct MoveWindow {
  std::size_t segment = 0;
  double a = 0.0, b = 0.0;  // plan time
  // Held compactly (single precision rates): memory grows with the moves, not the dwells.
  struct Held {
    double t = 0.0;
    float dt = 0.0F;
    Eigen::Vector3f omega_ib_b = Eigen::Vector3f::Zero();
  };
  std::vector<Held> samples;
  // The adjacent dwells' means of omega_ib_b less the Earth rate (bias), and their weights.
  Eigen::Vector3d bias_sum = Eigen::Vector3d::Zero();
  double bias_count = 0.0;
};

}  // namespace

double noise_smoothing(double density, double dt, double peak, int derivative) {
  const double bound = derivative == 0 ? kRateSmoothing : kAccelSmoothing;
  if (!(peak > 0.0)) return bound;
  const double e = kSmoothingNoise * peak;
  const double sigma = derivative == 0
                           ? density * density / (2.0 * std::sqrt(M_PI) * e * e)
                           : std::pow(density / (2.0 * std::pow(M_PI, 0.25) * e), 2.0 / 3.0);
  return std::clamp(sigma, dt, bound);
}

std::string DataMotion::summary() const {
  std::ostringstream m;
  char buf[200];
  if (offset_found()) {
    std::snprintf(buf, sizeof buf, "the plan starts at t = %.3f s of the log, not %.3f s; ",
                  time_offset, session_offset);
    m << buf;
  }
  const int n = departing();
  if (n == 0) {
    m << "the turns follow the plan's profile (within " << kFollowTolerance / units::deg << " deg)";
    return m.str();
  }
  double largest = 0.0, shift = 0.0, over = 0.0;
  for (const auto& d : moves) {
    if (d.follows) continue;
    largest = std::max(largest, d.largest);
    if (std::abs(d.start_shift) > std::abs(shift)) shift = d.start_shift;
    over = std::max(over, d.overshoot);
  }
  std::snprintf(buf, sizeof buf,
                "%d of %zu turns depart from the plan's profile: up to %.3g deg from the plan's "
                "angle, %.3g s late at mid-turn, %.3g deg of overshoot; the filter follows the "
                "data's motion",
                n, moves.size(), largest / units::deg, shift, over / units::deg);
  m << buf;
  return m.str();
}

namespace {

// The moves of the log under `out.time_offset`: their departures, the reference motion and the
// dwells where the data are still.
// NOLINTNEXTLINE(readability-function-size): each move analysed in one loop (to be split)
void analyse_moves(const Session& session, const CalibratorOptions& o, const Motion& plan,
                   DataMotion& out) {
  out.moves.clear();
  const auto& segs = plan.segments();
  const Earth& earth = Earth::wgs84();
  const Eigen::Vector3d omega_ie_n = earth.omega_ie_n(session.site.lat_rad);

  // The windows: from the middle of the dwell before a move to the middle of the dwell after it;
  // consecutive moves without a dwell meet at their boundary.
  std::vector<MoveWindow> windows;
  for (std::size_t i = 0; i < segs.size(); ++i) {
    if (segs[i].is_static()) continue;
    MoveWindow w;
    w.segment = i;
    w.a = segs[i].t0;
    w.b = segs[i].t1;
    if (i > 0 && segs[i - 1].is_static())
      w.a = std::max(segs[i - 1].t0 + 0.5 * (segs[i - 1].t1 - segs[i - 1].t0), w.a - kReach);
    if (i + 1 < segs.size() && segs[i + 1].is_static())
      w.b = std::min(segs[i + 1].t0 + 0.5 * (segs[i + 1].t1 - segs[i + 1].t0), w.b + kReach);
    windows.push_back(std::move(w));
  }
  // The dwells' bias: each dwell's samples away from the moves (its middle
  // half), less the Earth rate in the plan's attitude.
  struct DwellMean {
    double a = 0.0, b = 0.0;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double count = 0.0;
    Eigen::Vector3d earth_b = Eigen::Vector3d::Zero();
  };
  std::vector<DwellMean> dwell_means(segs.size());
  for (std::size_t i = 0; i < segs.size(); ++i) {
    if (!segs[i].is_static()) continue;
    const double len = segs[i].t1 - segs[i].t0;
    const double inset = 0.25 * len;  // the middle half: slow turns reach far into a dwell
    dwell_means[i].a = segs[i].t0 + inset;
    dwell_means[i].b = segs[i].t1 - inset;
    dwell_means[i].earth_b = segs[i].C_b_n_start.transpose() * omega_ie_n;
  }
  {
    std::size_t wi = 0, di = 0;
    const ImuErrorModel model = o.initial_model.value_or(ImuErrorModel{});
    read_log(session, model, out.time_offset, [&](const Sample& x) {
      while (wi < windows.size() && x.t > windows[wi].b) ++wi;
      if (wi < windows.size() && x.t >= windows[wi].a)
        windows[wi].samples.push_back({x.t, static_cast<float>(x.dt), x.omega_ib_b.cast<float>()});
      while (di < segs.size() && segs[di].t1 < x.t) ++di;
      if (di < segs.size() && segs[di].is_static() && x.t >= dwell_means[di].a &&
          x.t <= dwell_means[di].b) {
        dwell_means[di].sum += x.omega_ib_b - dwell_means[di].earth_b;
        dwell_means[di].count += 1.0;
      }
    });
  }

  std::vector<MotionSegment> ref_segs = segs;
  // Where the data's motion reaches (plan time), by segment: the dwells' updates keep clear.
  std::vector<double> reach_begin(segs.size()), reach_end(segs.size());
  for (std::size_t i = 0; i < segs.size(); ++i) {
    reach_begin[i] = segs[i].t0;
    reach_end[i] = segs[i].t1;
  }
  int move = 0;
  for (MoveWindow& w : windows) {
    ++move;
    const MotionSegment& seg = segs[w.segment];
    MoveDeparture d;
    d.move = move;
    d.t_plan = seg.t0;
    d.plan_begins = seg.t0;
    d.plan_ends = seg.t1;
    d.label = "turn " + std::to_string(move) + " at t = " + std::to_string(seg.t0) + " s";
    d.plan_turned = std::abs(seg.alpha.angle()) + std::abs(seg.beta.angle());
    const std::size_t n = w.samples.size();
    if (n < 8) {  // the log does not cover it: nothing to say
      out.moves.push_back(d);
      continue;
    }
    // The bias: the adjacent dwells' means (either, when only one is measured).
    Eigen::Vector3d bias = Eigen::Vector3d::Zero();
    double weight = 0.0;
    for (std::size_t j : {w.segment - 1, w.segment + 1})
      if (j < segs.size() && dwell_means[j].count > 0.0) {
        bias += dwell_means[j].sum;
        weight += dwell_means[j].count;
      }
    if (weight > 0.0) bias /= weight;
    // The rates on the move's axes: omega_nb_b = alpha' u_b + beta' b, u_b = C(beta)^T C_s^T a_n.
    const bool has_alpha = seg.alpha.angle() != 0.0, has_beta = seg.beta.angle() != 0.0;
    std::vector<double> ra(n, 0.0), rb(n, 0.0);
    double beta = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const MoveWindow::Held& x = w.samples[k];
      const KinematicState p = plan.at(x.t);
      const Eigen::Vector3d omega_nb =
          x.omega_ib_b.cast<double>() - bias - p.C_b_n.transpose() * omega_ie_n;
      const Eigen::Vector3d u_b =
          (seg.C_b_n_start * rotation(seg.axis_b, beta)).transpose() * seg.axis_n;
      if (has_alpha && has_beta) {
        Eigen::Matrix<double, 3, 2> A;
        A.col(0) = u_b;
        A.col(1) = seg.axis_b;
        const Eigen::Vector2d r = (A.transpose() * A).ldlt().solve(A.transpose() * omega_nb);
        ra[k] = r(0);
        rb[k] = r(1);
      } else if (has_alpha) {
        ra[k] = u_b.dot(omega_nb);
      } else {
        rb[k] = seg.axis_b.dot(omega_nb);
      }
      beta += rb[k] * x.dt;
    }
    const double dt = (w.samples.back().t - w.samples.front().t) / static_cast<double>(n - 1);
    // Smoothed rates; the motion where the rate stands above its noise at the window's ends.
    // The gyros' white noise and quantization as one density (rad/s/sqrt(Hz)).
    const TriadNoise& gn = o.noise.gyro;
    const double density = std::sqrt(gn.white * gn.white + gn.quantum * gn.quantum / 12.0 / dt);
    const double peak_rate =
        std::max(std::abs(seg.alpha.peak_rate()), std::abs(seg.beta.peak_rate()));
    const double peak_accel =
        std::max(std::abs(seg.alpha.acceleration()), std::abs(seg.beta.acceleration()));
    const double rate_sigma = noise_smoothing(density, dt, peak_rate, 0);
    const double accel_sigma = noise_smoothing(density, dt, peak_accel, 1);
    const std::vector<double> sa = smooth(ra, dt, rate_sigma), sb = smooth(rb, dt, rate_sigma);
    std::vector<double> mag(n);
    for (std::size_t k = 0; k < n; ++k) mag[k] = std::hypot(sa[k], sb[k]);
    // The noise from the window's ends that lie in a dwell (a move right after another shares
    // its boundary, where the table may still turn).
    const std::size_t edge = std::min<std::size_t>(n / 4, static_cast<std::size_t>(1.0 / dt));
    const bool dwell_before = w.segment > 0 && segs[w.segment - 1].is_static();
    const bool dwell_after = w.segment + 1 < segs.size() && segs[w.segment + 1].is_static();
    double noise = 0.0, peak = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      if ((k < edge && dwell_before) || (k + edge >= n && dwell_after))
        noise = std::max(noise, mag[k]);
      peak = std::max(peak, mag[k]);
    }
    const double threshold = std::max(2.0 * noise, 2e-3 * peak);
    std::size_t k0 = n, k1 = 0;
    for (std::size_t k = 0; k < n; ++k)
      if (mag[k] > threshold) {
        k0 = std::min(k0, k);
        k1 = k;
      }
    if (k0 >= k1 || !(peak > 0.0)) {  // no motion found in the data: the plan's
      out.moves.push_back(d);
      continue;
    }
    // The support: the motion found and the smoothing's reach, within the window.
    d.begins = w.samples[k0].t;
    d.ends = w.samples[k1].t;
    d.end_shift = d.ends - d.plan_ends;
    const auto reach = static_cast<std::size_t>(std::ceil(4.0 * accel_sigma / dt));
    k0 = k0 > reach && dwell_before ? k0 - reach : 0;
    k1 = dwell_after ? std::min(n - 1, k1 + reach) : n - 1;
    auto profile = [&](const std::vector<double>& raw, const std::vector<double>& smoothed,
                       double total, double& turned) -> std::shared_ptr<const SampledProfile> {
      std::vector<double> t, angle, rate, accel;
      const std::vector<double> slow = smooth(raw, dt, accel_sigma);
      double a = 0.0;
      for (std::size_t k = k0; k <= k1; ++k) {
        const double r = (k == k0 || k == k1) ? 0.0 : smoothed[k];
        if (k > k0) a += 0.5 * (rate.back() + r) * (w.samples[k].t - w.samples[k - 1].t);
        t.push_back(w.samples[k].t - seg.t0);
        angle.push_back(a);
        rate.push_back(r);
        const std::size_t lo = k > k0 ? k - 1 : k, hi = k < k1 ? k + 1 : k;
        accel.push_back(hi > lo && k != k0 && k != k1
                            ? (slow[hi] - slow[lo]) / (w.samples[hi].t - w.samples[lo].t)
                            : 0.0);
      }
      turned = a;
      if (!(std::abs(a) > 0.0) || total == 0.0) return nullptr;
      const double scale = total / a;  // the gyros' scale errors out: the plan's angle
      for (std::size_t k = 0; k < t.size(); ++k) {
        angle[k] *= scale;
        rate[k] *= scale;
        accel[k] *= scale;
      }
      return std::make_shared<const SampledProfile>(t, angle, rate, accel, total);
    };
    double turned_a = 0.0, turned_b = 0.0;
    const auto pa = has_alpha ? profile(ra, sa, seg.alpha.angle(), turned_a) : nullptr;
    const auto pb = has_beta ? profile(rb, sb, seg.beta.angle(), turned_b) : nullptr;
    d.turned = std::abs(turned_a) + std::abs(turned_b);
    // A turn the data do not make as the plan says (sign, size beyond 20 %) is not this move:
    // the plan's profile stays (the plausibility gate and the filter judge the mismatch).
    const bool same_turn = (!has_alpha || (pa && turned_a * seg.alpha.angle() > 0.0 &&
                                           std::abs(turned_a / seg.alpha.angle() - 1.0) < 0.2)) &&
                           (!has_beta || (pb && turned_b * seg.beta.angle() > 0.0 &&
                                          std::abs(turned_b / seg.beta.angle() - 1.0) < 0.2));
    if (!same_turn) {
      out.moves.push_back(d);
      continue;
    }
    MotionSegment data_seg = seg;
    if (pa) data_seg.alpha = AngleProfile(seg.alpha.commanded(), pa);
    if (pb) data_seg.beta = AngleProfile(seg.beta.commanded(), pb);
    // The data's angles for the comparisons: the unsmoothed rates integrated over the motion
    // found (the smoothing would round the turns' corners by sigma^2 / 2 times the
    // acceleration, 0.0125 deg on rot19), scaled to the plan's angle.
    std::array<std::vector<double>, 2> raw;
    for (std::size_t j = 0; j < 2; ++j) {
      const std::vector<double>& r = j == 0 ? ra : rb;
      const double total = j == 0 ? seg.alpha.angle() : seg.beta.angle();
      raw[j].assign(n, 0.0);
      double a = 0.0;
      for (std::size_t k = k0 + 1; k <= k1; ++k) {
        a += 0.5 * (r[k - 1] + r[k]) * (w.samples[k].t - w.samples[k - 1].t);
        raw[j][k] = a;
      }
      const double scale = a != 0.0 ? total / a : 0.0;
      for (std::size_t k = 0; k < n; ++k) raw[j][k] = k > k1 ? total : raw[j][k] * scale;
    }
    auto data_angle = [&](const AngleProfile* pr, std::size_t k) {
      return raw[pr == &data_seg.alpha ? 0 : 1][k];
    };
    // The departure: the data's angles against the plan's over the window.
    double half_data = 0.0, half_plan = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double tau = w.samples[k].t - seg.t0;
      double a1, a2, r2, c2, da = 0.0;
      double prog_data = 0.0, prog_plan = 0.0;
      for (const auto* pr : {&data_seg.alpha, &data_seg.beta}) {
        if (pr->angle() == 0.0) continue;
        a1 = data_angle(pr, k);
        pr->commanded().eval(tau, a2, r2, c2);
        da = std::max(da, std::abs(a1 - a2));
        d.overshoot = std::max(d.overshoot, std::abs(a1) - std::abs(pr->angle()));
        prog_data += std::abs(a1);
        prog_plan += std::abs(a2);
      }
      d.largest = std::max(d.largest, da);
      const double half = 0.5 * d.plan_turned;
      if (half_data == 0.0 && prog_data >= half) half_data = tau;
      if (half_plan == 0.0 && prog_plan >= half) half_plan = tau;
    }
    d.start_shift = half_data - half_plan;
    // The shift that best lays the plan's profile over the data's (Gauss-Newton on the angle
    // residuals), and what remains after it: a pure shift of the log leaves nothing.
    auto residuals = [&](double shift, auto&& take) {  // take(data - plan, plan rate)
      for (std::size_t k = 0; k < n; ++k) {
        const double tau = w.samples[k].t - seg.t0;
        for (const auto* pr : {&data_seg.alpha, &data_seg.beta}) {
          if (pr->angle() == 0.0) continue;
          double a2, r2, c2;
          pr->commanded().eval(tau - shift, a2, r2, c2);
          take(data_angle(pr, k) - a2, r2);
        }
      }
    };
    double shift = d.start_shift;
    for (int iter = 0; iter < 8; ++iter) {
      double num = 0.0, den = 0.0;
      residuals(shift, [&](double r, double rate) {
        num += rate * r;
        den += rate * rate;
      });
      if (!(den > 0.0)) break;
      shift -= num / den;
    }
    d.fitted_shift = shift;
    residuals(shift, [&](double r, double) {
      d.shift_residual = std::max(d.shift_residual, std::abs(r));
    });
    d.follows = d.largest <= kFollowTolerance;
    if (!d.follows) {
      ref_segs[w.segment] = data_seg;
      reach_begin[w.segment] = std::min(seg.t0, seg.t0 + data_seg.alpha.begin());
      reach_begin[w.segment] = std::min(reach_begin[w.segment], seg.t0 + data_seg.beta.begin());
      reach_end[w.segment] =
          std::max({seg.t1, seg.t0 + data_seg.alpha.end(), seg.t0 + data_seg.beta.end()});
    }
    out.moves.push_back(d);
  }
  out.reference = std::make_shared<const Motion>(session.site, ref_segs, plan.dwells());
  // The dwells where the data are still: after the motion before them, before the one after.
  auto timeline = std::make_shared<PlanTimeline>(PlanTimeline::of(session.plan, session.site));
  std::size_t dwell = 0;
  for (std::size_t i = 0; i < segs.size() && dwell < timeline->dwells.size(); ++i) {
    if (!segs[i].is_static()) continue;
    PlanDwell& pd = timeline->dwells[dwell++];
    if (i > 0) pd.t_start = std::max(pd.t_start, reach_end[i - 1]);
    if (i + 1 < segs.size()) pd.t_end = std::min(pd.t_end, reach_begin[i + 1]);
    pd.t_end = std::max(pd.t_end, pd.t_start);
  }
  out.timeline = timeline;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

}  // namespace

DataMotion motion_from_data(const Session& session, const CalibratorOptions& o) {
  DataMotion out;
  out.session_offset = out.time_offset = o.time_offset;
  const Motion plan = build_motion(session.plan, session.site);
  // The coarse offset (the rate magnitudes' correlation) brings each move into its window.
  find_offset(session, o, plan, out);
  analyse_moves(session, o, plan, out);
  // The offset proper. A pure shift of the log moves each turn's beginning, middle and end
  // alike: the middles' median is the rest of the offset. Otherwise the turns have their own
  // timing (slower, lagging, smoothed turns): the correlation's shift belongs to the turns'
  // centres, not to the log, and the offset is where the turns begin (when a shift was found).
  std::vector<double> begin, fitted, residual;
  for (const auto& m : out.moves) {
    if (m.follows || m.ends <= m.begins) continue;
    begin.push_back(m.begins - m.plan_begins);
    fitted.push_back(m.fitted_shift);
    residual.push_back(m.shift_residual);
  }
  if (fitted.empty()) return out;
  double shift = 0.0;
  if (median(residual) <= kFollowTolerance)
    shift = median(fitted);
  else if (out.offset_found())
    shift = median(begin);
  if (std::abs(shift) < 1e-4) return out;
  out.time_offset += shift;
  // Turns with their own timing locate the log's start to their detection only (0.1 s).
  if (median(residual) > kFollowTolerance &&
      std::abs(out.time_offset - out.session_offset) < kTimingResolution)
    out.time_offset = out.session_offset;
  if (!out.offset_found()) out.time_offset = out.session_offset;
  analyse_moves(session, o, plan, out);
  return out;
}

}  // namespace sinscal
