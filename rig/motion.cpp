#include "rig/motion.hpp"

#include <algorithm>
#include <cmath>
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

Eigen::Matrix3d MotionSegment::C_b_n_end() const {
  return rotation(axis_c_n, gamma.angle()) * rotation(axis_n, alpha.angle()) * C_b_n_start *
         rotation(axis_b, beta.angle());
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

bool Motion::static_between(double a, double b) const {
  const std::size_t i = segment_index(a), j = segment_index(b);
  if (i != j) {
    // b exactly at the end of segment i counts as inside it.
    if (!(j == i + 1 && b <= segments_[i].t1)) return false;
  }
  return segments_[i].is_static();
}

bool Motion::table_angles(double t, double& outer, double& inner) const {
  const MotionSegment& s = segments_[segment_index(t)];
  if (!s.has_table) return false;
  double al, al_d, al_dd, be, be_d, be_dd;
  s.alpha.eval(t - s.t0, al, al_d, al_dd);
  s.beta.eval(t - s.t0, be, be_d, be_dd);
  outer = s.outer0 + s.outer_sign * al;
  inner = s.inner0 + s.inner_sign * be;
  return true;
}

KinematicState Motion::at(double t) const {
  const MotionSegment& s = segments_[segment_index(t)];
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
