// Hand-held multi-position sessions for the simulator: the IMU rests in a random sequence of
// static poses (random orientations and durations), turned by hand between them (smooth-ish
// rotations at up to a few hundred deg/s about random axes), as a `Motion` that ImuSimulator
// samples with the project's error model and noise. Plus the raw-count view of a log (sensitivity
// and offset per axis), as hand-held sessions of consumer IMUs are logged.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "models/earth.hpp"
#include "models/units.hpp"
#include "rig/imu_sample.hpp"
#include "rig/motion.hpp"

namespace sinscal {

struct HandheldOptions {
  double first_rest = 50.0;  // s: the first pose (an initial static interval, as imu_tk uses)
  int poses = 36;            // further static poses after the first
  double rest_min = 3.0;     // s: duration of each further pose, uniform in [rest_min, rest_max]
  double rest_max = 10.0;    // s
  double peak_rate_min = 100.0 * units::deg;  // rad/s: peak rate of each turn, uniform in
  double peak_rate_max = 200.0 * units::deg;  //   [min, max]
  double angular_accel = 600.0 * units::deg;  // rad/s^2 of the turns' trapezoid profiles
  double min_turn = 30.0 * units::deg;        // rad: smallest rotation between two poses
  double max_body_turn = 60.0 * units::deg;   // rad: largest part of a turn about a body axis
};

/// A random hand-held session: `options.poses + 1` static poses at uniformly random orientations
/// (each at least `min_turn` from the previous one), the first starting at t = 0 with attitude
/// `C_b_n_first`. Each turn between poses is a rotation about a random axis fixed in the
/// navigation frame composed with one about a random body axis (both trapezoid profiles over the
/// same time), so the rotation axis moves in the body while turning. Every pose is a `Dwell` of
/// the motion (known attitude = true attitude). The same seed gives the same motion. Throws
/// std::invalid_argument for inconsistent options.
Motion handheld_motion(const Site& site, const HandheldOptions& options, std::uint64_t seed,
                       const Eigen::Matrix3d& C_b_n_first = Eigen::Matrix3d::Identity());

/// One reading of both triads at time t (s), as a log gives them: rates, not increments, in the
/// log's units (raw counts, or SI: accel m/s^2, gyro rad/s).
struct ImuReading {
  double t = 0.0;
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
};

/// Raw-count view of both triads: counts = sensitivity .* value_SI + offset, per axis.
struct RawScaling {
  Eigen::Vector3d accel_sensitivity = Eigen::Vector3d::Ones();  // counts per m/s^2
  Eigen::Vector3d accel_offset = Eigen::Vector3d::Zero();       // counts
  Eigen::Vector3d gyro_sensitivity = Eigen::Vector3d::Ones();   // counts per rad/s
  Eigen::Vector3d gyro_offset = Eigen::Vector3d::Zero();        // counts
};

/// Rates of simulated or logged samples (increment / interval), SI.
std::vector<ImuReading> readings_from_samples(const std::vector<ImuSample>& samples);
/// SI rates to counts with `scaling`; `round` gives whole counts (an ADC's output).
std::vector<ImuReading> counts_from_readings(const std::vector<ImuReading>& si,
                                             const RawScaling& scaling, bool round = true);
/// Counts to SI rates with `scaling` (its nominal values: the output still carries the sensor's
/// errors, in the model's form y = (I + diag(k) + M) x + b). Throws std::invalid_argument for a
/// zero sensitivity.
std::vector<ImuReading> si_from_counts(const std::vector<ImuReading>& counts,
                                       const RawScaling& scaling);

}  // namespace sinscal
