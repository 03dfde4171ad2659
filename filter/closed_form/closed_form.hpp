// The source paper's closed-form calibration, faithful and generalized: stage 1 turns each static
// dwell's navigation errors into equivalent accelerometer and gyro errors (the paper's single-time
// formulas, or a weighted fit over the dwell), stage 2 solves the 24 base coefficients for any
// static plan by weighted least squares, with the paper's literal closed forms for its
// 8-orientation plan. docs/methods/closed-form.md; the paper: docs/methods/source-paper.md.
#pragma once

#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "filter/installation/installation.hpp"
#include "filter/strapdown/ins_error_model.hpp"
#include "filter/strapdown/strapdown.hpp"
#include "models/imu_error_model.hpp"
#include "models/noise_model.hpp"
#include "rig/imu_sample.hpp"
#include "rig/session.hpp"
#include "rig/table.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

struct SensorProfile;

enum class Stage1Method { Point, Fit };

struct ChannelSet {
  bool north = true;
  bool east = true;
  bool vertical = false;
  bool heading = false;
  /// Which of the 6 inputs (df_n, df_e, df_d, dw_n, dw_e, dw_d) the channels give.
  std::array<bool, 6> inputs() const;
};

struct Stage1Options {
  Stage1Method method = Stage1Method::Fit;
  ErrorModelKind model = ErrorModelKind::Uncoupled;
  ChannelSet channels;
  double point_time = 0.0;  // s from the dwell start; 0: the end of the dwell
  double arw = 0.0;         // rad/sqrt(s), gyro white noise density (weights, sigma)
  double vrw = 0.0;         // m/s/sqrt(s), accelerometer white noise density
  double min_dwell = 20.0;  // s: a shorter dwell is an error
  StrapdownOptions strapdown;
};

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// Stage-1 result of one dwell.
struct EquivalentInputs {
  PlanDwell dwell;
  double duration = 0.0;  // s navigated
  std::size_t samples = 0;
  Vector6d u = Vector6d::Zero();    // df_n (m/s^2, NED), dw_n (rad/s, NED)
  Matrix6d cov = Matrix6d::Zero();  // of the estimated inputs; rows of the others are zero
  std::array<bool, 6> estimated{};  // which inputs this stage gave
  double rms_velocity = 0.0;        // m/s: RMS one-step residual of the velocity rows (fit)
  double rms_attitude = 0.0;        // rad: of the attitude rows (fit)
  double chi2_per_dof = 0.0;  // residual chi-square per degree of freedom under the noise model
  /// The log's temperatures over the dwell (a log with temperature columns): the means (deg C)
  /// and the gyros' mean rate of change (deg C/s, last minus first over the time between).
  bool has_temperature = false;
  double accel_temperature_c = 0.0, gyro_temperature_c = 0.0, gyro_temperature_rate = 0.0;
};

/// The command line's stage 1: the coupled model, all four channels, and the white-noise
/// densities of the sensor profile (nullptr: zero, to be given).
Stage1Options default_stage1(const SensorProfile* profile);

/// Runs the navigator through every dwell and stage 1 on it. Throws PlanMismatch (dwell missing
/// from the log) or std::invalid_argument (dwell shorter than min_dwell, no noise densities).
std::vector<EquivalentInputs> run_stage1(SampleSource& source, const std::vector<PlanDwell>& dwells,
                                         const Site& site, const Stage1Options& options,
                                         double time_offset = 0.0,
                                         const std::string& input = "the log");

/// The coefficients stage 2 solves for: the base families of the family table
/// (models/coefficient_families.hpp), as catalog indices in catalog order.
std::vector<int> stage2_parameters();

/// u = H theta at a static attitude (theta in SI, `parameters` catalog indices): the error
/// model's Jacobian (models/imu_error_model.hpp) at the static inputs f_b = -C^T g_n and
/// omega_ib_b = C^T omega_ie_n, rotated to NED: df_n = C J_accel theta, dw_n = C J_gyro theta.
/// `t` (s since the start of the plan; a dwell's middle) for the time-dependent terms,
/// `temperature` (its accel_dtemp, gyro_dtemp, gyro_dtemp_rate; null: zero) for the thermal ones.
Eigen::Matrix<double, 6, Eigen::Dynamic> equivalent_input_map(
    const Eigen::Matrix3d& C_b_n, const Site& site, const std::vector<int>& parameters,
    double t = 0.0, const KinematicSample* temperature = nullptr);
/// The map at a dwell: its known attitude, its middle, its temperatures from T0 (deg C).
Eigen::Matrix<double, 6, Eigen::Dynamic> equivalent_input_map(const EquivalentInputs& in,
                                                              const Site& site,
                                                              const std::vector<int>& parameters,
                                                              double reference_temperature_c);
/// The covariance stage 2 gives a dwell's equivalent inputs: stage 1's plus the table's attitude
/// error aliased into them (df_n += f_n x eps, dw_n += omega_ie_n x eps).
Matrix6d stage2_input_covariance(const EquivalentInputs& in, const Site& site,
                                 const TableAttitudeError& table);
/// The covariance between two dwells' equivalent inputs that the sensors' bias wander gives (both
/// the same dwell: its variance): the bias instability as a first-order Gauss-Markov process and
/// the rate (acceleration) random walk of `noise`, each dwell's input the mean bias over the time
/// it was navigated, rotated to NED by each dwell's attitude. Zero for a noise model without them.
Matrix6d stage2_wander_covariance(const EquivalentInputs& a, const EquivalentInputs& b,
                                  const NoiseModel& noise);
/// The stage-2 parameters of a model (SI), in the order of `parameters`.
Eigen::VectorXd parameter_vector(const class ImuErrorModel& model,
                                 const std::vector<int>& parameters);

struct Stage2Options {
  /// The table's attitude error at each orientation (rig/table.hpp: the one model both methods
  /// use); it aliases into the inputs as df_n += f_n x eps, dw_n += omega_ie_n x eps.
  TableAttitudeError table;
  double null_tolerance = 1e-9;  // relative singular value below which a direction is unobservable
  std::vector<int> parameters = stage2_parameters();
  /// Three more parameters: the error of the table base attitude common to every dwell (rotation
  /// vector, NED, true minus the dwells' known attitudes' base; docs/conventions.md "Table base
  /// and mounting"), aliasing into every dwell as the table's attitude error does.
  bool base_attitude = false;
  /// T0 of the thermal coefficients (deg C): the dwells' temperatures enter as T - T0.
  double reference_temperature_c = 25.0;
  /// The sensors' bias wander between dwells (its bias instability and random walk; the white
  /// noise is stage 1's): the dwells' inputs correlated across dwells (stage2_wander_covariance).
  /// Default none: independent dwells.
  NoiseModel bias_wander;
};

struct Stage2Result {
  std::vector<int> parameters;  // catalog index of each entry
  Eigen::VectorXd theta;        // SI; unobservable entries are NaN
  Eigen::MatrixXd cov;          // rows/columns of unobservable entries NaN
  std::vector<bool> observable;
  int rank = 0;
  std::vector<std::string> unobservable_directions;  // e.g. "+0.577 accel.scale.x +0.577 ..."
  std::vector<Eigen::VectorXd> null_vectors;         // in coefficient space (unit norm)
  /// The minimum-norm solution (Jacobi-scaled) and its covariance, every entry finite: a
  /// combination c of the coefficients orthogonal to every null vector is determined by the
  /// data, c^T theta_min_norm with variance c^T cov_min_norm c (the coefficients first, as in
  /// `parameters`, then the base's three when estimated).
  Eigen::VectorXd theta_min_norm;
  Eigen::MatrixXd cov_min_norm;
  /// Stage-2 residual: chi-square of the equivalent inputs against the solution per degree of
  /// freedom (inputs minus rank); 1 when the model explains the dwells to their sigmas.
  double chi2_per_dof = 0.0;
  int dof = 0;
  /// With Stage2Options::base_attitude: the base's error (rad, NED) and its covariance.
  bool base_estimated = false;
  bool base_observable = false;
  Eigen::Vector3d base_n = Eigen::Vector3d::Zero();
  Eigen::Matrix3d base_cov = Eigen::Matrix3d::Zero();
};

Stage2Result solve_stage2(const std::vector<EquivalentInputs>& inputs, const Site& site,
                          const Stage2Options& options);

/// The paper's closed forms for the X and Z sensors of the 8-orientation plan, literally
/// (X as printed, with the OCR-lost signs of docs/methods/source-paper.md; Z derived the same way).
/// `inputs` are the 8 dwells in the paper's order. SI units.
struct PaperClosedForms {
  double w0x, dkgx, nu_xy, nu_xz;  // X gyro: bias, scale, misalignments
  double w0z, dkgz, nu_zx, nu_zy;  // Z gyro
  double f0x, mu_xy, mu_xz;        // X accelerometer: bias, misalignments
  double f0z, mu_zx, mu_zy;        // Z accelerometer
};
PaperClosedForms paper_closed_forms(const std::vector<EquivalentInputs>& inputs, const Site& site);

/// The paper's closed forms beside the names of the coefficients they give, in the paper's order.
std::vector<std::pair<std::string, double>> named(const PaperClosedForms& p);

/// The whole method on a recorded session: navigation through every dwell, stage 1, stage 2.
struct ClosedFormReport {
  /// The alignment from the dwells (filter/installation/installation.hpp); when applied, the
  /// samples were turned by its mounting and the dwells' attitudes by its base before stage 1, and
  /// stage 2's coefficients turned back relative to the platform. The base attitude (the
  /// alignment's, if applied, turned by stage 2's correction), the mounting of the stage-2
  /// coefficients, and the alignment.
  InstallationResult installation;
  Stage1Options stage1_options;
  Stage2Options stage2_options;
  std::vector<EquivalentInputs> stage1;
  Stage2Result stage2;
  bool has_paper_forms = false;  // the plan is the paper's 8-orientation table
  PaperClosedForms paper{};
  /// Relinearization (run_closed_form_relinearized): how many times stage 1 ran, the gyro biases
  /// the samples were compensated with before the last (rad/s; stage2.theta includes them), and
  /// the first linearization's stage-2 gyro biases (rad/s).
  int linearizations = 1;
  Eigen::Vector3d removed_gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d first_gyro_bias = Eigen::Vector3d::Zero();
  /// Stage 1's linear range in the last linearization: the dwell where the gyros' equivalent
  /// input turned the attitude farthest against its bound (closed_form_turn, rad).
  std::string largest_turn_dwell;
  double largest_turn = 0.0, linear_turn = 0.0;
  /// The same for the accelerometers: the dwell whose equivalent inputs drove the navigator's
  /// velocity farthest against its bound (closed_form_turn, m/s), and whether the samples were
  /// compensated with the accelerometers' bias, scale and misalignment before the last
  /// linearization (stage2.theta holds the totals).
  std::string largest_speed_dwell;
  double largest_speed = 0.0, linear_speed = 0.0;
  bool removed_accel = false;
};

/// The attitude a dwell's gyro equivalent inputs turn over the dwell (|dw| x duration, rad), and
/// the turn stage 1's linear model tolerates there: its neglected second-order term g phi^2 / 2
/// at the dwell's end equal to the sigma of the dwell's horizontal accelerometer inputs. The
/// same for the velocity error the accelerometer inputs build up (|df| x duration, m/s): the
/// navigator's transport-rate and centripetal terms of it, of second order (v^2 / R), reach that
/// sigma at v = sqrt(sigma_f R).
struct DwellTurn {
  double turn = 0.0, bound = 0.0;
  double speed = 0.0, speed_bound = 0.0;
};
DwellTurn closed_form_turn(const EquivalentInputs& e, const Site& site);

/// `align`: align from the dwells first and estimate the base in stage 2 (the command line's
/// default); false: the plan's attitudes as they are, no base. `about`: the samples compensated
/// with this model first (its inverse, ImuErrorModel::compensate), so that stage 1 linearizes
/// about it and stage 2 gives corrections to it (errors too large for one linearization about
/// zero: MEMS).
ClosedFormReport run_closed_form(const Session& session, const Stage1Options& stage1,
                                 const TableAttitudeError& table, bool align = true,
                                 const class ImuErrorModel* about = nullptr);

/// The closed form linearized about its own gyro biases: while a dwell's gyro inputs turn the
/// attitude beyond stage 1's linear range (closed_form_turn), the samples are compensated with
/// the stage-2 gyro biases so far and stage 1 and 2 run again (at most `max_linearizations`
/// times). While its accelerometer inputs drive the velocity beyond the range (a pass within the
/// gyros' range, every accelerometer coefficient determined), the samples are compensated with
/// the accelerometers' bias, scale and misalignment too. The report's coefficients are the
/// totals (with their covariance); its largest turn and speed say whether the last linearization
/// is within the range (the gate refuses it otherwise, naming the gyros or accelerometers).
ClosedFormReport run_closed_form_relinearized(const Session& session, const Stage1Options& stage1,
                                              const TableAttitudeError& table,
                                              int max_linearizations = 4);

}  // namespace sinscal
