// Table-free (multi-position, hand-held) calibration of both triads, after Tedaldi, Pretto and
// Menegatti, "A robust and easy to implement method for IMU calibration without external
// equipments", ICRA 2014, in sinscal's one error model (models/imu_error_model.hpp):
//
//   y = (I + diag(k) + M) x + b      for each triad; base terms only
//
// with the body frame of the accelerometer triad (docs/conventions.md: accel.misalignment.xy,
// .xz, .yz are zero by this convention), so A = I + diag(k_a) + M_a is lower triangular.
//
// Stages (nonlinear least squares with Ceres):
//  1. Accelerometers: at rest the specific force's magnitude is local gravity g in every pose:
//     minimise sum_p (|A^-1 (y_p - b_a)| - g)^2 / sigma_p^2 over the 9 accelerometer terms.
//  2. Gyros: the bias from the static poses' mean rate; scale factors and misalignments from the
//     turns between poses: the calibrated rates G^-1 (y_g - b_g), integrated from the end of pose
//     p to the start of pose p+1 (rotation vectors with a two-sample coning term, quaternion
//     product), must turn the gravity direction the calibrated accelerometers see in pose p
//     into the one they see in pose p+1.
//  3. Joint refinement, the maximum-likelihood form of the same model: parameters are both
//     triads' terms plus the gravity direction u_p of every pose (a unit vector, Ceres
//     SphereManifold); residuals, each with its own noise and mutually independent for white
//     noise: the pose's mean specific force y_a,p - (A g u_p + b_a) (per-axis noise / sqrt(n)),
//     its mean rate y_g,p - (b_g + G w_v,p), and each turn's two tangent components of
//     R^T u_p - u_p+1 (gyro noise integrated over the turn).
//  Sigmas: the covariance of the joint solution (Ceres Covariance, dense SVD) scaled by
//  chi2/dof of its residuals.
//
// The noise of the residuals comes from the data: the per-reading variance of each axis pooled
// over the static poses (white noise assumed: a mean over n readings has variance / n; the rate
// noise density integrates over a turn's duration).
//
// Earth rate: the gyros at rest read b_g + G w_ie_b, w_ie_b of size 15 deg/h. Its vertical part
// (Omega sin(lat) along the pose's gravity direction) is modelled when the site is known; its
// horizontal part (Omega cos(lat)) points along the unknown heading of each pose, so it enters as
// noise of the pose's mean rate in the two horizontal directions only (variance
// (Omega cos(lat))^2 / 2 each, for a uniformly random heading), and of the turns (the gravity
// direction moves by up to Omega cos(lat) T during a turn of T s). Each pose so measures the
// bias along its own vertical to the white-noise level, and poses in many directions give all
// three components to that level: the horizontal Earth rate costs little even for a tactical
// gyro (Monte Carlo: 0.3 deg/h sigma at ARW 0.05 deg/sqrt(h), errors consistent with it). For a
// MEMS gyro (bias 0.1-2 deg/s) the Earth rate is far below the bias and comparable to the noise
// of a few-second pose. Without a site, the whole Earth rate is taken as noise of random
// direction (variance Omega^2 / 3 per axis).
#pragma once

#include <Eigen/Core>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "filter/table_free/pose_detector.hpp"
#include "models/earth.hpp"
#include "models/imu_error_model.hpp"
#include "rig/handheld.hpp"

namespace sinscal {

class TableFreeError : public std::runtime_error {
 public:
  enum class Kind {
    BadInput,      // readings or options unusable (units, times, gravity)
    TooFewPoses,   // fewer poses than the model needs
    PoseTooShort,  // a pose too short for its mean after the edges are trimmed
    SolveFailed,   // the least-squares solution did not converge or is singular
  };
  TableFreeError(Kind kind, const std::string& what) : std::runtime_error(what), kind_(kind) {}
  Kind kind() const { return kind_; }

 private:
  Kind kind_;
};

struct TableFreeOptions {
  /// Local gravity magnitude (m/s^2); 0: WGS-84 normal gravity at `site` (models/earth.hpp).
  double gravity = 0.0;
  /// The site: gravity (when not given) and the Earth rate's vertical part. Without it the
  /// gravity must be given and the Earth rate is noise of unknown direction.
  std::optional<Site> site;
  /// s cut from each end of a pose before its mean is taken; the turns are integrated across
  /// the cut, so readings at the edges of a pose that move a little do no harm.
  double edge_trim = 0.2;
  /// s: shortest pose after trimming (shorter: TableFreeError PoseTooShort).
  double min_pose = 1.0;
  /// The poses needed: the accelerometer stage has 9 unknowns and one equation per pose, and
  /// needs at least one more for a residual (this is the minimum; Tedaldi et al. advise 36-50).
  int min_poses = 10;
  int max_iterations = 200;
};

/// One base coefficient of the result, SI (names and units of coefficient_catalog()).
struct TableFreeCoefficient {
  std::string name;
  double value = 0.0;
  double sigma = 0.0;                // 0 when fixed by convention
  bool fixed_by_convention = false;  // accel.misalignment.xy, .xz, .yz
};

/// Raw-count view of one triad: counts = sensitivity .* x + offset along each sensor's own axis
/// (sensitivity = nominal * (1 + k), offset = nominal offset + nominal sensitivity * b).
struct RawTriadView {
  Eigen::Vector3d sensitivity = Eigen::Vector3d::Zero();  // counts per SI unit of the input
  Eigen::Vector3d sensitivity_sigma = Eigen::Vector3d::Zero();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();  // counts
  Eigen::Vector3d offset_sigma = Eigen::Vector3d::Zero();
  /// Norm of each sensor's row of counts per SI unit (the sensitivity along its own sensitive
  /// axis, whatever the body frame): comparable across misalignment conventions.
  Eigen::Vector3d row_norm = Eigen::Vector3d::Zero();
};

/// Residuals of one pose at the solution.
struct TableFreePoseFit {
  int index = 0;                    // the pose's index (1-based, as detected)
  double t_start = 0.0;             // s: the trimmed stretch used for the means
  double t_end = 0.0;               // s
  std::size_t count = 0;            // readings averaged
  double gravity_error = 0.0;       // |f_p| - g (m/s^2), f_p the calibrated mean specific force
  double accel_rms = 0.0;           // RMS over the axes of y_a,p - (A g u_p + b_a) (m/s^2)
  double gyro_rms = 0.0;            // RMS over the axes of y_g,p - (b_g + G w_v,p) (rad/s)
  double turn_error = 0.0;          // rad: angle between the gravity direction the turn into this
                                    // pose predicts and the pose's own (0 for the first pose)
  std::size_t first = 0, last = 0;  // readings of the trimmed stretch (indices)
  /// Unit direction of the pose's specific force at the solution (u_p, body axes).
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  double turn_sigma = 0.0;  // rad: 1-sigma of each tangent component of the turn into this pose
};

struct TableFreeStage {
  int iterations = 0;
  bool converged = false;
  double chi2 = 0.0;
  int residuals = 0;
  int parameters = 0;
};

struct TableFreeResult {
  ImuErrorModel model;  // the estimated base terms (SI), accelerometer-triad frame
  /// The 24 base coefficients in coefficient_catalog() order, value and sigma (SI).
  std::vector<TableFreeCoefficient> coefficients;
  /// Covariance (SI) of the 21 estimated coefficients, in the order of `covariance_names`
  /// (the coefficients above without the three fixed by convention); scaled by chi2/dof.
  Eigen::MatrixXd covariance;
  std::vector<std::string> covariance_names;
  bool has_raw = false;  // raw views filled (the readings were counts with a nominal scaling)
  RawTriadView accel_raw, gyro_raw;
  std::vector<TableFreePoseFit> poses;
  double gravity = 0.0;  // m/s^2 used
  double chi2 = 0.0;     // of the joint solution
  int dof = 0;
  double chi2_per_dof = 0.0;
  int iterations = 0;  // all stages
  bool converged = false;
  TableFreeStage accel_stage, gyro_stage, joint_stage;
  /// Per-reading noise at rest, pooled over the poses (SI): accel m/s^2, gyro rad/s.
  Eigen::Vector3d accel_noise = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_noise = Eigen::Vector3d::Zero();

  /// The coefficient by name; throws std::invalid_argument for a name not in the result.
  const TableFreeCoefficient& at(const std::string& name) const;
};

/// Calibrates from readings in SI (rates: m/s^2 and rad/s, e.g. counts through a nominal
/// scaling, the result then relative to it) and the static poses found in them. Throws
/// TableFreeError.
TableFreeResult calibrate_table_free(const std::vector<ImuReading>& readings_si,
                                     const std::vector<Pose>& poses,
                                     const TableFreeOptions& options);

/// The raw-count path: detects the poses in the counts, converts with the nominal scaling (the
/// starting values), calibrates, and fills the raw views. Throws TableFreeError (a pose-detector
/// failure becomes BadInput).
TableFreeResult calibrate_table_free_counts(const std::vector<ImuReading>& counts,
                                            const RawScaling& nominal,
                                            const TableFreeOptions& options,
                                            const PoseDetectorOptions& detector = {});

}  // namespace sinscal
