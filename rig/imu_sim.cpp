#include "rig/imu_sim.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace sinscal {
namespace {
// 4-point Gauss-Legendre on [-1, 1]: exact for polynomials up to degree 7.
constexpr double kNode[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                             0.8611363115940526};
constexpr double kWeight[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                               0.3478548451374538};
}  // namespace

ImuSimulator::ImuSimulator(const Motion& motion, const ImuErrorModel& errors,
                           const NoiseModel& noise, const SimulatorOptions& options)
    : motion_(motion),
      errors_(errors),
      options_(options),
      noise_(options.noise ? noise : NoiseModel{}, options.noise_seed),
      dt_(1.0 / options.rate_hz) {
  if (!(options.rate_hz > 0.0)) throw std::invalid_argument("sample rate must be positive");
  // Cover the whole motion: a last partial interval is completed at rest.
  if (!(motion.duration() + options.motion_start > 0.0))
    throw std::invalid_argument("the log would begin after the motion ends (start offset)");
  total_ = static_cast<std::size_t>(
      std::ceil((motion.duration() + options.motion_start) * options.rate_hz - 1e-9));
  if (options.table_angles)
    for (const auto& seg : motion.segments())
      if (!seg.has_table)
        throw std::invalid_argument(
            "no table angles for this motion: its rotations are about body axes, not the "
            "table's (plan steps +outer/-inner give table angles)");
}

Eigen::Vector3d ImuSimulator::integrate(double a, double b, double shift, bool gyro) const {
  // The integrand is the model output for the motion at time t - shift; its kinks are at the
  // motion's knots plus shift.
  auto output = [&](double t) {
    KinematicState k = motion_.at(t - shift);
    k.imu.t = t;  // the sensor's own time (time-dependent error terms)
    if (options_.temperature) {
      k.imu.accel_dtemp = k.imu.gyro_dtemp =
          options_.temperature->at(t) - errors_.reference_temperature_c;
      k.imu.gyro_dtemp_rate = options_.temperature->rate(t);
    }
    return gyro ? errors_.gyro_output(k.imu) : errors_.accel_output(k.imu);
  };
  if (motion_.static_between(a - shift, b - shift)) return output(0.5 * (a + b)) * (b - a);
  const auto& knots = motion_.knots();
  auto it = std::upper_bound(knots.begin(), knots.end(), a - shift);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double lo = a;
  while (lo < b) {
    double hi = b;
    if (it != knots.end() && *it + shift < b) hi = *it++ + shift;
    const double half = 0.5 * (hi - lo), mid = 0.5 * (hi + lo);
    if (half > 0.0)
      for (int i = 0; i < 4; ++i) sum += kWeight[i] * half * output(mid + half * kNode[i]);
    lo = hi;
  }
  return sum;
}

bool ImuSimulator::next(ImuSample& s) {
  if (k_ >= total_) return false;
  ++k_;
  // Times from the sample index, so they do not accumulate rounding.
  const double b = static_cast<double>(k_) * dt_;
  const double a = static_cast<double>(k_ - 1) * dt_;
  s.t = b;
  s.dt = b - a;
  s.dtheta_b = integrate(a, b, options_.motion_start, true);
  s.dv_b = integrate(a, b, options_.motion_start + errors_.time_delay, false);
  noise_.apply(s.dtheta_b, s.dv_b, s.dt);
  bool clipped = false;
  auto clip = [&](Eigen::Vector3d& inc, double range) {
    if (range <= 0.0) return;
    for (int i = 0; i < 3; ++i)
      if (std::abs(inc(i)) > range * s.dt) {
        inc(i) = std::copysign(range * s.dt, inc(i));
        clipped = true;
      }
  };
  clip(s.dtheta_b, options_.gyro_range);
  clip(s.dv_b, options_.accel_range);
  if (clipped) ++saturated_;
  s.has_table = options_.table_angles;
  if (s.has_table) motion_.table_angles(s.t - options_.motion_start, s.table_outer, s.table_inner);
  s.has_temperature = options_.temperature != nullptr;
  if (s.has_temperature)
    s.accel_temperature_c = s.gyro_temperature_c = options_.temperature->at(s.t);
  return true;
}

}  // namespace sinscal
