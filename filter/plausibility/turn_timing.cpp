#include "filter/plausibility/turn_timing.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>

#include "models/attitude.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

struct Reading {
  Eigen::Vector3d omega, f;
  double dt = 0.0;
};

// Each reading of the log in order, with its index (bad readings left out). The log is read once
// per call: three streaming passes keep the memory bounded whatever the log's length.
template <typename F>
void for_each_reading(const LogFormat& log, F take) {
  LogReader reader(log);
  reader.skip_bad_samples([](const BadSampleError&) {});
  ImuSample s;
  std::size_t k = 0;
  while (reader.next(s))
    if (s.dt > 0.0) take(k++, Reading{s.dtheta_b / s.dt, s.dv_b / s.dt, s.dt});
}

// A rest's readings [a, b) and their means and per-reading variances (summed over the axes).
struct Rest {
  std::size_t a = 0, b = 0;
  Eigen::Vector3d omega = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_omega2 = Eigen::Vector3d::Zero(), sum_f2 = Eigen::Vector3d::Zero();
  double var_omega = 0.0, var_f = 0.0;
};

// Pass 1: the rests, runs of the centred moving average of the rates (2h + 1 readings) below the
// threshold, at least min_len + 2h long, trimmed by h at both ends.
std::vector<Rest> find_rests(const LogFormat& log, std::size_t h, std::size_t min_len,
                             double threshold) {
  std::vector<Rest> out;
  std::vector<Eigen::Vector3d> ring(2 * h + 1, Eigen::Vector3d::Zero());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  std::size_t run_start = 0, n = 0;
  bool in_run = false;
  auto classify = [&](std::size_t k, bool still) {  // reading k is still or not
    if (still && !in_run) run_start = k;
    if (!still && in_run && k - run_start >= min_len + 2 * h)
      out.push_back(Rest{run_start + h, k - h});
    in_run = still;
  };
  for_each_reading(log, [&](std::size_t k, const Reading& r) {
    sum += r.omega - ring[k % ring.size()];
    ring[k % ring.size()] = r.omega;
    n = k + 1;
    // The window of reading k - h is full from k = 2h on (the first h: their own readings).
    if (k >= 2 * h) classify(k - h, (sum / static_cast<double>(ring.size())).norm() < threshold);
  });
  classify(n > h ? n - h : 0, false);  // the last h readings: a run ends before them
  return out;
}

// Pass 2: the rests' means and variances.
void rest_statistics(const LogFormat& log, std::vector<Rest>& rests) {
  std::size_t i = 0;
  for_each_reading(log, [&](std::size_t k, const Reading& r) {
    while (i < rests.size() && k >= rests[i].b) ++i;
    if (i == rests.size() || k < rests[i].a) return;
    Rest& x = rests[i];
    x.omega += r.omega;
    x.f += r.f;
    x.sum_omega2 += r.omega.cwiseAbs2();
    x.sum_f2 += r.f.cwiseAbs2();
  });
  for (Rest& x : rests) {
    const double n = static_cast<double>(x.b - x.a);
    x.omega /= n;
    x.f /= n;
    const double m = std::max(1.0, n - 1.0);
    x.var_omega = std::max(0.0, (x.sum_omega2 - n * x.omega.cwiseAbs2()).sum() / m);
    x.var_f = std::max(0.0, (x.sum_f2 - n * x.f.cwiseAbs2()).sum() / m);
  }
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// The bound of a turn's disagreement. Noise: each rest's mean direction (per axis across
// gravity), the bias's mean and its change between the rests over the turn's time; the gyros'
// errors the profile allows over the path, the accelerometers' in each rest's direction.
double tolerance(const Rest& A, const Rest& B, double duration, double path,
                 const TurnTimingOptions& o) {
  const auto nA = static_cast<double>(A.b - A.a), nB = static_cast<double>(B.b - B.a);
  const double g2 = 0.5 * (A.f.squaredNorm() + B.f.squaredNorm());
  const double var_dir = (A.var_f / nA + B.var_f / nB) / g2;
  const double var_bias = 0.25 * (A.var_omega / nA + B.var_omega / nB) * duration * duration;
  const double bias_change = 0.5 * (A.omega - B.omega).norm() * duration;
  return o.sigmas * std::sqrt(var_dir + var_bias) + bias_change + o.relative * path +
         2.0 * o.accel_direction;
}

// Pass 3: each turn from one rest to the next, the gyros integrated at the readings' intervals
// less the two rests' mean rate (bias and Earth rate).
std::vector<TurnTiming> integrate_turns(const LogFormat& log, const std::vector<Rest>& rests,
                                        const TurnTimingOptions& o) {
  std::vector<TurnTiming> turns(rests.size() > 1 ? rests.size() - 1 : 0);
  std::vector<Eigen::Matrix3d> C(turns.size(), Eigen::Matrix3d::Identity());  // B's body to A's
  std::vector<Eigen::Matrix3d> probe = C;  // the same at a true rate kTimingProbe off
  std::vector<double> duration(turns.size(), 0.0);
  std::size_t i = 0;
  for_each_reading(log, [&](std::size_t k, const Reading& r) {
    while (i < turns.size() && k >= rests[i + 1].a) ++i;
    if (i == turns.size() || k < rests[i].b) return;
    const Eigen::Vector3d step = (r.omega - 0.5 * (rests[i].omega + rests[i + 1].omega)) * r.dt;
    C[i] = C[i] * dcm_from_rotvec(step);
    probe[i] = probe[i] * dcm_from_rotvec((1.0 + kTimingProbe) * step);
    turns[i].path += step.norm();
    duration[i] += r.dt;
  });
  std::vector<TurnTiming> out;
  for (std::size_t j = 0; j < turns.size(); ++j) {
    TurnTiming t = turns[j];
    const Rest &A = rests[j], &B = rests[j + 1];
    if (t.path < o.min_turn) continue;
    t.turn = static_cast<int>(out.size()) + 1;
    t.first = A.b;
    t.last = B.a;
    t.integrated = rotvec_from_dcm(C[j]).norm();
    t.gravity_angle = angle_between(A.f, B.f);
    t.disagreement = angle_between(C[j].transpose() * A.f, B.f);
    t.tolerance = tolerance(A, B, duration[j], t.path, o);
    t.probe_shift = angle_between(C[j].transpose() * A.f, probe[j].transpose() * A.f);
    t.rest_omega = 0.5 * (A.omega + B.omega);
    t.rest_var_f = (A.var_f + B.var_f) / 6.0;  // the mean over both rests and the three axes
    t.rest_var_omega = (A.var_omega + B.var_omega) / 6.0;
    out.push_back(t);
  }
  return out;
}

std::string deg(double rad) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", rad / units::deg);
  return b;
}

// Every turn agrees: passed when one of them judges the time, else failed (the time cannot be
// checked), naming the turn that comes closest to judging it.
PlausibilityCheck unjudged_or_agreeing(const std::vector<TurnTiming>& turns, const LogFormat& log,
                                       const std::string& worst_turn, const TurnTiming& worst) {
  PlausibilityCheck c{"turn timing", true, ""};
  const TurnTiming* best = nullptr;
  int judging = 0;
  for (const auto& t : turns) {
    judging += t.judges() ? 1 : 0;
    if (!best || t.probe_shift / t.tolerance > best->probe_shift / best->tolerance) best = &t;
  }
  const std::string n = std::to_string(turns.size());
  if (judging > 0) {
    c.detail = log.file + ": " + n + " turns between rests agree with the nominal rate (" +
               std::to_string(judging) + " of them would show a " +
               std::to_string(std::lround(100.0 * kTimingProbe)) +
               " % error of it); the closest to its bound: " + worst_turn + "within " +
               deg(worst.tolerance) + " deg)";
    return c;
  }
  c.passed = false;
  c.detail = log.file +
             ": the log's time cannot be checked: without a time column each reading "
             "is taken as 1 / rate, and none of the " +
             n + " turns between rests would show a " +
             std::to_string(std::lround(100.0 * kTimingProbe)) +
             " % error of that rate (the most: turn " + std::to_string(best->turn) + ", readings " +
             std::to_string(best->first + 1) + "-" + std::to_string(best->last) +
             ", integrating to " + deg(best->integrated) + " deg, would move gravity " +
             deg(best->probe_shift) + " deg against its tolerance " + "of " + deg(best->tolerance) +
             " deg: a turn about the vertical moves no gravity, a "
             "long turn's tolerance exceeds what the time moves): the integrating methods need "
             "the true intervals; the means need none (--method rate-table)";
  return c;
}

}  // namespace

std::vector<TurnTiming> turn_timings(const LogFormat& log, const TurnTimingOptions& o) {
  // The window and the shortest rest in readings, at the log's nominal rate (or its first
  // reading's interval when it has a time column and no rate).
  double rate_hz = log.rate_hz;
  if (!(rate_hz > 0.0))
    for_each_reading(log, [&](std::size_t, const Reading& r) {
      if (!(rate_hz > 0.0)) rate_hz = 1.0 / r.dt;
    });
  if (!(rate_hz > 0.0)) return {};
  const auto h = static_cast<std::size_t>(std::max(1.0, std::round(0.5 * o.smoothing * rate_hz)));
  const auto min_len = static_cast<std::size_t>(o.min_rest * rate_hz);
  std::vector<Rest> rests = find_rests(log, h, min_len, o.rate_threshold);
  rest_statistics(log, rests);
  return integrate_turns(log, rests, o);
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
  if (disagree == 0) return unjudged_or_agreeing(turns, log, turn, *worst);
  c.passed = false;
  c.detail = log.file + ": the log's time does not match the nominal rate: " + turn + "beyond " +
             deg(worst->tolerance) + " deg of noise and the profile's sensor errors; " +
             std::to_string(disagree) + " of " + std::to_string(turns.size()) +
             " turns disagree): without a time column each reading is taken as 1 / rate, and "
             "the integrating methods need the true intervals";
  return c;
}

TurnTimingOptions turn_timing_options(const SensorProfile* profile) {
  TurnTimingOptions t;
  if (!profile) return t;
  auto largest = [&](const std::string& family) {
    const auto it = profile->ranges.find(family);
    return it != profile->ranges.end() && it->second.present()
               ? std::max(std::abs(it->second.lo), std::abs(it->second.hi))
               : 0.0;
  };
  t.relative = largest("gyro.scale") + largest("gyro.misalignment");
  t.accel_direction =
      largest("accel.bias") / units::g0 + largest("accel.scale") + largest("accel.misalignment");
  return t;
}

std::optional<PlausibilityCheck> no_time_turn_timing(const LogFormat& log,
                                                     const SensorProfile* profile) {
  if (!(integrating_limits(PlausibilityLimits{}, log).assumed_rate_hz > 0.0)) return std::nullopt;
  return check_turn_timing(turn_timings(log, turn_timing_options(profile)), log);
}

}  // namespace sinscal
