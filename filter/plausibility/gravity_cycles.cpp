#include "filter/plausibility/gravity_cycles.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <Eigen/QR>
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

// One reading inside a turn: its rate (less the rests') and specific force; whether the reading
// before it is the turn's too, at speed (an interval between them).
struct Point {
  Eigen::Vector3d w = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::Zero();
  bool after_fast = false;
};

// The specific force's track in the plane across a turn's axis: a circle for a perfect
// accelerometer, an ellipse off the origin for one with a bias (its centre), scale factors and
// misalignments (its shape): the conic A x^2 + B xy + C y^2 + D x + E y = 1 fitted by least
// squares; `to_circle` maps a point less `centre` onto a circle on which gravity's angle advances
// with the turn's.
struct Track {
  Eigen::Vector3d axis, e1, e2;
  Eigen::Vector2d centre;
  Eigen::Matrix2d to_circle;
  double radius2 = 0.0;  // the mean squared distance from the centre, (m/s^2)^2
  Eigen::Vector2d in_plane(const Eigen::Vector3d& f) const { return {f.dot(e1), f.dot(e2)}; }
};

bool fit_track(const std::vector<Point>& points, Track& t) {
  if (points.size() < 12) return false;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& p : points) sum += p.w;
  t.axis = sum.normalized();
  t.e1 = t.axis.unitOrthogonal();
  t.e2 = t.axis.cross(t.e1);
  Eigen::MatrixXd A(static_cast<Eigen::Index>(points.size()), 5);
  for (Eigen::Index k = 0; k < A.rows(); ++k) {
    const Eigen::Vector2d q = t.in_plane(points[static_cast<std::size_t>(k)].f);
    A.row(k) << q.x() * q.x(), q.x() * q.y(), q.y() * q.y(), q.x(), q.y();
  }
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(Eigen::VectorXd::Ones(A.rows()));
  Eigen::Matrix2d Q;
  Q << c(0), 0.5 * c(1), 0.5 * c(1), c(2);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(Q);
  if (!(eig.eigenvalues().minCoeff() > 0.0)) return false;  // not an ellipse: no turn across g
  t.centre = -0.5 * Q.ldlt().solve(Eigen::Vector2d(c(3), c(4)));
  t.to_circle = eig.operatorSqrt();
  t.radius2 = 0.0;
  for (const auto& p : points) t.radius2 += (t.in_plane(p.f) - t.centre).squaredNorm();
  t.radius2 /= static_cast<double>(points.size());
  return true;
}

// The intervals of one turn's readings at speed: gravity's step about the track's centre, on the
// circle, over the gyros' rate about the axis, added to the sums (false: no usable track).
bool add_turn(const std::vector<Point>& points, const TurnTiming& turn, Sums& s) {
  Track t;
  if (!fit_track(points, t)) return false;
  // Gravity across the axis above half its magnitude: a turn about a tilted axis is still one.
  if (!(t.radius2 > 0.25 * points.front().f.squaredNorm())) return false;
  for (std::size_t k = 1; k < points.size(); ++k) {
    if (!points[k].after_fast) continue;
    const Eigen::Vector2d a = t.to_circle * (t.in_plane(points[k - 1].f) - t.centre),
                          b = t.to_circle * (t.in_plane(points[k].f) - t.centre);
    const double rate = 0.5 * (points[k - 1].w + points[k].w).dot(t.axis);
    if (!(rate > 0.0)) continue;
    // Gravity turns in the body against the body's turn: its angle about the axis falls.
    const double dt = -std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b)) / rate;
    s.n += 1.0;
    s.dt += dt;
    s.dt2 += dt * dt;
    // The noise (the rests' per axis): each reading's direction about the centre moves by
    // sigma_f / radius, the step by both; the rate, a mean of two readings, by sigma_w^2 / 2.
    s.noise +=
        (2.0 * turn.rest_var_f / t.radius2 + dt * dt * 0.5 * turn.rest_var_omega) / (rate * rate);
  }
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
  // Each turn's readings at speed, in runs about one axis (a turn between rests may hold several
  // rate segments about different axes: the APOPHIS rate logs' +y, -y, -x, +x).
  struct Run {
    std::size_t turn = 0;
    std::vector<Point> points;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  };
  std::vector<Run> runs;
  LogReader reader(log);
  reader.skip_bad_samples([](const BadSampleError&) {});
  ImuSample x;
  std::size_t k = 0, i = 0;
  bool have = false;  // the previous reading is in the same turn, at speed
  while (reader.next(x)) {
    if (!(x.dt > 0.0)) continue;
    if (g.nominal == 0.0) g.nominal = x.dt;
    while (i < turns.size() && k >= turns[i].last) {
      ++i;
      have = false;
    }
    ++k;
    if (i == turns.size() || k - 1 < turns[i].first) continue;
    Point p{x.dtheta_b / x.dt - turns[i].rest_omega, x.dv_b / x.dt, have};
    have = p.w.norm() > 0.5 * peak[i];
    if (!have) continue;
    // A new run after a reading below speed, or where the axis turns by more than 30 deg.
    if (!p.after_fast || runs.empty() || runs.back().turn != i ||
        p.w.dot(runs.back().sum) <
            std::cos(30.0 * M_PI / 180.0) * p.w.norm() * runs.back().sum.norm())
      runs.push_back(Run{i, {}, Eigen::Vector3d::Zero()});
    runs.back().points.push_back(p);
    runs.back().sum += p.w;
  }
  Sums s;
  for (auto& r : runs) {
    r.points.front().after_fast = false;  // its first interval is not the run's
    g.turns += add_turn(r.points, turns[r.turn], s) ? 1 : 0;
  }
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
