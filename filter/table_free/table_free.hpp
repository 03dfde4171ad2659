// Table-free (multi-position, hand-held) calibration of both triads, after Tedaldi, Pretto and
// Menegatti, "A robust and easy to implement method for IMU calibration without external
// equipments", ICRA 2014: the accelerometers from the constancy of gravity's magnitude over the
// static poses, the gyros from the turns between them, then a joint maximum-likelihood refinement
// (Ceres), in the body frame of the accelerometer triad. The model, the stages, the noise and the
// Earth rate: docs/methods/table-free.md.
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
  std::string message;  // the solver's termination
};

/// One part of the joint fit's chi2: the static poses' accelerometer or gyro residuals, or the
/// turns'. `dof` is its residuals less its leverage (the sum of the hat matrix's diagonal over
/// them: the parameters it determines, the poses' directions shared with the other parts by
/// share); the three add up to the joint fit's dof.
struct TableFreeFitPart {
  double chi2 = 0.0;
  int residuals = 0;
  double dof = 0.0;
  /// How much the part's noise model was completed from its residuals (re-estimated until it
  /// settles; docs/methods/table-free.md, "Sigmas and the fit gate"): the turns, the root of
  /// their variance factor max(1, chi2/dof); the static parts, a typical pose mean's sigma with
  /// the bias wander over its white noise's. The sigmas of the coefficients it determines grow
  /// with it.
  double sigma_scale = 1.0;
  /// Static parts: the bias wander found (1-sigma, SI: m/s^2, rad/s) added to every pose mean's
  /// white noise in the fit's weights (0 when the white noise explains the residuals).
  double wander = 0.0;
  double chi2_per_dof() const { return dof > 0.0 ? chi2 / dof : 0.0; }
};

/// One turn between two poses as the fit gate sees it.
struct TableFreeTurn {
  int from = 0;              // the pose it starts from (1-based, as detected)
  double duration = 0.0;     // s
  double angle = 0.0;        // rad: integral of |omega| (nominal) over the turn
  double peak_rate = 0.0;    // rad/s: largest |omega| (nominal) in the turn
  double interval = 0.0;     // s: mean sample interval in the turn
  double noise_sigma = 0.0;  // rad: the fit's 1-sigma per tangent component (noise, Earth)
  double chi2 = 0.0;         // its 2 residuals at the solution
};

struct TableFreeResult {
  ImuErrorModel model;  // the estimated base terms (SI), accelerometer-triad frame
  /// The 24 base coefficients in coefficient_catalog() order, value and sigma (SI).
  std::vector<TableFreeCoefficient> coefficients;
  /// Covariance (SI) of the 21 estimated coefficients, in the order of `covariance_names`
  /// (the coefficients above without the three fixed by convention), of the fit weighted by its
  /// parts' variance factors (accel_fit, gyro_rest_fit, turn_fit sigma_scale squared).
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
  /// "Converged" from the estimate: the Gauss-Newton step still left at the solution is below
  /// kConvergedStep of every coefficient's sigma (step_over_sigma: the largest ratio), the
  /// covariance finite. Says nothing of the chi2: the fit gate judges that.
  static constexpr double kConvergedStep = 0.01;
  bool converged = false;
  double step_over_sigma = 0.0;
  /// Rounds of the parts' variance factors (accel_fit, gyro_rest_fit, turn_fit sigma_scale^2,
  /// the joint fit's weights) and whether they settled within 1 %.
  int variance_rounds = 0;
  bool variance_settled = false;
  std::string termination;  // the solver's message
  /// The joint fit's chi2 in parts (their sigma scales applied to the covariance per block:
  /// accelerometer terms, gyro biases, gyro matrix) and the turns one by one.
  TableFreeFitPart accel_fit, gyro_rest_fit, turn_fit;
  std::vector<TableFreeTurn> turns;
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
