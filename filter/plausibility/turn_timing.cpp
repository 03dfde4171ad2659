#include "filter/plausibility/turn_timing.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "models/attitude.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

struct Reading {
  Eigen::Vector3d omega, f;
  double dt = 0.0;
};

// A rest's readings [a, b) and their means and per-reading variances (summed over the axes).
struct Rest {
  std::size_t a = 0, b = 0;
  Eigen::Vector3d omega = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::Zero();
  double var_omega = 0.0, var_f = 0.0;
};

std::vector<Reading> read_all(const LogFormat& log) {
  LogReader reader(log);
  reader.skip_bad_samples([](const BadSampleError&) {});
  std::vector<Reading> out;
  ImuSample s;
  while (reader.next(s))
    if (s.dt > 0.0) out.push_back({s.dtheta_b / s.dt, s.dv_b / s.dt, s.dt});
  return out;
}

Rest rest_of(const std::vector<Reading>& r, std::size_t a, std::size_t b) {
  Rest x;
  x.a = a;
  x.b = b;
  const double n = static_cast<double>(b - a);
  for (std::size_t k = a; k < b; ++k) {
    x.omega += r[k].omega / n;
    x.f += r[k].f / n;
  }
  for (std::size_t k = a; k < b; ++k) {
    x.var_omega += (r[k].omega - x.omega).squaredNorm() / std::max(1.0, n - 1.0);
    x.var_f += (r[k].f - x.f).squaredNorm() / std::max(1.0, n - 1.0);
  }
  return x;
}

// The rests: runs of the smoothed rate below the threshold, trimmed by the smoothing window.
std::vector<Rest> rests_of(const std::vector<Reading>& r, double rate_hz,
                           const TurnTimingOptions& o) {
  const auto h = static_cast<std::size_t>(std::max(1.0, std::round(0.5 * o.smoothing * rate_hz)));
  std::vector<bool> still(r.size(), false);
  for (std::size_t k = 0; k < r.size(); ++k) {
    const std::size_t lo = k >= h ? k - h : 0, hi = std::min(r.size(), k + h + 1);
    Eigen::Vector3d m = Eigen::Vector3d::Zero();
    for (std::size_t j = lo; j < hi; ++j) m += r[j].omega;
    still[k] = (m / static_cast<double>(hi - lo)).norm() < o.rate_threshold;
  }
  std::vector<Rest> out;
  const auto min_len = static_cast<std::size_t>(o.min_rest * rate_hz);
  for (std::size_t k = 0; k < r.size();) {
    if (!still[k]) {
      ++k;
      continue;
    }
    std::size_t e = k;
    while (e < r.size() && still[e]) ++e;
    if (e - k >= min_len + 2 * h) out.push_back(rest_of(r, k + h, e - h));
    k = e;
  }
  return out;
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// The turn from rest A to rest B: the gyros integrated at the readings' intervals, less the
// rests' mean rate (bias and Earth rate).
TurnTiming turn_between(const std::vector<Reading>& r, const Rest& A, const Rest& B,
                        const TurnTimingOptions& o) {
  TurnTiming t;
  t.first = A.b;
  t.last = B.a;
  const Eigen::Vector3d bias = 0.5 * (A.omega + B.omega);
  Eigen::Matrix3d C = Eigen::Matrix3d::Identity();  // body at B to body at A
  double duration = 0.0;
  for (std::size_t k = A.b; k < B.a; ++k) {
    const Eigen::Vector3d step = (r[k].omega - bias) * r[k].dt;
    C = C * dcm_from_rotvec(step);
    t.path += step.norm();
    duration += r[k].dt;
  }
  t.integrated = rotvec_from_dcm(C).norm();
  t.gravity_angle = angle_between(A.f, B.f);
  t.disagreement = angle_between(C.transpose() * A.f, B.f);
  // Noise: each rest's mean direction (per axis across gravity), the bias's mean and its change
  // between the rests over the turn's time; the gyros' errors the profile allows over the path,
  // the accelerometers' in each rest's direction.
  const auto nA = static_cast<double>(A.b - A.a), nB = static_cast<double>(B.b - B.a);
  const double g2 = 0.5 * (A.f.squaredNorm() + B.f.squaredNorm());
  const double var_dir = (A.var_f / nA + B.var_f / nB) / g2;
  const double var_bias = 0.25 * (A.var_omega / nA + B.var_omega / nB) * duration * duration;
  const double bias_change = 0.5 * (A.omega - B.omega).norm() * duration;
  t.tolerance = o.sigmas * std::sqrt(var_dir + var_bias) + bias_change + o.relative * t.path +
                2.0 * o.accel_direction;
  return t;
}

std::string deg(double rad) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", rad / units::deg);
  return b;
}

}  // namespace

std::vector<TurnTiming> turn_timings(const LogFormat& log, const TurnTimingOptions& o) {
  const std::vector<Reading> r = read_all(log);
  if (r.empty()) return {};
  double total = 0.0;
  for (const auto& x : r) total += x.dt;
  const double rate_hz = static_cast<double>(r.size()) / total;
  const std::vector<Rest> rests = rests_of(r, rate_hz, o);
  std::vector<TurnTiming> out;
  for (std::size_t i = 0; i + 1 < rests.size(); ++i) {
    TurnTiming t = turn_between(r, rests[i], rests[i + 1], o);
    if (t.path < o.min_turn) continue;
    t.turn = static_cast<int>(out.size()) + 1;
    out.push_back(t);
  }
  return out;
}

PlausibilityCheck check_turn_timing(const std::vector<TurnTiming>& turns, const LogFormat& log) {
  PlausibilityCheck c{"turn timing", true, ""};
  // The turn furthest beyond its tolerance (or closest to it), and how many disagree.
  const TurnTiming* worst = nullptr;
  int disagree = 0;
  for (const auto& t : turns) {
    disagree += t.agrees() ? 0 : 1;
    if (!worst || t.disagreement / t.tolerance > worst->disagreement / worst->tolerance) worst = &t;
  }
  if (!worst) {
    c.detail = log.file + ": no turn between two rests to judge the nominal rate by";
    return c;
  }
  const std::string turn = "turn " + std::to_string(worst->turn) + " (readings " +
                           std::to_string(worst->first + 1) + "-" + std::to_string(worst->last) +
                           ") integrates to " + deg(worst->integrated) +
                           " deg, the rests' gravity differ by " + deg(worst->gravity_angle) +
                           " deg (the integrated turn leaves gravity " + deg(worst->disagreement) +
                           " deg from the next rest's, ";
  if (disagree == 0) {
    c.detail =
        log.file + ": " + std::to_string(turns.size()) +
        " turns between rests agree with the nominal rate; the closest to its bound: " + turn +
        "within " + deg(worst->tolerance) + " deg)";
    return c;
  }
  c.passed = false;
  c.detail = log.file + ": the log's time does not match the nominal rate: " + turn + "beyond " +
             deg(worst->tolerance) + " deg of noise and the profile's sensor errors; " +
             std::to_string(disagree) + " of " + std::to_string(turns.size()) +
             " turns disagree): without a time column each reading is taken as 1 / rate, and "
             "the integrating methods need the true intervals";
  return c;
}

}  // namespace sinscal
