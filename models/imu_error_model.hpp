// The IMU error model: one formula for both triads, used by the simulator, the filter and `apply`.
//
//   y = (I + diag(k) + M) x + a .* |x| + k2 .* x .* x + b + extra
//
//   x      true input along body axes: omega_ib_b (rad/s) for gyros, f_ib_b (m/s^2) for accels
//   y      sensor output, same units
//   b      bias, drifting linearly: b + d t (d the bias drift, t the time since the start of
//          the plan);  k  scale-factor error;  M  misalignment (off-diagonal; M(i,j) = angle of
//          sensor axis i towards body axis j);  a  scale-factor asymmetry (half the difference
//          between the scale factors for positive and negative input);  k2  quadratic scale factor
//   extra  gyros: g-sensitivity G * f_ib_b (G(i,j): gyro axis i, acceleration axis j)
//          accels: size effect, accelerometer i sees e_i . (dw/dt x r_i + w x (w x r_i)) with r_i
//          the position of its proof mass relative to the IMU reference point (body axes)
//
// Thermal terms, with dT = T - T0 the triad's temperature relative to the model's reference
// temperature T0 (deg C) and p = (dT, dT^2, dT^3):
//   b -> b + B p + r dT/dt   (B column d: the bias's degree-d coefficient; r: gyros only)
//   k -> k + S p             (S column d: the scale factor's)
//   M -> M + M1 dT           (M1: the misalignments' temperature coefficients)
// The size effect's sensitive axes stay those at T0 (a thermal change of them is of second order).
//
// The coefficient families (names, components, units, switches) are the table of
// models/coefficient_families.hpp; this file holds their physics.
//
// Coefficients are errors (not corrections). The gyro-to-accelerometer time delay tau shifts the
// accelerometer input in time: the accelerometers output the model applied to the motion at t - tau
// (tau > 0: accelerometer samples late). The simulator evaluates the motion at t - tau;
// compensate() works on samples already aligned in time. Units of members are SI; names and
// engineering units of every coefficient are listed by coefficient_refs() and in
// docs/conventions.md.
#pragma once

#include <Eigen/Core>
#include <Eigen/LU>
#include <map>
#include <string>
#include <vector>

namespace sinscal {

/// Upper bound of the number of coefficients of the catalog (fixed-size storage per sample).
constexpr int kMaxCoefficients = 128;

/// Errors of one sensor triad (gyro or accelerometer), SI units of its input.
struct TriadErrors {
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();          // rad/s | m/s^2
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();         // dimensionless
  Eigen::Matrix3d misalignment = Eigen::Matrix3d::Zero();  // rad, diagonal unused (zero)
  Eigen::Vector3d scale_asym = Eigen::Vector3d::Zero();    // dimensionless
  Eigen::Vector3d k2 = Eigen::Vector3d::Zero();            // 1/(input unit)
  Eigen::Vector3d bias_drift = Eigen::Vector3d::Zero();    // (rad/s | m/s^2) per s
  /// Thermal terms (header comment): column d - 1 holds the degree-d coefficients per deg C^d.
  Eigen::Matrix3d bias_temp = Eigen::Matrix3d::Zero();          // (rad/s | m/s^2) / C^d
  Eigen::Matrix3d scale_temp = Eigen::Matrix3d::Zero();         // 1 / C^d
  Eigen::Matrix3d misalignment_temp = Eigen::Matrix3d::Zero();  // rad/C, diagonal unused
  Eigen::Vector3d bias_temp_rate = Eigen::Vector3d::Zero();     // (rad/s | m/s^2) per C/s

  /// I + diag(k) + M.
  Eigen::Matrix3d linear() const;
  /// I + diag(k + S p) + M + M1 dT: the linear part at dT = T - T0 (deg C).
  Eigen::Matrix3d linear(double dT) const;
  /// The thermal terms' additive part at dT and dT/dt: B p + r dT/dt.
  Eigen::Vector3d thermal_bias(double dT, double dT_rate) const;
  /// The model formula at a temperature (dT = T - T0, deg C; dT/dt in C/s).
  Eigen::Vector3d apply(const Eigen::Vector3d& x, const Eigen::Vector3d& extra, double dT,
                        double dT_rate) const;
  /// The model formula (truth to output).
  Eigen::Vector3d apply(const Eigen::Vector3d& x, const Eigen::Vector3d& extra) const;
  /// One fixed-point step of the inverse: the input x that gives output y, from a guess of x;
  /// `linear_inverse` is linear().inverse() (computed once per inversion).
  Eigen::Vector3d invert_step(const Eigen::Vector3d& y, const Eigen::Vector3d& extra,
                              const Eigen::Vector3d& x_guess,
                              const Eigen::Matrix3d& linear_inverse) const;
  Eigen::Vector3d invert_step(const Eigen::Vector3d& y, const Eigen::Vector3d& extra,
                              const Eigen::Vector3d& x_guess) const {
    return invert_step(y, extra, x_guess, linear().inverse());
  }
};

/// True kinematics at the IMU reference point at one instant, body axes.
struct KinematicSample {
  Eigen::Vector3d omega_ib_b = Eigen::Vector3d::Zero();      // rad/s
  Eigen::Vector3d omega_dot_ib_b = Eigen::Vector3d::Zero();  // rad/s^2
  Eigen::Vector3d f_ib_b = Eigen::Vector3d::Zero();          // m/s^2
  double t = 0.0;  // s, time of the output since the start of the plan (time-dependent terms)
  /// The triads' temperatures relative to the model's reference temperature (deg C) and the
  /// gyros' rate of change of temperature (deg C/s): the thermal terms. 0 without temperatures.
  double accel_dtemp = 0.0;      // deg C
  double gyro_dtemp = 0.0;       // deg C
  double gyro_dtemp_rate = 0.0;  // deg C/s
};

/// Name, unit and family of one coefficient; value_si = value_in_unit * si_per_unit.
struct CoefficientInfo {
  std::string name;  // e.g. "gyro.bias.x"
  std::string unit;  // e.g. "deg/h"
  double si_per_unit;
  std::string family;  // its entry in models/coefficient_families.hpp, e.g. "gyro.bias"
};

class ImuErrorModel {
 public:
  TriadErrors gyro;
  TriadErrors accel;
  Eigen::Matrix3d gyro_g_sensitivity = Eigen::Matrix3d::Zero();  // rad/s per m/s^2
  Eigen::Matrix3d accel_lever_arm_b = Eigen::Matrix3d::Zero();   // m; column i = r_i of accel i
  double time_delay = 0.0;                                       // s
  /// T0, the temperature the thermal terms are relative to (deg C; the sensor profile's
  /// `[thermal] reference_temperature`). Not a coefficient: it defines them.
  double reference_temperature_c = 25.0;  // deg C
  /// Whether any thermal coefficient is non-zero.
  bool has_thermal() const;
  /// The inverses of both triads' linear parts at the reference temperature (constant while the
  /// coefficients are: a filter computes them once per change of its estimate). The rate of
  /// change of an input from its output's, to first order in the errors, is the inverse times it
  /// (the rates of change of the nonlinear terms are of second order).
  struct LinearInverses {
    Eigen::Matrix3d gyro = Eigen::Matrix3d::Identity(), accel = Eigen::Matrix3d::Identity();
  };
  LinearInverses linear_inverses() const;

  /// Gyro output for the kinematics at the gyro sampling instant.
  Eigen::Vector3d gyro_output(const KinematicSample& s) const;
  /// Accelerometer output for the kinematics at the accelerometer sampling instant (t - tau).
  Eigen::Vector3d accel_output(const KinematicSample& s) const;
  /// Size-effect term added to the accelerometer outputs (m/s^2): accelerometer i's
  /// dw/dt x r_i + w x (w x r_i) along its sensitive axis, row i of accel.linear().
  Eigen::Vector3d size_effect(const Eigen::Vector3d& omega_ib_b,
                              const Eigen::Vector3d& omega_dot_ib_b) const;
  /// Inverse of the model for time-aligned outputs: solves for omega_ib_b and f_ib_b.
  /// Converges to rounding for any coefficients of realistic size (each step gains the size of
  /// the errors, ~1e-3 or less). Throws std::runtime_error if it does not converge.
  /// `t` is the time of the outputs since the start of the plan (time-dependent terms).
  /// `temperature` (optional) carries the thermal deviations (KinematicSample's accel_dtemp,
  /// gyro_dtemp, gyro_dtemp_rate); its other fields are not read. `inverses` (optional) are
  /// this model's linear_inverses(), used where the temperature leaves the linear parts alone.
  void compensate(const Eigen::Vector3d& y_gyro, const Eigen::Vector3d& y_accel,
                  const Eigen::Vector3d& omega_dot_ib_b, Eigen::Vector3d& omega_ib_b,
                  Eigen::Vector3d& f_ib_b, double t = 0.0,
                  const KinematicSample* temperature = nullptr,
                  const LinearInverses* inverses = nullptr) const;

  /// Sensitivity of the sensor errors (y - x) to every coefficient, in the order of
  /// coefficient_refs(): rows 0-2 gyro outputs (rad/s), rows 3-5 accelerometer outputs (m/s^2),
  /// per SI unit of the coefficient. The model is linear in its coefficients for given inputs, so
  /// this is exact. The time-delay column needs the rate of change of the specific force,
  /// `f_dot_ib_b` (m/s^3): a delay tau shifts the accelerometer input by -tau f_dot.
  Eigen::Matrix<double, 6, Eigen::Dynamic> jacobian(const KinematicSample& s,
                                                    const Eigen::Vector3d& f_dot_ib_b) const;
  /// The columns of jacobian() for the catalog indices `columns` only, in that order (the
  /// estimators' coefficient states), into fixed storage: no allocation per sample.
  using JacobianColumns =
      Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxCoefficients>;
  void jacobian(const KinematicSample& s, const Eigen::Vector3d& f_dot_ib_b,
                const std::vector<int>& columns, JacobianColumns& J) const;

  /// Every coefficient with its name, unit and a pointer to its SI value, in the contract order.
  std::vector<std::pair<CoefficientInfo, double*>> coefficient_refs();
  /// Every coefficient in SI, in the order of coefficient_catalog().
  Eigen::VectorXd vector() const;
  /// The model whose SI coefficients, in catalog order, are `v` (the inverse of vector()).
  static ImuErrorModel from_vector(const Eigen::VectorXd& v);
  /// Values in engineering units by name.
  std::map<std::string, double> coefficients() const;
  /// Sets one coefficient by name, value in its engineering unit; throws std::invalid_argument
  /// for an unknown name.
  void set(const std::string& name, double value_in_unit);
};

/// The same sensors with the body frame re-defined by the accelerometer triad (the convention of
/// calibration without known attitude, docs/conventions.md): body x along the x accelerometer's
/// sensitive axis, body y in the plane of the x and y accelerometers, so that
/// accel.misalignment.xy = .xz = .yz = 0. Exact for the linear part of both triads (an LQ
/// factorization of the accelerometer matrix); g-sensitivity and lever arms are rotated with the
/// frame; the per-axis nonlinear terms (K2, asymmetry) keep their values (the change is of second
/// order in the misalignments). `C_a_b` (optional) receives the rotation from the new frame to
/// the old body frame: x_b = C_a_b x_a.
ImuErrorModel in_accel_triad_frame(const ImuErrorModel& model, Eigen::Matrix3d* C_a_b = nullptr);

/// The same sensors described in the table platform's axes when the IMU sits on the platform
/// with the mounting rotation C_b_p (x_b = C_b_p^T x_p): the misalignments relative to the
/// platform include the mounting (docs/conventions.md "Table base and mounting"). Exact for the
/// linear part of both triads (A_p = A_b C_b_p^T); g-sensitivity and lever arms are rotated
/// (G C_b_p^T, C_b_p r); K2 and asymmetry keep their values (second order in the mounting).
ImuErrorModel in_platform_frame(const ImuErrorModel& model, const Eigen::Matrix3d& C_b_p);

/// The same sensors with the IMU reference point moved to the proof mass of accelerometer `axis`
/// (0, 1, 2): every inner lever arm relative to that one's, which becomes zero (the convention
/// of calibration with a reference lever arm, docs/conventions.md).
ImuErrorModel with_lever_arm_reference(const ImuErrorModel& model, int axis);

/// Names, units and families of all coefficients in contract order (the family table's order).
const std::vector<CoefficientInfo>& coefficient_catalog();
/// The catalog entry of one coefficient; throws std::invalid_argument for an unknown name.
const CoefficientInfo& coefficient_info(const std::string& name);

}  // namespace sinscal
