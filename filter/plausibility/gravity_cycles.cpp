#include "filter/plausibility/gravity_cycles.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sinscal {

namespace {

// 1st to 99th percentile of a normal spread, in standard deviations.
constexpr double kPercentileSpan = 4.65;
// The smallest relative error of the mean rate judged (a FOG profile's gyro scale range is below
// what the measurement's own approximations leave).
constexpr double kRateFloor = 0.005;

// Sums over the intervals, and over the noise's differences.
struct Sums {
  double n = 0.0, dt = 0.0, dt2 = 0.0;
  double noise = 0.0;  // the intervals' variance the noise gives, summed
};

// Each turn's largest rate (less its rests' rate), the log read once.
std::vector<double> peaks(const LogFormat& log, const std::vector<TurnTiming>& turns) {
  std::vector<double> out(turns.size(), 0.0);
  LogReader reader(log);
  reader.skip_bad_samples([](const BadSampleError&) {});
  ImuSample s;
  std::size_t k = 0, i = 0;
  while (reader.next(s)) {
    if (!(s.dt > 0.0)) continue;
    while (i < turns.size() && k >= turns[i].last) ++i;
    if (i < turns.size() && k >= turns[i].first)
      out[i] = std::max(out[i], (s.dtheta_b / s.dt - turns[i].rest_omega).norm());
    ++k;
  }
  return out;
}

// One reading inside a turn: its rate (less the rests') and specific force.
struct Point {
  Eigen::Vector3d w = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::Zero();
};

// Two neighbouring readings of a turn at speed: the interval between them from gravity's step
// across their mean axis, added to the sums (false: not usable, gravity along the axis).
bool add_interval(const Point& p, const Point& q, const TurnTiming& t, Sums& s) {
  const Eigen::Vector3d mean = 0.5 * (p.w + q.w);
  const double rate = mean.norm();
  const Eigen::Vector3d axis = mean / rate;
  const Eigen::Vector3d a = p.f - p.f.dot(axis) * axis, b = q.f - q.f.dot(axis) * axis;
  if (!(a.norm() > 0.5 * p.f.norm() && b.norm() > 0.5 * q.f.norm())) return false;
  const double dt = std::atan2(a.cross(b).norm(), a.dot(b)) / rate;
  s.n += 1.0;
  s.dt += dt;
  s.dt2 += dt * dt;
  // The noise (the rests' per axis): each reading's direction across the axis moves by
  // sigma_f / |f across|, the step by both; the rate, a mean of two readings, by sigma_w^2 / 2.
  const double fperp2 = 0.5 * (a.squaredNorm() + b.squaredNorm());
  s.noise += (2.0 * t.rest_var_f / fperp2 + dt * dt * 0.5 * t.rest_var_omega) / (rate * rate);
  return true;
}

}  // namespace

bool GravityCycleIntervals::irregular() const {
  return intervals > 0 &&
         jitter >
             PlausibilityLimits::kIntegratingIntervalSpread / kPercentileSpan + 4.0 * jitter_sigma;
}

GravityCycleIntervals gravity_cycle_intervals(const LogFormat& log,
                                              const std::vector<TurnTiming>& turns) {
  GravityCycleIntervals g;
  const std::vector<double> peak = peaks(log, turns);
  Sums s;
  std::vector<bool> used(turns.size(), false);
  LogReader reader(log);
  reader.skip_bad_samples([](const BadSampleError&) {});
  ImuSample x;
  std::size_t k = 0, i = 0;
  bool have = false;  // the previous reading is in the same turn, at speed
  Point previous;
  while (reader.next(x)) {
    if (!(x.dt > 0.0)) continue;
    if (g.nominal == 0.0) g.nominal = x.dt;
    while (i < turns.size() && k >= turns[i].last) {
      ++i;
      have = false;
    }
    ++k;
    if (i == turns.size() || k - 1 < turns[i].first) continue;
    const Point p{x.dtheta_b / x.dt - turns[i].rest_omega, x.dv_b / x.dt};
    const bool fast = p.w.norm() > 0.5 * peak[i];
    if (fast && have && add_interval(previous, p, turns[i], s)) used[i] = true;
    have = fast;
    previous = p;
  }
  for (const bool u : used) g.turns += u ? 1 : 0;
  if (s.n < 10.0) return g;
  g.intervals = static_cast<std::size_t>(s.n);
  g.mean = s.dt / s.n;
  const double var = std::max(0.0, s.dt2 / s.n - g.mean * g.mean);
  const double noise_var = s.noise / s.n;
  g.noise = std::sqrt(noise_var) / g.mean;
  const double excess = std::max(0.0, var - noise_var);
  g.jitter = std::sqrt(excess) / g.mean;
  // The sample variance's sigma (normal: var sqrt(2 / n)), carried to the relative std.
  const double var_sigma = var * std::sqrt(2.0 / s.n);
  g.jitter_sigma =
      excess > 0.0 ? 0.5 * var_sigma / std::sqrt(excess) / g.mean : std::sqrt(var_sigma) / g.mean;
  g.mean_sigma = std::sqrt(var / s.n);
  return g;
}

PlausibilityCheck check_gravity_cycle_intervals(const GravityCycleIntervals& g,
                                                const LogFormat& log, double relative) {
  PlausibilityCheck c{"sample intervals from gravity", true, ""};
  if (g.intervals == 0) {
    c.detail = log.file + ": no turn across gravity to measure the readings' intervals by";
    return c;
  }
  char b[600];
  std::snprintf(b, sizeof b,
                "%s: without a time column, the readings' intervals measured from gravity's cycles "
                "in %d turn(s) across it (%zu intervals): mean %.4g ms +- %.2g (the session's rate "
                "says %.4g ms: %.4g Hz against %.4g Hz), spread %.3g %% +- %.2g of the mean beyond "
                "the noise's %.3g %%",
                log.file.c_str(), g.turns, g.intervals, 1e3 * g.mean, 1e3 * g.mean_sigma,
                1e3 * g.nominal, 1.0 / g.mean, 1.0 / g.nominal, 100.0 * g.jitter,
                100.0 * g.jitter_sigma, 100.0 * g.noise);
  c.detail = b;
  const double off = std::abs(g.mean - g.nominal);
  // The gyros' scale error the profile allows, at least kRateFloor (the Earth rate turning in
  // the body frame over a turn at tens of deg/s, second-order terms of the step).
  const bool rate_off = off > 4.0 * g.mean_sigma + std::max(relative, kRateFloor) * g.nominal;
  if (!g.irregular() && !rate_off) return c;
  c.passed = false;
  c.detail += g.irregular() ? ": the intervals are irregular (tolerated: a 1st-99th percentile "
                              "spread of 2 %)"
                            : ": the log's rate is not the session's";
  c.detail +=
      "; the integrating methods need the true intervals; the means need none "
      "(--method rate-table)";
  return c;
}

}  // namespace sinscal
