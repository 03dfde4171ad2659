#include "models/imu_error_model.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "models/units.hpp"

namespace sinscal {

Eigen::Matrix3d TriadErrors::linear() const {
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity() + misalignment;
  A.diagonal() = Eigen::Vector3d::Ones() + scale;
  return A;
}

Eigen::Matrix3d TriadErrors::linear(double dT) const {
  Eigen::Matrix3d A = linear();
  if (dT == 0.0) return A;
  const Eigen::Vector3d p(dT, dT * dT, dT * dT * dT);
  A += dT * misalignment_temp;
  A.diagonal() += scale_temp * p - dT * misalignment_temp.diagonal();
  return A;
}

Eigen::Vector3d TriadErrors::thermal_bias(double dT, double dT_rate) const {
  const Eigen::Vector3d p(dT, dT * dT, dT * dT * dT);
  return bias_temp * p + bias_temp_rate * dT_rate;
}

Eigen::Vector3d TriadErrors::apply(const Eigen::Vector3d& x, const Eigen::Vector3d& extra,
                                   double dT, double dT_rate) const {
  if (dT == 0.0 && dT_rate == 0.0) return apply(x, extra);
  return linear(dT) * x + scale_asym.cwiseProduct(x.cwiseAbs()) + k2.cwiseProduct(x.cwiseAbs2()) +
         bias + extra + thermal_bias(dT, dT_rate);
}

Eigen::Vector3d TriadErrors::apply(const Eigen::Vector3d& x, const Eigen::Vector3d& extra) const {
  return linear() * x + scale_asym.cwiseProduct(x.cwiseAbs()) + k2.cwiseProduct(x.cwiseAbs2()) +
         bias + extra;
}

Eigen::Vector3d TriadErrors::invert_step(const Eigen::Vector3d& y, const Eigen::Vector3d& extra,
                                         const Eigen::Vector3d& x_guess,
                                         const Eigen::Matrix3d& linear_inverse) const {
  const Eigen::Vector3d rhs = y - bias - extra - scale_asym.cwiseProduct(x_guess.cwiseAbs()) -
                              k2.cwiseProduct(x_guess.cwiseAbs2());
  return linear_inverse * rhs;
}

Eigen::Vector3d ImuErrorModel::size_effect(const Eigen::Vector3d& omega_ib_b,
                                           const Eigen::Vector3d& omega_dot_ib_b) const {
  // Each accelerometer measures the specific force at its proof mass along its own sensitive
  // axis, row i of the linear part: a rotation of the triad (a mounting) carries it exactly.
  Eigen::Vector3d out;
  const Eigen::Matrix3d A = accel.linear();
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d r = accel_lever_arm_b.col(i);
    out(i) = r.isZero(0.0)
                 ? 0.0
                 : A.row(i).dot(omega_dot_ib_b.cross(r) + omega_ib_b.cross(omega_ib_b.cross(r)));
  }
  return out;
}

Eigen::Vector3d ImuErrorModel::gyro_output(const KinematicSample& s) const {
  return gyro.apply(s.omega_ib_b, gyro_g_sensitivity * s.f_ib_b + gyro.bias_drift * s.t,
                    s.gyro_dtemp, s.gyro_dtemp_rate);
}

Eigen::Vector3d ImuErrorModel::accel_output(const KinematicSample& s) const {
  return accel.apply(s.f_ib_b, size_effect(s.omega_ib_b, s.omega_dot_ib_b) + accel.bias_drift * s.t,
                     s.accel_dtemp, 0.0);
}

bool ImuErrorModel::has_thermal() const {
  for (const TriadErrors* e : {&gyro, &accel})
    if (!e->bias_temp.isZero(0.0) || !e->scale_temp.isZero(0.0) ||
        !e->misalignment_temp.isZero(0.0) || !e->bias_temp_rate.isZero(0.0))
      return true;
  return false;
}

ImuErrorModel::LinearInverses ImuErrorModel::linear_inverses() const {
  return {gyro.linear().inverse(), accel.linear().inverse()};
}

namespace {
// Whether the triad's linear part moves with the temperature.
bool thermal_linear(const TriadErrors& t) {
  return !t.scale_temp.isZero(0.0) || !t.misalignment_temp.isZero(0.0);
}
}  // namespace

void ImuErrorModel::compensate(const Eigen::Vector3d& y_gyro, const Eigen::Vector3d& y_accel,
                               const Eigen::Vector3d& omega_dot_ib_b, Eigen::Vector3d& omega_ib_b,
                               Eigen::Vector3d& f_ib_b, double t,
                               const KinematicSample* temperature,
                               const LinearInverses* inverses) const {
  Eigen::Vector3d w = y_gyro, f = y_accel;
  const double dTa = temperature ? temperature->accel_dtemp : 0.0;
  const double dTg = temperature ? temperature->gyro_dtemp : 0.0;
  const double dTg_rate = temperature ? temperature->gyro_dtemp_rate : 0.0;
  const Eigen::Matrix3d gyro_inverse = inverses && (dTg == 0.0 || !thermal_linear(gyro))
                                           ? inverses->gyro
                                           : gyro.linear(dTg).inverse();
  const Eigen::Matrix3d accel_inverse = inverses && (dTa == 0.0 || !thermal_linear(accel))
                                            ? inverses->accel
                                            : accel.linear(dTa).inverse();
  const Eigen::Vector3d accel_fixed = accel.bias_drift * t + accel.thermal_bias(dTa, 0.0);
  const Eigen::Vector3d gyro_fixed = gyro.bias_drift * t + gyro.thermal_bias(dTg, dTg_rate);
  for (int iter = 0; iter < 60; ++iter) {
    const Eigen::Vector3d f_new =
        accel.invert_step(y_accel, size_effect(w, omega_dot_ib_b) + accel_fixed, f, accel_inverse);
    const Eigen::Vector3d w_new =
        gyro.invert_step(y_gyro, gyro_g_sensitivity * f_new + gyro_fixed, w, gyro_inverse);
    const double change = std::max((f_new - f).norm() / (1.0 + f_new.norm()),
                                   (w_new - w).norm() / (1.0 + w_new.norm()));
    w = w_new;
    f = f_new;
    if (change < 1e-16) {
      omega_ib_b = w;
      f_ib_b = f;
      return;
    }
  }
  // Rounding may keep the last digit oscillating; accept a tiny final change.
  const Eigen::Vector3d f_chk =
      accel.invert_step(y_accel, size_effect(w, omega_dot_ib_b) + accel_fixed, f, accel_inverse);
  if ((f_chk - f).norm() > 1e-13 * (1.0 + f.norm()))
    throw std::runtime_error("IMU error model inverse does not converge: coefficients too large");
  omega_ib_b = w;
  f_ib_b = f;
}

namespace {
// Where each coefficient lives in an ImuErrorModel (byte offset, catalog order), which output it
// enters and how: found once, so the per-sample Jacobian builds no names. Every term of the
// error model is linear in its coefficient, so each column is written in closed form from the
// place a unit value of the coefficient lands in the model's fields (`locate`); a coefficient
// found in none of them keeps the column by perturbation of the whole model.
struct CoefficientSlot {
  std::ptrdiff_t offset;
  enum class Output { Gyro, Accel, Delay } output;
  // The column's form: e_row times
  enum class Form {
    Perturb,   // (not located: the difference of the model's outputs)
    Bias,      // 1
    Linear,    // x_input (+ the size effect's v_row(input) for an accelerometer)
    Abs,       // |x_input|
    Square,    // x_input^2
    Time,      // t
    GSens,     // f_input (a gyro output)
    LeverArm,  // A_row . (omega_dot x e_input + omega x (omega x e_input))
    Thermal,   // x_input (or 1 when input < 0) times dT^power (power 0: the gyros' dT/dt)
  } form = Form::Perturb;
  int row = 0, input = -1, power = 0;
};

// Where a unit value of the coefficient at `slot` lands in `m` (otherwise zero).
void locate(const ImuErrorModel& m, CoefficientSlot& slot) {
  using Form = CoefficientSlot::Form;
  Eigen::Index i = 0, j = 0;
  auto set = [&slot](Form form, Eigen::Index row, Eigen::Index input, Eigen::Index power) {
    slot.form = form;
    slot.row = static_cast<int>(row);
    slot.input = static_cast<int>(input);
    slot.power = static_cast<int>(power);
  };
  if (slot.output == CoefficientSlot::Output::Delay) return;
  const TriadErrors& t = slot.output == CoefficientSlot::Output::Gyro ? m.gyro : m.accel;
  if (t.bias.maxCoeff(&i) > 0.0) {
    set(Form::Bias, i, -1, 0);
  } else if (t.scale.maxCoeff(&i) > 0.0) {
    set(Form::Linear, i, i, 0);
  } else if (t.misalignment.maxCoeff(&i, &j) > 0.0) {
    set(Form::Linear, i, j, 0);
  } else if (t.scale_asym.maxCoeff(&i) > 0.0) {
    set(Form::Abs, i, i, 0);
  } else if (t.k2.maxCoeff(&i) > 0.0) {
    set(Form::Square, i, i, 0);
  } else if (t.bias_drift.maxCoeff(&i) > 0.0) {
    set(Form::Time, i, -1, 0);
  } else if (t.bias_temp.maxCoeff(&i, &j) > 0.0) {
    set(Form::Thermal, i, -1, j + 1);
  } else if (t.scale_temp.maxCoeff(&i, &j) > 0.0) {
    set(Form::Thermal, i, i, j + 1);
  } else if (t.misalignment_temp.maxCoeff(&i, &j) > 0.0) {
    set(Form::Thermal, i, j, 1);
  } else if (t.bias_temp_rate.maxCoeff(&i) > 0.0) {
    set(Form::Thermal, i, -1, 0);
  } else if (slot.output == CoefficientSlot::Output::Gyro &&
             m.gyro_g_sensitivity.maxCoeff(&i, &j) > 0.0) {
    set(Form::GSens, i, j, 0);
  } else if (slot.output == CoefficientSlot::Output::Accel &&
             m.accel_lever_arm_b.maxCoeff(&j, &i) > 0.0) {
    set(Form::LeverArm, i, j, 0);  // column i is accelerometer i's arm, j its component
  }
}

const std::vector<CoefficientSlot>& coefficient_slots() {
  static const std::vector<CoefficientSlot> slots = [] {
    ImuErrorModel m;
    std::vector<CoefficientSlot> out;
    if (m.coefficient_refs().size() > static_cast<std::size_t>(kMaxCoefficients))
      throw std::logic_error("the coefficient catalog outgrew kMaxCoefficients");
    const char* base = reinterpret_cast<const char*>(&m);
    for (const auto& [info, ptr] : m.coefficient_refs()) {
      const FamilyOutput family_output = coefficient_family_info(info.family).output;
      const auto output = family_output == FamilyOutput::Delay  ? CoefficientSlot::Output::Delay
                          : family_output == FamilyOutput::Gyro ? CoefficientSlot::Output::Gyro
                                                                : CoefficientSlot::Output::Accel;
      CoefficientSlot slot{reinterpret_cast<const char*>(ptr) - base, output};
      *ptr = 1.0;
      locate(m, slot);
      *ptr = 0.0;
      if (coefficient_family_info(info.family).thermal() &&
          slot.form != CoefficientSlot::Form::Thermal)
        throw std::logic_error(info.name + ": not a thermal term");
      out.push_back(slot);
    }
    return out;
  }();
  return slots;
}
}  // namespace

void ImuErrorModel::jacobian(const KinematicSample& s, const Eigen::Vector3d& f_dot,
                             const std::vector<int>& columns, JacobianColumns& J) const {
  // Each coefficient's column: the derivative of the outputs (TriadErrors::apply, size_effect,
  // the g-sensitivity product) in its coefficient, in closed form (every term is linear in its
  // coefficient; the finite-difference test of the Jacobian checks each column against the
  // formula). A gyro coefficient enters only the gyro outputs, an accelerometer one only the
  // accelerometer outputs.
  // The accelerometers' linear part and lever arms stay the model's: the size effect is measured
  // along each accelerometer's sensitive axis (row i of the linear part), bilinear in the two, so
  // a lever arm's column carries the row (a mounting makes it a rotation of degrees) and a linear
  // column the size effect. Every other term is additive: its column does not depend on them.
  using Form = CoefficientSlot::Form;
  const auto& slots = coefficient_slots();
  J.setZero(6, static_cast<Eigen::Index>(columns.size()));
  // The size effect's lever-arm vectors v_i = omega_dot x r_i + omega x (omega x r_i), per
  // accelerometer (zero where its arm is).
  Eigen::Matrix3d v = Eigen::Matrix3d::Zero();
  const Eigen::Matrix3d A = accel.linear();
  for (int i = 0; i < 3; ++i) {
    const Eigen::Vector3d r = accel_lever_arm_b.col(i);
    if (!r.isZero(0.0))
      v.col(i) = s.omega_dot_ib_b.cross(r) + s.omega_ib_b.cross(s.omega_ib_b.cross(r));
  }
  ImuErrorModel zero;  // for the columns by perturbation (none in the catalog today)
  bool zero_ready = false;
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const auto col = static_cast<Eigen::Index>(k);
    const CoefficientSlot& slot = slots.at(static_cast<std::size_t>(columns[k]));
    const bool is_gyro = slot.output == CoefficientSlot::Output::Gyro;
    const Eigen::Vector3d& x = is_gyro ? s.omega_ib_b : s.f_ib_b;
    const Eigen::Index row = slot.row + (is_gyro ? 0 : 3);
    switch (slot.form) {
      case Form::Bias:
        J(row, col) = 1.0;
        break;
      case Form::Linear:
        J(row, col) = x(slot.input) + (is_gyro ? 0.0 : v(slot.input, slot.row));
        break;
      case Form::Abs:
        J(row, col) = std::abs(x(slot.input));
        break;
      case Form::Square:
        J(row, col) = x(slot.input) * x(slot.input);
        break;
      case Form::Time:
        J(row, col) = s.t;
        break;
      case Form::GSens:
        J(row, col) = s.f_ib_b(slot.input);
        break;
      case Form::LeverArm: {
        const Eigen::Vector3d e = Eigen::Vector3d::Unit(slot.input);
        J(row, col) = A.row(slot.row).dot(s.omega_dot_ib_b.cross(e) +
                                          s.omega_ib_b.cross(s.omega_ib_b.cross(e)));
        break;
      }
      case Form::Thermal: {
        const double dT = is_gyro ? s.gyro_dtemp : s.accel_dtemp;
        double c = slot.power == 0 ? s.gyro_dtemp_rate : std::pow(dT, slot.power);
        if (slot.input >= 0) c *= x(slot.input);
        J(row, col) = c;
        break;
      }
      case Form::Perturb: {
        if (slot.output == CoefficientSlot::Output::Delay) {
          J.col(col).tail<3>() = -f_dot;
          break;
        }
        if (!zero_ready) {
          zero.accel.scale = accel.scale;
          zero.accel.misalignment = accel.misalignment;
          zero.accel_lever_arm_b = accel_lever_arm_b;
          zero_ready = true;
        }
        double* value = reinterpret_cast<double*>(reinterpret_cast<char*>(&zero) + slot.offset);
        const double held = *value;
        if (is_gyro) {
          const Eigen::Vector3d g0 = zero.gyro_output(s);
          *value = held + 1.0;
          J.col(col).head<3>() = zero.gyro_output(s) - g0;
        } else {
          const Eigen::Vector3d a0 = zero.accel_output(s);
          *value = held + 1.0;
          J.col(col).tail<3>() = zero.accel_output(s) - a0;
        }
        *value = held;
        break;
      }
    }
  }
}

Eigen::Matrix<double, 6, Eigen::Dynamic> ImuErrorModel::jacobian(
    const KinematicSample& s, const Eigen::Vector3d& f_dot) const {
  static const std::vector<int> all = [] {
    std::vector<int> c(coefficient_slots().size());
    for (std::size_t k = 0; k < c.size(); ++k) c[k] = static_cast<int>(k);
    return c;
  }();
  JacobianColumns J;
  jacobian(s, f_dot, all, J);
  return J;
}

std::vector<std::pair<CoefficientInfo, double*>> ImuErrorModel::coefficient_refs() {
  std::vector<std::pair<CoefficientInfo, double*>> out;
  for (const auto& f : coefficient_families())
    for (int k = 0; k < f.size(); ++k)
      out.emplace_back(CoefficientInfo{f.coefficient_name(k), f.unit(), f.si_per_unit(), f.name},
                       &f.value(*this, k));
  return out;
}

Eigen::VectorXd ImuErrorModel::vector() const {
  ImuErrorModel copy = *this;
  const auto refs = copy.coefficient_refs();
  Eigen::VectorXd v(static_cast<Eigen::Index>(refs.size()));
  for (std::size_t i = 0; i < refs.size(); ++i) v(static_cast<Eigen::Index>(i)) = *refs[i].second;
  return v;
}

ImuErrorModel ImuErrorModel::from_vector(const Eigen::VectorXd& v) {
  ImuErrorModel m;
  const auto refs = m.coefficient_refs();
  if (static_cast<std::size_t>(v.size()) != refs.size())
    throw std::invalid_argument("ImuErrorModel::from_vector: " + std::to_string(v.size()) +
                                " values for " + std::to_string(refs.size()) + " coefficients");
  for (std::size_t i = 0; i < refs.size(); ++i) *refs[i].second = v(static_cast<Eigen::Index>(i));
  return m;
}

std::map<std::string, double> ImuErrorModel::coefficients() const {
  ImuErrorModel copy = *this;
  std::map<std::string, double> out;
  for (const auto& [info, ptr] : copy.coefficient_refs()) out[info.name] = *ptr / info.si_per_unit;
  return out;
}

void ImuErrorModel::set(const std::string& name, double value_in_unit) {
  for (auto& [info, ptr] : coefficient_refs())
    if (info.name == name) {
      *ptr = value_in_unit * info.si_per_unit;
      return;
    }
  throw std::invalid_argument("unknown coefficient '" + name + "'");
}

const std::vector<CoefficientInfo>& coefficient_catalog() {
  static const std::vector<CoefficientInfo> catalog = [] {
    ImuErrorModel m;
    std::vector<CoefficientInfo> out;
    for (const auto& ref : m.coefficient_refs()) out.push_back(ref.first);
    return out;
  }();
  return catalog;
}

ImuErrorModel in_accel_triad_frame(const ImuErrorModel& model, Eigen::Matrix3d* C_a_b) {
  // Accelerometer outputs y = A x_b + ... with x_b = R x_a: choose the rotation R that makes A R
  // lower triangular (positive diagonal). A^T = Q U (QR) gives A = U^T Q^T, so R = Q.
  const Eigen::Matrix3d A = model.accel.linear();
  const Eigen::HouseholderQR<Eigen::Matrix3d> qr(A.transpose());
  Eigen::Matrix3d Q = qr.householderQ();
  const Eigen::Matrix3d U = qr.matrixQR().triangularView<Eigen::Upper>();
  for (int i = 0; i < 3; ++i)
    if (U(i, i) < 0.0) Q.col(i) = -Q.col(i);
  if (Q.determinant() < 0.0)
    throw std::invalid_argument("accelerometer triad is left-handed: no body frame can follow it");
  ImuErrorModel out = model;
  auto split = [](TriadErrors& t, const Eigen::Matrix3d& linear) {
    t.scale = linear.diagonal() - Eigen::Vector3d::Ones();
    t.misalignment = linear;
    t.misalignment.diagonal().setZero();
  };
  Eigen::Matrix3d L = A * Q;
  L.triangularView<Eigen::StrictlyUpper>().setZero();  // rounding
  split(out.accel, L);
  split(out.gyro, model.gyro.linear() * Q);
  out.gyro_g_sensitivity = model.gyro_g_sensitivity * Q;
  out.accel_lever_arm_b = Q.transpose() * model.accel_lever_arm_b;
  if (C_a_b) *C_a_b = Q;
  return out;
}

ImuErrorModel in_platform_frame(const ImuErrorModel& model, const Eigen::Matrix3d& C_b_p) {
  ImuErrorModel out = model;
  auto split = [](TriadErrors& t, const Eigen::Matrix3d& linear) {
    t.scale = linear.diagonal() - Eigen::Vector3d::Ones();
    t.misalignment = linear;
    t.misalignment.diagonal().setZero();
  };
  split(out.accel, model.accel.linear() * C_b_p.transpose());
  split(out.gyro, model.gyro.linear() * C_b_p.transpose());
  out.gyro_g_sensitivity = model.gyro_g_sensitivity * C_b_p.transpose();
  out.accel_lever_arm_b = C_b_p * model.accel_lever_arm_b;
  return out;
}

ImuErrorModel with_lever_arm_reference(const ImuErrorModel& model, int axis) {
  ImuErrorModel out = model;
  const Eigen::Vector3d reference = model.accel_lever_arm_b.col(axis);
  out.accel_lever_arm_b.colwise() -= reference;
  return out;
}

const CoefficientInfo& coefficient_info(const std::string& name) {
  for (const auto& info : coefficient_catalog())
    if (info.name == name) return info;
  throw std::invalid_argument("unknown coefficient '" + name + "'");
}

}  // namespace sinscal
