// Rate-table and tumble calibration from segment means (the practice of IEEE Std 952 / 1431 for
// gyros and IEEE Std 1293 for accelerometers): a plan's constant-rate segments about body axes
// and its static positions (dwells, pauses, the faces of a tumble), each found in the log in the
// plan's order without using the log's time, reduced to its mean outputs; one weighted linear
// least squares over every mean gives both triads' biases, scale factors, misalignments (with
// cross-axis sensitivity: from means alone they are one 3x3 matrix), gyro scale-factor asymmetry
// and nonlinearity across rates, gyro g-sensitivity, and the accelerometers' K2 and K3 (the
// polynomial in f), each only when the segments determine it. The Earth rate is in the model.
// Means need no integration, so a log with irregular or no time works. docs/methods/rate-table.md.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "models/earth.hpp"
#include "rig/io/log_io.hpp"
#include "rig/plan.hpp"

namespace sinscal {

class RateTableError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// What the plan says of one segment, in the plan's order.
struct RateSegment {
  enum class Kind { Static, Rate };
  Kind kind = Kind::Static;
  std::string label;
  Eigen::Matrix3d C_b_n_known = Eigen::Matrix3d::Identity();  // static; rate: at its start
  Eigen::Vector3d axis_b = Eigen::Vector3d::UnitZ();          // rate: unit, signed
  double rate = 0.0;                                          // rad/s (rate), positive
  double duration = 0.0;   // s: the dwell, or the time at the constant rate (plan)
  double angle = 0.0;      // rad turned at the constant rate (plan)
  std::size_t number = 0;  // 1-based position in the plan's segments (what messages name)
};

/// The plan's static dwells and rate-table segments in order (known-angle turns and moves are
/// not used: their means carry no known input). Throws RateTableError when there is none.
std::vector<RateSegment> rate_segments(const Plan& plan, const Site& site);

/// One reading of a log: rates (rad/s) and specific force (m/s^2), the sample's increments over
/// its interval (a log of rates gives them back whatever its time column).
struct RateReading {
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
};

/// Every reading of a log as rates and specific force (its increments over its interval); throws
/// LogError naming the file and line (a reading without an interval, no readings). With
/// `on_skip`, bad readings (a NaN field, a damaged line) are left out and passed to it instead of
/// stopping the read (`calibrate --on-bad-sample skip`).
std::vector<RateReading> read_rate_readings(
    const LogFormat& log, const std::function<void(const BadSampleError&)>& on_skip = nullptr);

/// The means of one segment found in the log.
struct SegmentMean {
  std::size_t first = 0, last = 0;  // reading indices [first, last) used (trimmed)
  std::size_t count = 0;
  Eigen::Vector3d omega = Eigen::Vector3d::Zero(), f = Eigen::Vector3d::Zero();          // means
  Eigen::Vector3d var_omega = Eigen::Vector3d::Zero(), var_f = Eigen::Vector3d::Zero();  // /read
  /// Each output's integrated autocorrelation time in readings (at least 1): the mean's variance
  /// is var * tau / count, an effective sample count count / tau. Outputs that toggle between
  /// levels or ripple stay correlated over many readings (the APOPHIS BMI160 logs).
  Eigen::Vector3d tau_omega = Eigen::Vector3d::Ones(), tau_f = Eigen::Vector3d::Ones();
};

struct RateTableOptions {
  double nominal_rate_hz = 100.0;  // readings per second, for the segments' expected lengths
  double static_threshold = 3.0 * M_PI / 180.0;  // rad/s: a mean rate above is motion
  /// rad/s plus this fraction of the commanded rate: how far a rate segment's reading may be
  /// from the commanded one (large errors: consumer MEMS).
  double rate_tolerance = 0.15;
  double smoothing = 0.5;     // s: the detector's centred moving average (nominal readings)
  double min_fraction = 0.3;  // a run shorter than this fraction of the plan's segment: skipped
  double table_sigma = 0.0;   // rad per axis and static position (the table's attitude error)
  /// The gyros' response to |rate| across each turn's axis (gyro.cross_asym.ij: gyro i's output
  /// per |omega_j|, i != j; the even part of the cross-axis response, as the scale-factor
  /// asymmetry is along it), taken with the scale asymmetries before the g-sensitivity, which a
  /// single gravity direction cannot tell from them (calibrate --cross-asymmetry).
  bool cross_asymmetry = false;
  /// The gyros' bias drift over the log (gyro.bias_drift.i, rad/s^2): each segment's mean at its
  /// middle reading's time at the nominal rate (index / nominal_rate_hz; the log's own time is not
  /// read). A BMI160 warming up on a tumble drifts by 0.01-0.04 deg/s over its 7 rests, several
  /// times its means' noise (calibrate --gyro-drift).
  bool gyro_drift = false;
};

/// Finds the segments in the readings in order (the k-th run that matches the k-th segment; a
/// static run: the smoothed rate below static_threshold; a rate run: within the tolerance of the
/// commanded rate vector), each trimmed by the smoothing window and 5 % at both ends. Throws
/// RateTableError naming the first segment not found.
std::vector<SegmentMean> find_segments(const std::vector<RateReading>& readings,
                                       const std::vector<RateSegment>& segments,
                                       const RateTableOptions& options);

/// Each output's autocorrelation time floored by its readings-weighted mean over all `means` (the
/// same sensor; the long segments dominate it): a segment only a few times its outputs'
/// correlation long gives too short a time (its own mean takes part of the correlation out, its
/// few lags leave the tail unseen). White outputs keep 1. find_segments applies it.
void floor_by_pooled(std::vector<SegmentMean>& means);

struct RateCoefficient {
  std::string name;  // catalog name (e.g. "gyro.scale.x") or rate-table only: gyro.k2.*,
                     // gyro.cross_asym.*, accel.k3.*
  double value = 0.0, sigma = 0.0;  // SI (k2: 1/(rad/s) or 1/(m/s^2); k3 its square)
  bool in_catalog = true;  // false: gyro.k2, gyro.cross_asym, accel.k3 (not in the schema's model)
};

/// A rest whose outputs are not stationary (filter/rate_table/unsteady_rests.hpp): its largest
/// level change beyond its quantile, and what was done with the rest.
struct UnsteadyRest {
  std::size_t segment = 0;          // index in the plan's segments
  int output = 0;                   // 0-2 gyro x y z, 3-5 accelerometer x y z
  std::size_t first = 0, last = 0;  // the rest's readings [first, last)
  std::size_t at = 0;               // the first reading at the later level
  double change = 0.0;              // SI (rad/s, m/s^2): the later level less the earlier one
  double sigma = 0.0;               // the split's chi2 gain as a normal deviate (its square root)
  double quantile = 0.0;  // the gain's quantile as a normal deviate (Bonferroni over the splits)
  double scatter_ratio = 0.0;  // the rest's readings' scatter over the other rests'
  /// The rest's means against the fit of the other segments: the coefficients' shift when it is
  /// left out, chi2 in the shift's covariance (P without it less P with it), its dof and quantile.
  double others_chi2 = 0.0, others_quantile = 0.0;
  int others_dof = 0;
  bool excluded = false;  // left out of the estimate
  std::string statement;  // what a user reads (text and JSON)
};

struct RateTableResult {
  std::vector<RateCoefficient> coefficients;
  Eigen::MatrixXd covariance;             // of the coefficients, in their order (SI)
  std::vector<std::string> undetermined;  // parameter names the segments do not determine
  double chi2 = 0.0;
  int dof = 0;
  /// Each triad's share of the fit (its rows and coefficients are its own): "gyro", "accel".
  struct TriadFit {
    std::string triad;
    double chi2 = 0.0;
    int dof = 0;
  };
  std::vector<TriadFit> triad_fits;
  std::size_t static_segments = 0, rate_segments = 0;
  std::vector<SegmentMean> means;
  /// Each segment's residuals in its own sigmas (whitened, the data less the fit: gyro x y z,
  /// accelerometer x y z; NaN where a segment has no row: the accelerometers of a rate segment, or
  /// of a fit without them).
  std::vector<Eigen::Matrix<double, 6, 1>> residual_sigma;
  /// Rests whose outputs are not stationary, each left out of the fit or kept, said so
  /// (rate_table_calibrate_rests; empty from rate_table_calibrate).
  std::vector<UnsteadyRest> unsteady;
};

/// "segment 7 (label)": its plan position (`number`, else index + 1) and label.
std::string segment_name(const RateSegment& s, std::size_t index);

/// The largest whitened residual of a fit, named: "segment 7 (label): gyro y -5.9 sigma" (empty
/// without residuals). What a refused fit's user looks at first.
/// With `triad` ("gyro", "accel") only that triad's residuals: a refusal names the triad that
/// failed, not the largest of one that passed.
std::string largest_residual(const RateTableResult& r, const std::vector<RateSegment>& segments,
                             const std::string& triad = "");

/// The calibration from the segments' means at `site` (gravity: its normal gravity, or
/// `gravity` m/s^2 when positive). Throws RateTableError when nothing can be estimated.
RateTableResult rate_table_calibrate(const std::vector<RateSegment>& segments,
                                     const std::vector<SegmentMean>& means, const Site& site,
                                     double gravity, const RateTableOptions& options);

}  // namespace sinscal
