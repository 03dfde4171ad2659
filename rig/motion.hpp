// Truth motion of the IMU on the table: attitude, angular rate and acceleration, specific force,
// exact (analytic) at any time. The site is fixed on the Earth, the navigation frame is the local
// NED frame there, the IMU reference point sits at the intersection of the table axes.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "models/earth.hpp"
#include "models/imu_error_model.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

/// Trapezoidal angle profile: constant acceleration, constant rate, constant deceleration.
class TrapezoidProfile {
 public:
  TrapezoidProfile() = default;
  /// Profile of `angle` (signed, rad) at peak `rate` (rad/s) with `accel` (rad/s^2); triangular
  /// when the angle is too small to reach the rate.
  static TrapezoidProfile by_rate(double angle, double rate, double accel);
  /// Profile of `angle` lasting `duration` (s) with `accel`; throws std::invalid_argument when the
  /// acceleration cannot turn the angle in that time.
  static TrapezoidProfile by_duration(double angle, double duration, double accel);
  double duration() const { return 2.0 * t_acc_ + t_cruise_; }
  double angle() const { return angle_; }
  double peak_rate() const { return accel_ * t_acc_; }
  double acceleration() const { return accel_; }  // rad/s^2, of the ramps
  /// Angle (rad), rate (rad/s), angular acceleration (rad/s^2) at time t from the start; the
  /// profile holds its end angle after it ends and zero before it starts.
  void eval(double t, double& angle, double& rate, double& accel) const;
  /// Times (from the start) where the acceleration jumps.
  std::vector<double> knots() const;

 private:
  double angle_ = 0.0, accel_ = 0.0, t_acc_ = 0.0, t_cruise_ = 0.0;
};

/// How a table realizes a commanded angle profile (its dynamics, or the motion measured in the
/// data): angle, rate and angular acceleration at time t from the commanded start. The realized
/// profile may begin before the commanded one (a zero-phase smoothing) and end after it (servo
/// lag, settling); outside [begin(), end()] it holds 0 before and the commanded angle after.
class ProfileRealization {
 public:
  virtual ~ProfileRealization() = default;
  virtual void eval(double t, double& angle, double& rate, double& accel) const = 0;
  virtual double begin() const = 0;  // s from the commanded start (<= 0)
  virtual double end() const = 0;    // s from the commanded start (>= the commanded duration)
  /// Times (from the commanded start) where the profile is not smooth.
  virtual std::vector<double> knots() const = 0;
};

/// An angle profile as commanded (a trapezoid) and, optionally, as the table realized it.
class AngleProfile {
 public:
  AngleProfile() = default;
  AngleProfile(const TrapezoidProfile& commanded)  // NOLINT(google-explicit-constructor)
      : commanded_(commanded) {}
  AngleProfile(const TrapezoidProfile& commanded,
               std::shared_ptr<const ProfileRealization> realized)
      : commanded_(commanded), realized_(std::move(realized)) {}
  const TrapezoidProfile& commanded() const { return commanded_; }
  const ProfileRealization* realized() const { return realized_.get(); }
  double angle() const { return commanded_.angle(); }  // the total turn (realized too)
  double duration() const { return commanded_.duration(); }
  double peak_rate() const { return commanded_.peak_rate(); }
  double acceleration() const { return commanded_.acceleration(); }
  double begin() const { return realized_ ? realized_->begin() : 0.0; }
  double end() const { return realized_ ? realized_->end() : commanded_.duration(); }
  void eval(double t, double& angle, double& rate, double& accel) const {
    if (realized_)
      realized_->eval(t, angle, rate, accel);
    else
      commanded_.eval(t, angle, rate, accel);
  }
  std::vector<double> knots() const { return realized_ ? realized_->knots() : commanded_.knots(); }

 private:
  TrapezoidProfile commanded_;
  std::shared_ptr<const ProfileRealization> realized_;
};

/// A table's dynamics: how its turns depart from the trapezoid a plan commands (docs/formats.md
/// "Table dynamics"). Every part is optional (zero: off); the realized angle is the commanded
/// trapezoid (re-timed to `max_rate` and `max_acceleration` when they are below the plan's)
/// through a linear filter of unit gain: a jerk limit (the acceleration ramps over
/// jerk_time), a zero-phase Gaussian smoothing (another tool's turns), a
/// second-order servo (lag and overshoot) and a lightly damped structural mode (settling ripple)
/// in series; then a cogging ripple, periodic in the turned angle (rate ripple), that vanishes
/// at the turn's ends. The smoothing and the servo or mode exclude each other.
struct TableDynamics {
  double max_rate = 0.0;            // rad/s
  double max_acceleration = 0.0;    // rad/s^2
  double jerk_time = 0.0;           // s over which the acceleration ramps (the jerk limit)
  double smoothing = 0.0;           // s, the Gaussian's standard deviation
  double servo_frequency = 0.0;     // Hz, natural frequency of the servo loop
  double servo_damping = 0.7;       // in (0, 1)
  double ripple_frequency = 0.0;    // Hz, the structural mode
  double ripple_damping = 0.05;     // in (0, 1)
  double rate_ripple = 0.0;         // rad, amplitude of the cogging ripple in angle
  double rate_ripple_period = 0.0;  // rad of turn per ripple period
  double start_offset = 0.0;        // s: the plan starts this late in the log
  bool any() const {
    return max_rate > 0.0 || max_acceleration > 0.0 || jerk_time > 0.0 || smoothing > 0.0 ||
           servo_frequency > 0.0 || ripple_frequency > 0.0 || rate_ripple > 0.0;
  }
  /// Throws std::invalid_argument naming the part out of its range.
  void validate() const;
  /// The profile a table with these dynamics realizes for `commanded`.
  AngleProfile realize(const TrapezoidProfile& commanded) const;
};

/// One piece of motion:
///   C_b_n(t) = R(axis_c_n, gamma(t)) * R(axis_n, alpha(t)) * C_b_n_start * R(axis_b, beta(t)),
/// a rotation about an axis fixed in the navigation frame composed with one about an axis fixed in
/// the body; gamma is a small correction about a second navigation-frame axis that a simulated
/// table makes during a move to set the next dwell to its accuracy (TableErrors::attitude_sigma),
/// zero otherwise. The profiles start at t0. A static piece has every angle zero.
struct MotionSegment {
  double t0 = 0.0;
  double t1 = 0.0;
  Eigen::Matrix3d C_b_n_start = Eigen::Matrix3d::Identity();
  Eigen::Vector3d axis_n = Eigen::Vector3d::UnitX();
  AngleProfile alpha;
  Eigen::Vector3d axis_b = Eigen::Vector3d::UnitZ();
  AngleProfile beta;
  Eigen::Vector3d axis_c_n = Eigen::Vector3d::UnitZ();
  AngleProfile gamma;
  bool is_static() const {
    return alpha.angle() == 0.0 && beta.angle() == 0.0 && gamma.angle() == 0.0;
  }
  Eigen::Matrix3d C_b_n_end() const;
  /// Where the realized motion begins and ends (absolute s): [t0, t1] for a commanded profile,
  /// wider when the table's dynamics smooth, lag or settle.
  double motion_begin() const;
  double motion_end() const;
  /// Table axis angles, when the piece is a table move (alpha about the outer axis, beta about
  /// the inner one): outer = outer0 + outer_sign * alpha(t), inner likewise.
  bool has_table = false;
  double outer0 = 0.0, inner0 = 0.0;  // rad
  double outer_sign = 1.0, inner_sign = 1.0;
};

/// A static interval of the simulated motion: what the plan says (rig/timeline.hpp) and the
/// attitude the simulation produced (true; differs by the table errors). Estimators take the
/// PlanDwell part only.
struct Dwell : PlanDwell {
  Eigen::Matrix3d C_b_n_true = Eigen::Matrix3d::Identity();
};

struct KinematicState {
  Eigen::Matrix3d C_b_n = Eigen::Matrix3d::Identity();
  Eigen::Vector3d omega_nb_b = Eigen::Vector3d::Zero();  // rad/s
  KinematicSample imu;                                   // omega_ib_b, omega_dot_ib_b, f_ib_b
};

class Motion {
 public:
  Motion(const Site& site, std::vector<MotionSegment> segments, std::vector<Dwell> dwells);
  /// Truth at time t (s); before the start and after the end the IMU rests in the first / last
  /// attitude.
  KinematicState at(double t) const;
  double duration() const { return segments_.back().t1; }
  const Site& site() const { return site_; }
  const std::vector<Dwell>& dwells() const { return dwells_; }
  const std::vector<MotionSegment>& segments() const { return segments_; }
  /// Sorted times where the motion is not smooth (segment ends, profile knots).
  const std::vector<double>& knots() const { return knots_; }
  /// The table's axis angles at time t (rad), the truth an encoder reads; false if the motion is
  /// not made of table moves (rotations about body axes).
  bool table_angles(double t, double& outer, double& inner) const;
  /// True if [a, b] lies in one static segment (or outside the motion, where it rests).
  bool static_between(double a, double b) const;

 private:
  std::size_t segment_index(double t) const;
  /// The segment whose (realized) motion holds at t: a move reaching into a static segment.
  std::size_t active_index(double t) const;
  Site site_;
  std::vector<MotionSegment> segments_;
  std::vector<Dwell> dwells_;
  std::vector<double> knots_;
  std::vector<std::size_t> moving_;  // indices of the moving segments, in time order
  Eigen::Vector3d omega_ie_n_;
  Eigen::Vector3d g_n_;
};

}  // namespace sinscal
