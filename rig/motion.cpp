#include "rig/motion.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <stdexcept>

#include "models/attitude.hpp"

namespace sinscal {

TrapezoidProfile TrapezoidProfile::by_rate(double angle, double rate, double accel) {
  if (!(rate > 0.0) || !(accel > 0.0))
    throw std::invalid_argument("move rate and acceleration must be positive");
  TrapezoidProfile p;
  p.angle_ = angle;
  p.accel_ = accel;
  const double a = std::abs(angle);
  if (a >= rate * rate / accel) {
    p.t_acc_ = rate / accel;
    p.t_cruise_ = (a - rate * rate / accel) / rate;
  } else {
    p.t_acc_ = std::sqrt(a / accel);
  }
  return p;
}

TrapezoidProfile TrapezoidProfile::by_duration(double angle, double duration, double accel) {
  if (!(duration > 0.0) || !(accel > 0.0))
    throw std::invalid_argument("rotation duration and acceleration must be positive");
  const double a = std::abs(angle);
  const double disc = duration * duration - 4.0 * a / accel;
  if (disc < 0.0)
    throw std::invalid_argument("acceleration too low to turn " + std::to_string(a * 180 / M_PI) +
                                " deg in " + std::to_string(duration) + " s");
  TrapezoidProfile p;
  p.angle_ = angle;
  p.accel_ = accel;
  p.t_acc_ = 0.5 * (duration - std::sqrt(disc));
  p.t_cruise_ = duration - 2.0 * p.t_acc_;
  return p;
}

void TrapezoidProfile::eval(double t, double& angle, double& rate, double& accel) const {
  const double s = angle_ < 0.0 ? -1.0 : 1.0;
  const double T = duration();
  const double w = accel_ * t_acc_;
  if (angle_ == 0.0 || t <= 0.0) {
    angle = rate = accel = 0.0;
  } else if (t < t_acc_) {
    angle = s * 0.5 * accel_ * t * t;
    rate = s * accel_ * t;
    accel = s * accel_;
  } else if (t < t_acc_ + t_cruise_) {
    angle = s * (0.5 * accel_ * t_acc_ * t_acc_ + w * (t - t_acc_));
    rate = s * w;
    accel = 0.0;
  } else if (t < T) {
    const double r = T - t;
    angle = angle_ - s * 0.5 * accel_ * r * r;
    rate = s * accel_ * r;
    accel = -s * accel_;
  } else {
    angle = angle_;
    rate = accel = 0.0;
  }
}

std::vector<double> TrapezoidProfile::knots() const {
  if (angle_ == 0.0) return {};
  return {0.0, t_acc_, t_acc_ + t_cruise_, duration()};
}

namespace {

// The realized profile of a table with TableDynamics: the (re-timed) trapezoid's angle is a sum
// of acceleration steps a_j R2(t - t_j), R2(x) = x^2/2 for x > 0; through a linear filter of unit
// gain it is the sum of a_j K2(t - t_j), K2 the filter's response to R2 (closed forms below), and
// its rate and acceleration the sums of the responses K1, K0 to R1 = x, R0 = the unit step.
class ShapedProfile : public ProfileRealization {
 public:
  ShapedProfile(const TrapezoidProfile& realized, const TableDynamics& d)
      : total_(realized.angle()) {
    const std::vector<double> k = realized.knots();
    const double a = realized.acceleration() * (total_ < 0.0 ? -1.0 : 1.0);
    if (!k.empty()) steps_ = {{k[0], a}, {k[1], -a}, {k[2], -a}, {k[3], a}};
    box_ = d.jerk_time;
    sigma_ = d.smoothing;
    auto section = [&](double f_hz, double zeta) {
      const double w = 2.0 * M_PI * f_hz;
      const std::complex<double> p(-zeta * w, w * std::sqrt(1.0 - zeta * zeta));
      poles_.push_back(p);
      poles_.push_back(std::conj(p));
      gain_ *= w * w;
      decay_ = std::min(decay_, zeta * w);
    };
    if (d.servo_frequency > 0.0) section(d.servo_frequency, d.servo_damping);
    if (d.ripple_frequency > 0.0) section(d.ripple_frequency, d.ripple_damping);
    for (std::size_t i = 0; i < poles_.size(); ++i) {
      std::complex<double> den = 1.0;
      for (std::size_t j = 0; j < poles_.size(); ++j)
        if (j != i) den *= poles_[i] - poles_[j];
      residues_.push_back(gain_ / den);
    }
    begin_ = sigma_ > 0.0 ? -8.0 * sigma_ : 0.0;
    end_ = realized.duration() + box_ + (sigma_ > 0.0 ? 8.0 * sigma_ : 0.0) +
           (poles_.empty() ? 0.0 : 37.0 / decay_);
    if (d.rate_ripple > 0.0 && d.rate_ripple_period > 0.0) {
      const double n = std::round(std::abs(total_) / d.rate_ripple_period);
      if (n >= 1.0) {
        ripple_ = d.rate_ripple;
        wavenumber_ = 2.0 * M_PI * n / std::abs(total_);
      }
    }
    for (const auto& [t, amp] : steps_) {
      knots_.push_back(t);
      if (box_ > 0.0) knots_.push_back(t + box_);
    }
  }

  void eval(double t, double& angle, double& rate, double& accel) const override {
    if (t <= begin_ || total_ == 0.0) {
      angle = rate = accel = 0.0;
      return;
    }
    if (t >= end_) {
      angle = total_;
      rate = accel = 0.0;
      return;
    }
    angle = rate = accel = 0.0;
    for (const auto& [tj, a] : steps_) {
      angle += a * boxed(2, t - tj);
      rate += a * boxed(1, t - tj);
      accel += a * boxed(0, t - tj);
    }
    if (ripple_ > 0.0) {
      // Cogging: angle + A sin(k angle), periodic in the angle turned, zero at both ends.
      const double s = std::sin(wavenumber_ * angle), c = std::cos(wavenumber_ * angle);
      const double gain = 1.0 + ripple_ * wavenumber_ * c;
      accel = accel * gain - ripple_ * wavenumber_ * wavenumber_ * s * rate * rate;
      rate *= gain;
      angle += ripple_ * s;
    }
  }
  double begin() const override { return begin_; }
  double end() const override { return end_; }
  std::vector<double> knots() const override { return knots_; }

 private:
  // The response to R_n (n = 0..3) of the filter without the box.
  double response(int n, double x) const {
    static constexpr double kFactorial[5] = {1.0, 1.0, 2.0, 6.0, 24.0};
    if (sigma_ > 0.0) {
      // E[R_n(x - sigma Z)] = sigma^n I_n(x / sigma) / n!, I_n(y) = E[(y - Z)_+^n]:
      // I_0 = Phi(y), I_1 = y Phi(y) + phi(y), I_n = y I_(n-1) + (n-1) I_(n-2).
      const double y = x / sigma_;
      const double Phi = 0.5 * std::erfc(-y / std::sqrt(2.0));
      const double phi = std::exp(-0.5 * y * y) / std::sqrt(2.0 * M_PI);
      double i0 = Phi, i1 = y * Phi + phi;
      for (int m = 2; m <= n; ++m) {
        const double i2 = y * i1 + (m - 1) * i0;
        i0 = i1;
        i1 = i2;
      }
      const double in = n == 0 ? Phi : i1;
      return std::pow(sigma_, n) * in / kFactorial[n];
    }
    if (x <= 0.0) return 0.0;
    if (poles_.empty()) return std::pow(x, n) / kFactorial[n];
    // Impulse response sum_k r_k e^(p_k x): (R_n * h)(x) = sum_k r_k (e^(p x) - sum_(m<=n)
    // (p x)^m / m!) / p^(n+1).
    std::complex<double> sum = 0.0;
    for (std::size_t k = 0; k < poles_.size(); ++k) {
      const std::complex<double> px = poles_[k] * x;
      std::complex<double> taylor = 0.0, term = 1.0;
      for (int m = 0; m <= n; ++m) {
        taylor += term;
        term *= px / static_cast<double>(m + 1);
      }
      sum += residues_[k] * (std::exp(px) - taylor) / std::pow(poles_[k], n + 1);
    }
    return sum.real();
  }
  // With the jerk limit: the acceleration ramps over box_ (a moving average of width box_).
  double boxed(int n, double x) const {
    if (box_ <= 0.0) return response(n, x);
    return (response(n + 1, x) - response(n + 1, x - box_)) / box_;
  }

  double total_ = 0.0;
  std::vector<std::pair<double, double>> steps_;  // (time, acceleration step)
  double box_ = 0.0, sigma_ = 0.0;
  std::vector<std::complex<double>> poles_, residues_;
  double gain_ = 1.0, decay_ = 1e300;
  double begin_ = 0.0, end_ = 0.0;
  double ripple_ = 0.0, wavenumber_ = 0.0;
  std::vector<double> knots_;
};

}  // namespace

void TableDynamics::validate() const {
  auto check = [](bool ok, const std::string& what) {
    if (!ok) throw std::invalid_argument("table dynamics: " + what);
  };
  check(max_rate >= 0.0 && max_rate <= 100.0, "max_rate must be within 0 and 100 rad/s");
  check(max_acceleration >= 0.0 && max_acceleration <= 1000.0,
        "max_acceleration must be within 0 and 1000 rad/s^2");
  check(jerk_time >= 0.0 && jerk_time <= 10.0, "jerk_time must be within 0 and 10 s");
  check(smoothing >= 0.0 && smoothing <= 10.0, "smoothing must be within 0 and 10 s");
  check(servo_frequency >= 0.0 && servo_frequency <= 1000.0,
        "servo_frequency must be within 0 and 1000 Hz");
  check(ripple_frequency >= 0.0 && ripple_frequency <= 1000.0,
        "ripple_frequency must be within 0 and 1000 Hz");
  check(servo_damping > 0.0 && servo_damping < 1.0, "servo_damping must be within 0 and 1");
  check(ripple_damping > 0.0 && ripple_damping < 1.0, "ripple_damping must be within 0 and 1");
  check(!(smoothing > 0.0 && (servo_frequency > 0.0 || ripple_frequency > 0.0)),
        "a smoothing and a servo or structural mode exclude each other");
  check(!(servo_frequency > 0.0 && servo_frequency == ripple_frequency &&
          servo_damping == ripple_damping),
        "the servo and the structural mode must differ");
  check(!(servo_frequency > 0.0 && servo_damping * 2.0 * M_PI * servo_frequency < 0.5),
        "the servo settles too slowly (damping times 2 pi frequency below 0.5 /s)");
  check(!(ripple_frequency > 0.0 && ripple_damping * 2.0 * M_PI * ripple_frequency < 0.5),
        "the structural mode settles too slowly (damping times 2 pi frequency below 0.5 /s)");
  check(rate_ripple >= 0.0 && rate_ripple <= 0.01, "rate_ripple must be within 0 and 0.01 rad");
  check(rate_ripple == 0.0 || rate_ripple_period > 0.0,
        "a rate ripple needs its period (rad of turn)");
  check(std::abs(start_offset) <= 1e6, "start_offset must be within -1e6 and 1e6 s");
}

AngleProfile TableDynamics::realize(const TrapezoidProfile& commanded) const {
  if (!any() || commanded.angle() == 0.0) return commanded;
  TrapezoidProfile realized = commanded;
  const double rate =
      max_rate > 0.0 ? std::min(max_rate, commanded.peak_rate()) : commanded.peak_rate();
  const double acc = max_acceleration > 0.0 ? std::min(max_acceleration, commanded.acceleration())
                                            : commanded.acceleration();
  if (rate > 0.0 && acc > 0.0 && (rate < commanded.peak_rate() || acc < commanded.acceleration()))
    realized = TrapezoidProfile::by_rate(commanded.angle(), rate, acc);
  return {commanded, std::make_shared<const ShapedProfile>(realized, *this)};
}

Eigen::Matrix3d MotionSegment::C_b_n_end() const {
  return rotation(axis_c_n, gamma.angle()) * rotation(axis_n, alpha.angle()) * C_b_n_start *
         rotation(axis_b, beta.angle());
}

double MotionSegment::motion_begin() const {
  if (is_static()) return t0;
  return t0 + std::min({alpha.begin(), beta.begin(), gamma.begin()});
}

double MotionSegment::motion_end() const {
  if (is_static()) return t1;
  return std::max(t1, t0 + std::max({alpha.end(), beta.end(), gamma.end()}));
}

Motion::Motion(const Site& site, std::vector<MotionSegment> segments, std::vector<Dwell> dwells)
    : site_(site), segments_(std::move(segments)), dwells_(std::move(dwells)) {
  if (segments_.empty()) throw std::invalid_argument("a motion needs at least one segment");
  const Earth& earth = Earth::wgs84();
  omega_ie_n_ = earth.omega_ie_n(site.lat_rad);
  g_n_ = earth.gravity_n(site.lat_rad, site.h_m);
  for (auto& s : segments_) {
    s.axis_n.normalize();
    s.axis_b.normalize();
    s.axis_c_n.normalize();
    knots_.push_back(s.t0);
    knots_.push_back(s.t1);
    for (double k : s.alpha.knots()) knots_.push_back(s.t0 + k);
    for (double k : s.beta.knots()) knots_.push_back(s.t0 + k);
    for (double k : s.gamma.knots()) knots_.push_back(s.t0 + k);
    if (!s.is_static()) {
      knots_.push_back(s.motion_begin());
      knots_.push_back(s.motion_end());
    }
  }
  // The moving segments in time order; a realized motion that smooths, lags or settles past its
  // segment must not reach into the next move's.
  for (std::size_t i = 0; i < segments_.size(); ++i) {
    if (segments_[i].is_static()) continue;
    if (!moving_.empty()) {
      const MotionSegment& before = segments_[moving_.back()];
      if (before.motion_end() > segments_[i].motion_begin() + 1e-9)
        throw std::invalid_argument(
            "the table's dynamics make the move at t = " + std::to_string(before.t0) +
            " s still settle at t = " + std::to_string(before.motion_end()) +
            " s, after the next move begins (t = " + std::to_string(segments_[i].motion_begin()) +
            " s): lengthen the pause between them or shorten the table's settling");
    }
    moving_.push_back(i);
  }
  std::sort(knots_.begin(), knots_.end());
  knots_.erase(std::unique(knots_.begin(), knots_.end()), knots_.end());
}

std::size_t Motion::segment_index(double t) const {
  // First segment whose end is after t; the last one for t beyond the end.
  const auto it = std::upper_bound(segments_.begin(), segments_.end(), t,
                                   [](double x, const MotionSegment& s) { return x < s.t1; });
  return it == segments_.end() ? segments_.size() - 1
                               : static_cast<std::size_t>(it - segments_.begin());
}

std::size_t Motion::active_index(double t) const {
  const std::size_t i = segment_index(t);
  if (!segments_[i].is_static()) return i;
  // A static segment, unless a move's realized motion reaches into it.
  const auto it =
      std::upper_bound(moving_.begin(), moving_.end(), t,
                       [this](double x, std::size_t k) { return x < segments_[k].motion_begin(); });
  if (it != moving_.begin() && segments_[*(it - 1)].motion_end() > t) return *(it - 1);
  return i;
}

bool Motion::static_between(double a, double b) const {
  // No move's realized motion inside [a, b].
  const auto it =
      std::upper_bound(moving_.begin(), moving_.end(), b,
                       [this](double x, std::size_t k) { return x < segments_[k].motion_begin(); });
  if (it != moving_.begin() && segments_[*(it - 1)].motion_end() > a &&
      segments_[*(it - 1)].motion_begin() < b)
    return false;
  const std::size_t i = segment_index(a), j = segment_index(b);
  if (i != j) {
    // b exactly at the end of segment i counts as inside it.
    if (!(j == i + 1 && b <= segments_[i].t1)) return false;
  }
  return segments_[i].is_static();
}

bool Motion::table_angles(double t, double& outer, double& inner) const {
  const MotionSegment& s = segments_[active_index(t)];
  if (!s.has_table) return false;
  double al, al_d, al_dd, be, be_d, be_dd;
  s.alpha.eval(t - s.t0, al, al_d, al_dd);
  s.beta.eval(t - s.t0, be, be_d, be_dd);
  outer = s.outer0 + s.outer_sign * al;
  inner = s.inner0 + s.inner_sign * be;
  return true;
}

KinematicState Motion::at(double t) const {
  const MotionSegment& s = segments_[active_index(t)];
  const double tau = t - s.t0;
  double al, al_d, al_dd, be, be_d, be_dd, ga, ga_d, ga_dd;
  s.alpha.eval(tau, al, al_d, al_dd);
  s.beta.eval(tau, be, be_d, be_dd);
  s.gamma.eval(tau, ga, ga_d, ga_dd);
  KinematicState k;
  const Eigen::Matrix3d C_c = rotation(s.axis_c_n, ga);
  k.C_b_n = C_c * rotation(s.axis_n, al) * s.C_b_n_start * rotation(s.axis_b, be);
  // The axes in body: u_b (the move's outer axis, fixed in the frame the correction turns) and
  // c_b (the correction's axis, fixed in the navigation frame).
  const Eigen::Vector3d u_b = k.C_b_n.transpose() * (C_c * s.axis_n);
  const Eigen::Vector3d c_b = k.C_b_n.transpose() * s.axis_c_n;
  k.omega_nb_b = ga_d * c_b + al_d * u_b + be_d * s.axis_b;
  // d(c_b)/dt = -omega_nb_b x c_b; d(u_b)/dt = -be_d axis_b x u_b; axis_b is body-fixed.
  const Eigen::Vector3d omega_dot_nb_b = ga_dd * c_b - ga_d * k.omega_nb_b.cross(c_b) +
                                         al_dd * u_b - al_d * be_d * s.axis_b.cross(u_b) +
                                         be_dd * s.axis_b;
  const Eigen::Vector3d omega_ie_b = k.C_b_n.transpose() * omega_ie_n_;
  k.imu.omega_ib_b = k.omega_nb_b + omega_ie_b;
  k.imu.omega_dot_ib_b = omega_dot_nb_b - k.omega_nb_b.cross(omega_ie_b);
  k.imu.f_ib_b = -(k.C_b_n.transpose() * g_n_);
  return k;
}

}  // namespace sinscal
