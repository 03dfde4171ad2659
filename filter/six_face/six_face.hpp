// Calibration by hand without a table: the six-face and known-turn procedure of Ferraris, Grimaldi
// and Parvis (1995), as imucal records it. The unit rests on each of its six faces, then is turned
// by hand about each axis, that axis up, through a known angle; the parts are labelled in the log.
// Two linear least-squares problems (accelerometers with each face's placement tilt, then gyros
// from the rests and the turns), the rests' noise from their pooled Allan variance (a hand's
// tremor). The model and why it is so: docs/methods/six-face.md.
#pragma once

#include <Eigen/Core>
#include <array>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "filter/diagnosis/diagnosis_core.hpp"
#include "models/earth.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "rig/ferraris.hpp"
#include "rig/handheld.hpp"
#include "rig/imu_sample.hpp"
#include "rig/session.hpp"

namespace sinscal {

class SixFaceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The scatter of a part's readings over blocks of 1, 2, 4, ... readings (constant memory: the
/// successive differences of the block means at each length), from which the variance of the
/// part's mean follows when its noise is not white: a hand's tremor turns the unit back and forth
/// (the gyros' mean over a rest carries only the net turn between its ends, far less than white
/// noise of the same scatter would give) and tilts it (the accelerometers' readings are correlated
/// over the tremor's period, so their mean scatters more than white noise of the same scatter).
class BlockScatter {
 public:
  using Vector6d = Eigen::Matrix<double, 6, 1>;
  /// One reading: [rate (3), specific force (3)].
  void push(const Vector6d& x) { push_level(0, x); }
  /// The white part W (variance of a mean over 1 s) and the wander's B of each component.
  struct Noise {
    Vector6d white = Vector6d::Zero(), wander = Vector6d::Zero();
    /// The variance of the mean over T s: W / T + (2/3) B / T^2.
    Vector6d var_mean(double T) const;
  };
  /// W and B of the parts' readings (the same sensor and hand: their scatters pooled at each
  /// block length; readings dt s apart): the Allan variance at each block length tau >= tau_min s
  /// (at least 8 blocks in all) fitted per component as W / tau + B / tau^2 (white noise; a wander
  /// that averages out, for which a mean over T has variance (2/3) B / T^2, from the ends' turn),
  /// each term non-negative. Parts too short for two such lengths use their longest two of at
  /// least 4 blocks; fewer than 8 readings, the readings' variance as white.
  static Noise fit(const std::vector<const BlockScatter*>& parts, double dt, double tau_min);
  std::size_t count() const { return count_; }

 private:
  struct Level {
    Vector6d pending = Vector6d::Zero(), last = Vector6d::Zero(), sum_d2 = Vector6d::Zero();
    bool has_pending = false, has_last = false;
    std::size_t diffs = 0;
  };
  std::vector<Level> levels_;
  std::size_t count_ = 0;
  Vector6d sum_ = Vector6d::Zero(), sum2_ = Vector6d::Zero();
  void push_level(std::size_t k, const Vector6d& x);
};

/// The statistics of one labelled part of a log (constant memory: accumulated sample by sample).
struct PartStatistics {
  std::string label;
  std::size_t count = 0;                                      // readings
  double duration = 0.0;                                      // s, sum of the intervals
  double t_start = 0.0, t_end = 0.0;                          // s
  Eigen::Vector3d mean_rate = Eigen::Vector3d::Zero();        // rad/s, gyro output
  Eigen::Vector3d mean_f = Eigen::Vector3d::Zero();           // m/s^2, accelerometer output
  Eigen::Vector3d var_rate = Eigen::Vector3d::Zero();         // (rad/s)^2 per reading
  Eigen::Vector3d var_f = Eigen::Vector3d::Zero();            // (m/s^2)^2 per reading
  Eigen::Vector3d integral_dtheta = Eigen::Vector3d::Zero();  // rad, sum of the increments
  BlockScatter scatter;  // of [rate, f], for the variance of the means (see BlockScatter)
  /// The readings (rates, SI), kept for the parts whose label the accumulator was told to keep
  /// (the turns: a few seconds each), empty otherwise.
  std::vector<ImuReading> readings;
};

/// Accumulates parts from samples with a label each: a part is a run of samples with the same
/// label; a label that comes back after another part is an error (parts are contiguous).
class PartAccumulator {
 public:
  /// `keep`: labels whose readings are kept (the turns).
  explicit PartAccumulator(std::vector<std::string> keep = {}) : keep_(std::move(keep)) {}
  /// `label` empty: the sample belongs to no part (between parts). Throws SixFaceError.
  void push(const ImuSample& sample, const std::string& label);
  const std::vector<PartStatistics>& parts() const { return parts_; }

 private:
  std::vector<PartStatistics> parts_;
  std::vector<std::string> keep_;
  bool keeping_ = false;
  std::string current_;
  Eigen::Vector3d m2_rate_ = Eigen::Vector3d::Zero(), m2_f_ = Eigen::Vector3d::Zero();
  void close();
};

struct SixFaceOptions {
  FerrarisDeclaration declared;  // labels and the hand's accuracies
  double gravity = 0.0;          // m/s^2; 0: normal gravity at `site`
  std::optional<Site> site;      // the Earth rate's vertical part; without: noise
  /// A turn whose integrated angle (with the nominal scaling) is farther than this from the
  /// declared one is not the declared turn (wrong axis, direction or rate).
  double turn_tolerance = 30.0 * units::deg;
  /// 1-sigma of each triad's in-run bias (Gauss-Markov bias instability, from the sensor profile
  /// when one is given): a session of minutes is shorter than its correlation time, so it is a
  /// common offset of every rest that the readings' own scatter does not show; it adds to the
  /// biases' variance (rad/s, m/s^2).
  double gyro_bias_instability = 0.0, accel_bias_instability = 0.0;
  /// Estimate the gyro g-sensitivity K too (gyro.g_sensitivity, 9 terms: w_meas = G w + b + K f):
  /// the rests' gyro means against their six specific-force directions, and each turn's mean
  /// specific force. Off: K is taken as zero (the base model).
  bool g_sensitivity = false;
  double alpha = 0.01;  // the g-sensitivity test's significance level
};

/// The test of the gyro g-sensitivity on the rests (SixFaceOptions::g_sensitivity): K's estimate
/// against zero by its covariance (TestVerdict): "wald", the statistic K^T P^-1 K on 9 degrees
/// of freedom, the threshold alpha, significant: detected.
struct GSensitivityTest : TestVerdict {
  Eigen::Matrix3d K = Eigen::Matrix3d::Zero();        // rad/s per m/s^2
  Eigen::Matrix3d K_sigma = Eigen::Matrix3d::Zero();  // rad/s per m/s^2
  /// rad/s per m/s^2: the largest component K can have unseen: sqrt(chi2_9(1 - alpha)) times the
  /// largest component sigma (a K of that size along its worst direction just reaches the
  /// threshold).
  double detection_limit = 0.0;
};

struct SixFaceCoefficient {
  std::string name;                 // coefficient_catalog() name
  double value = 0.0, sigma = 0.0;  // SI
};

struct SixFaceFace {
  std::string label;
  double duration = 0.0;                                 // s
  Eigen::Vector2d tilt = Eigen::Vector2d::Zero();        // rad, estimated placement tilt
  Eigen::Vector2d tilt_sigma = Eigen::Vector2d::Zero();  // rad
  double gravity_error = 0.0;                            // |A^-1 (m - b)| - g, m/s^2
};

struct SixFaceTurn {
  std::string label;
  double duration = 0.0;  // s
  double angle = 0.0;     // rad: the calibrated gyros' angle about the turn's axis
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();  // body, unit: the mean specific force's
};

struct SixFaceResult {
  ImuErrorModel model;                           // base terms, SI, the faces' frame
  std::vector<SixFaceCoefficient> coefficients;  // 24 base terms (33 with K), catalog order
  std::vector<SixFaceFace> faces;
  std::vector<SixFaceTurn> turns;
  double gravity = 0.0;     // m/s^2 used
  double accel_chi2 = 0.0;  // of the accelerometer fit (priors included)
  int accel_dof = 0;
  double earth_rate_bound = 0.0;  // rad/s: the Earth rate not modelled (noise), per axis
  /// What the procedure cannot determine, one sentence each.
  std::vector<std::string> undetermined;
  /// With SixFaceOptions::g_sensitivity: the test (its K also in `coefficients` and `model`).
  std::optional<GSensitivityTest> g_test;
};

/// A six-face session's parts, read from its log's label column (the turns' readings kept).
/// Throws LogError naming the file and line: no label column, a part that comes back.
std::vector<PartStatistics> read_parts(const Session& session);
/// The options a session gives: its declaration, gravity, site, and its profile's bias
/// instabilities (when it names a sensor profile).
SixFaceOptions six_face_options(const Session& session);

/// The calibration from the parts (the nine declared labels must all be present; other labels
/// are ignored). Throws SixFaceError naming the part and the cause: a missing or repeated part,
/// a face shorter than min_rest, a face whose reading is not near its declared axis, a turn far
/// from its declared angle or axis.
SixFaceResult six_face_calibrate(const std::vector<PartStatistics>& parts,
                                 const SixFaceOptions& options);

}  // namespace sinscal
