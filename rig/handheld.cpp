#include "rig/handheld.hpp"

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

#include "models/attitude.hpp"

namespace sinscal {
namespace {

Eigen::Vector3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  for (;;) {
    const Eigen::Vector3d v(n(rng), n(rng), n(rng));
    const double norm = v.norm();
    if (norm > 1e-6) return v / norm;
  }
}

/// Uniformly distributed rotation (normalized 4-D Gaussian quaternion).
Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  for (;;) {
    Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
    const double norm = q.norm();
    if (norm > 1e-6) {
      q.coeffs() /= norm;
      return q.toRotationMatrix();
    }
  }
}

}  // namespace

Motion handheld_motion(const Site& site, const HandheldOptions& o, std::uint64_t seed,
                       const Eigen::Matrix3d& C_b_n_first) {
  if (o.poses < 0) throw std::invalid_argument("hand-held motion: negative number of poses");
  if (!(o.first_rest > 0.0) || !(o.rest_min > 0.0) || o.rest_max < o.rest_min)
    throw std::invalid_argument("hand-held motion: rest durations need 0 < rest_min <= rest_max");
  if (!(o.peak_rate_min > 0.0) || o.peak_rate_max < o.peak_rate_min || !(o.angular_accel > 0.0))
    throw std::invalid_argument(
        "hand-held motion: turn rates need 0 < peak_rate_min <= peak_rate_max and a positive "
        "angular acceleration");
  if (o.min_turn < 0.0 || o.min_turn > 0.9 * units::pi || o.max_body_turn < 0.0)
    throw std::invalid_argument("hand-held motion: min_turn must lie in [0, 0.9 pi]");

  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto uniform = [&](double lo, double hi) { return lo + (hi - lo) * unit(rng); };

  std::vector<MotionSegment> segments;
  std::vector<Dwell> dwells;
  Eigen::Matrix3d C = C_b_n_first;
  double t = 0.0;
  auto add_rest = [&](double duration) {
    MotionSegment s;
    s.t0 = t;
    s.t1 = t + duration;
    s.C_b_n_start = C;
    segments.push_back(s);
    Dwell d;
    d.index = static_cast<int>(dwells.size()) + 1;
    d.label = "pose " + std::to_string(d.index);
    d.t_start = s.t0;
    d.t_end = s.t1;
    d.C_b_n_known = d.C_b_n_true = C;
    dwells.push_back(d);
    t = s.t1;
  };

  add_rest(o.first_rest);
  for (int k = 0; k < o.poses; ++k) {
    // Next pose: a uniformly random attitude far enough from this one.
    Eigen::Matrix3d C_next = random_rotation(rng);
    while (rotvec_from_dcm(C_next * C.transpose()).norm() < o.min_turn)
      C_next = random_rotation(rng);
    // Part of the turn about a random body axis, the rest about an axis fixed in n:
    // C_next = R(axis_n, alpha) C R(axis_b, beta).
    const Eigen::Vector3d axis_b = random_unit(rng);
    const double beta = uniform(-o.max_body_turn, o.max_body_turn);
    const Eigen::Vector3d r_n =
        rotvec_from_dcm(C_next * rotation(axis_b, beta).transpose() * C.transpose());
    const double alpha = r_n.norm();
    const Eigen::Vector3d axis_n = alpha > 0.0 ? Eigen::Vector3d(r_n / alpha) : random_unit(rng);
    // One duration for both profiles: the time to turn |alpha| + |beta| at the peak rate, which
    // keeps the combined rate below it.
    const double peak = uniform(o.peak_rate_min, o.peak_rate_max);
    if (alpha + std::abs(beta) == 0.0) continue;  // min_turn = 0 drew the same attitude
    const double duration =
        TrapezoidProfile::by_rate(alpha + std::abs(beta), peak, o.angular_accel).duration();
    MotionSegment s;
    s.t0 = t;
    s.t1 = t + duration;
    s.C_b_n_start = C;
    s.axis_n = axis_n;
    s.axis_b = axis_b;
    if (alpha > 0.0) s.alpha = TrapezoidProfile::by_duration(alpha, duration, o.angular_accel);
    if (beta != 0.0) s.beta = TrapezoidProfile::by_duration(beta, duration, o.angular_accel);
    segments.push_back(s);
    C = segments.back().C_b_n_end();
    t = s.t1;
    add_rest(uniform(o.rest_min, o.rest_max));
  }
  return Motion(site, std::move(segments), std::move(dwells));
}

std::vector<ImuReading> readings_from_samples(const std::vector<ImuSample>& samples) {
  std::vector<ImuReading> out;
  out.reserve(samples.size());
  for (const auto& s : samples) {
    if (!(s.dt > 0.0)) throw std::invalid_argument("sample interval must be positive");
    out.push_back({s.t, s.dv_b / s.dt, s.dtheta_b / s.dt});
  }
  return out;
}

std::vector<ImuReading> counts_from_readings(const std::vector<ImuReading>& si, const RawScaling& c,
                                             bool round) {
  std::vector<ImuReading> out;
  out.reserve(si.size());
  for (const auto& r : si) {
    ImuReading q;
    q.t = r.t;
    q.accel = c.accel_sensitivity.cwiseProduct(r.accel) + c.accel_offset;
    q.gyro = c.gyro_sensitivity.cwiseProduct(r.gyro) + c.gyro_offset;
    if (round) {
      q.accel = q.accel.array().round();
      q.gyro = q.gyro.array().round();
    }
    out.push_back(q);
  }
  return out;
}

std::vector<ImuReading> si_from_counts(const std::vector<ImuReading>& counts, const RawScaling& c) {
  for (int i = 0; i < 3; ++i)
    if (c.accel_sensitivity(i) == 0.0 || c.gyro_sensitivity(i) == 0.0)
      throw std::invalid_argument("raw scaling: zero sensitivity");
  std::vector<ImuReading> out;
  out.reserve(counts.size());
  for (const auto& r : counts)
    out.push_back({r.t, (r.accel - c.accel_offset).cwiseQuotient(c.accel_sensitivity),
                   (r.gyro - c.gyro_offset).cwiseQuotient(c.gyro_sensitivity)});
  return out;
}

}  // namespace sinscal
