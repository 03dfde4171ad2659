// The installation of the IMU on the table (docs/conventions.md "Table base and mounting"): the
// attitude of the table's base in the navigation frame and the IMU's mounting on the platform.
//
// Alignment from the data: before the Kalman filter's first pass, the mean specific force and
// rate of every static dwell of the plan give, by Gauss-Newton least squares,
//   f_k     = R(m)^T C_k^T R(base)^T (-g_n)      + b_a
//   omega_k = R(m)^T C_k^T R(base)^T omega_ie_n  + b_g
// (C_k the dwell's attitude relative to the base, as the plan or the table's angles give it):
// the common rotation m of the triads (the mounting, rotation vector of C_b_p), the base's
// level (from gravity: turns of the platform tell a body-fixed rotation from a navigation-fixed
// one) and heading (from the Earth rate), and rough biases. It is the filter's starting point:
// the coefficients' linearization point and prior centre, the navigation's start attitude.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "filter/kalman/state_layout.hpp"
#include "models/earth.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "rig/io/log_io.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

/// The largest mounting of the IMU on the platform the calibration admits: the alignment puts
/// the filter's linearization within the triads' own misalignments of it (docs/conventions.md).
constexpr double kAdmittedMounting = 2.0 * units::deg;
/// The alignment is the estimators' starting point when its mounting or base angle is beyond this
/// (rad; the Kalman filter: and beyond 3 times the largest accelerometer-misalignment prior
/// sigma): below, the linearization about the plan is as good, and a session without
/// installation errors runs exactly as before.
constexpr double kAlignmentThreshold = 0.1 * units::deg;
constexpr double kAlignmentPriorMultiple = 3.0;
/// ... and only when that angle is beyond this many of its own sigmas: a plan with few dwells
/// (three orientations) determines the alignment poorly, and starting from a 2-sigma mounting
/// made the filter worse than starting from the plan.
constexpr double kAlignmentSignificance = 3.0;
/// Without a sensor profile (the closed form): what the alignment's fit leaves unmodelled, the
/// triads' scale factors and own misalignments, relative to the input (100 ppm, 20 arcsec: a
/// navigation-grade unit), and the time left out at each end of a dwell (the table settling).
constexpr double kAlignmentLinearError = 1e-4;
constexpr double kAlignmentEdge = 0.5;  // s

/// The mean output of a static dwell of the plan.
struct AlignmentDwell {
  int dwell = 0;                                      // the plan's dwell index (1-based)
  Eigen::Matrix3d C_b_n_known;                        // its attitude relative to the base
  Eigen::Vector3d f_b = Eigen::Vector3d::Zero();      // m/s^2, mean accelerometer output
  Eigen::Vector3d omega_b = Eigen::Vector3d::Zero();  // rad/s, mean gyro output
  int samples = 0;
};

/// Mean outputs over each dwell of the timeline, `margin` seconds inside its ends (log time =
/// plan time + time_offset). Dwells without samples are left out.
std::vector<AlignmentDwell> dwell_means(SampleSource& source, const PlanTimeline& timeline,
                                        double time_offset, double margin);

struct Alignment {
  bool valid = false;  // enough dwells of different attitudes to determine it
  /// Whether the estimators start from it: valid, and its mounting or (`with_base`) base angle
  /// beyond `threshold` (rad) and beyond kAlignmentSignificance of its sigma.
  bool significant(double threshold, bool with_base = true) const {
    const auto beyond = [threshold](const Eigen::Vector3d& v, const Eigen::Vector3d& s) {
      return v.norm() > threshold && v.norm() > kAlignmentSignificance * s.norm();
    };
    return valid &&
           (beyond(mounting_b, mounting_sigma_b) || (with_base && beyond(base_n, base_sigma_n)));
  }
  Eigen::Vector3d base_n = Eigen::Vector3d::Zero();  // rad, rotation vector (N, E level; D)
  Eigen::Vector3d base_sigma_n = Eigen::Vector3d::Zero();
  Eigen::Vector3d mounting_b = Eigen::Vector3d::Zero();  // rad, rotation vector of C_b_p
  Eigen::Vector3d mounting_sigma_b = Eigen::Vector3d::Zero();
  int dwells = 0;
};

/// The installation estimates of a run, either method (docs/formats.md "Installation").
struct InstallationResult {
  std::optional<Alignment> alignment;  // runs with KalmanRunOptions::align
  bool alignment_applied = false;      // the filter started from it
  bool alignment_streamed = false;     // from a stream's first dwells (stream_alignment.hpp)
  bool base_estimated = false;         // base states in the filter (attitude updates)
  bool base_known = false;  // not estimated on request (CalibratorOptions::base_attitude off)
  Eigen::Vector3d base_n = Eigen::Vector3d::Zero();  // rad, rotation vector (N, E, D)
  Eigen::Vector3d base_sigma_n = Eigen::Vector3d::Zero();
  bool mounting_estimated = false;                       // body frame = platform (attitude updates)
  Eigen::Vector3d mounting_b = Eigen::Vector3d::Zero();  // rad, mounting_of(model)
  Eigen::Vector3d mounting_sigma_b = Eigen::Vector3d::Zero();
};

/// The alignment from dwell means at `site`. `accel_sigma` (m/s^2) and `gyro_sigma` (rad/s) are
/// the 1-sigma per axis of what the fit does not model (scale factors and the triads' own
/// misalignments times the input, noise); the covariance is scaled by the fit's chi^2/dof when
/// that is above 1.
Alignment align(const std::vector<AlignmentDwell>& means, const Site& site, double accel_sigma,
                double gyro_sigma);

/// The common rotation of the triads that a model relative to the platform carries: the
/// rotation U of the polar decomposition of the accelerometer matrix A = I + K + M = U S (S
/// symmetric positive definite), mounting C_b_p = U^T, as a rotation vector (rad, body axes). It
/// includes the antisymmetric part of the accelerometer triad's own misalignment, which no data
/// can tell from a mounting.
Eigen::Vector3d mounting_of(const ImuErrorModel& model);

/// Its 1-sigma from the covariance of the accelerometer-misalignment states (first order: m_x =
/// (M_yz - M_zy) / 2, m_y = (M_zx - M_xz) / 2, m_z = (M_xy - M_yx) / 2); zero where a
/// misalignment is not a state.
Eigen::Vector3d mounting_sigma(const StateLayout& layout, const Eigen::MatrixXd& P);
/// The same from a covariance over `parameters` (catalog indices; the closed form's stage 2).
Eigen::Vector3d mounting_sigma(const std::vector<int>& parameters, const Eigen::MatrixXd& cov);

}  // namespace sinscal
