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

Eigen::Vector3d TriadErrors::input_rate(const Eigen::Vector3d& output_rate) const {
  return linear().partialPivLu().solve(output_rate);
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

void ImuErrorModel::compensate(const Eigen::Vector3d& y_gyro, const Eigen::Vector3d& y_accel,
                               const Eigen::Vector3d& omega_dot_ib_b, Eigen::Vector3d& omega_ib_b,
                               Eigen::Vector3d& f_ib_b, double t,
                               const KinematicSample* temperature) const {
  Eigen::Vector3d w = y_gyro, f = y_accel;
  const double dTa = temperature ? temperature->accel_dtemp : 0.0;
  const double dTg = temperature ? temperature->gyro_dtemp : 0.0;
  const double dTg_rate = temperature ? temperature->gyro_dtemp_rate : 0.0;
  const Eigen::Matrix3d gyro_inverse = gyro.linear(dTg).inverse();
  const Eigen::Matrix3d accel_inverse = accel.linear(dTa).inverse();
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
// Where each coefficient lives in an ImuErrorModel (byte offset, catalog order) and which output
// it enters: found once, so the per-sample Jacobian builds no names.
struct CoefficientSlot {
  std::ptrdiff_t offset;
  enum class Output { Gyro, Accel, Delay } output;
  // A thermal coefficient's column in closed form (TriadErrors::linear(dT), thermal_bias):
  // e_row times the input along `input` (-1: none, a bias) times dT^power (power 0: the rate).
  bool thermal = false;
  int row = 0, input = -1, power = 0;
};

// Where a unit value of a thermal coefficient lands in its triad's thermal terms.
void locate_thermal(const TriadErrors& t, CoefficientSlot& slot) {
  Eigen::Index i = 0, j = 0;
  if (t.bias_temp.maxCoeff(&i, &j) > 0.0) {
    slot = {slot.offset, slot.output, true, static_cast<int>(i), -1, static_cast<int>(j) + 1};
  } else if (t.scale_temp.maxCoeff(&i, &j) > 0.0) {
    slot = {slot.offset,         slot.output,         true,
            static_cast<int>(i), static_cast<int>(i), static_cast<int>(j) + 1};
  } else if (t.misalignment_temp.maxCoeff(&i, &j) > 0.0) {
    slot = {slot.offset, slot.output, true, static_cast<int>(i), static_cast<int>(j), 1};
  } else if (t.bias_temp_rate.maxCoeff(&i) > 0.0) {
    slot = {slot.offset, slot.output, true, static_cast<int>(i), -1, 0};
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
      if (coefficient_family_info(info.family).thermal()) {
        *ptr = 1.0;
        locate_thermal(family_output == FamilyOutput::Gyro ? m.gyro : m.accel, slot);
        *ptr = 0.0;
        if (!slot.thermal) throw std::logic_error(info.name + ": not a thermal term");
      }
      out.push_back(slot);
    }
    return out;
  }();
  return slots;
}
}  // namespace

void ImuErrorModel::jacobian(const KinematicSample& s, const Eigen::Vector3d& f_dot,
                             const std::vector<int>& columns, JacobianColumns& J) const {
  // Each coefficient's column: its unit perturbation applied through the same formula, taking
  // the difference to the model without it. Exact (linear) and written once: the formula lives
  // only in TriadErrors::apply, size_effect and the g-sensitivity product. A gyro coefficient
  // enters only the gyro outputs, an accelerometer one only the accelerometer outputs (the
  // finite-difference test of the Jacobian checks this too).
  // The accelerometers' linear part and lever arms stay the model's: the size effect is measured
  // along each accelerometer's sensitive axis (row i of the linear part), bilinear in the two, so
  // a lever arm's column carries the row (a mounting makes it a rotation of degrees) and a linear
  // column the size effect. Every other term is additive: its column does not depend on them.
  ImuErrorModel zero;
  zero.accel.scale = accel.scale;
  zero.accel.misalignment = accel.misalignment;
  zero.accel_lever_arm_b = accel_lever_arm_b;
  const auto& slots = coefficient_slots();
  J.setZero(6, static_cast<Eigen::Index>(columns.size()));
  const Eigen::Vector3d g0 = zero.gyro_output(s), a0 = zero.accel_output(s);
  char* base = reinterpret_cast<char*>(&zero);
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const auto col = static_cast<Eigen::Index>(k);
    const CoefficientSlot& slot = slots.at(static_cast<std::size_t>(columns[k]));
    if (slot.thermal) {  // linear in the input: its column in closed form
      const bool is_gyro = slot.output == CoefficientSlot::Output::Gyro;
      const double dT = is_gyro ? s.gyro_dtemp : s.accel_dtemp;
      double c = slot.power == 0 ? s.gyro_dtemp_rate : std::pow(dT, slot.power);
      if (slot.input >= 0) c *= (is_gyro ? s.omega_ib_b : s.f_ib_b)(slot.input);
      J(slot.row + (is_gyro ? 0 : 3), col) = c;
      continue;
    }
    double* value = reinterpret_cast<double*>(base + slot.offset);
    switch (slot.output) {
      case CoefficientSlot::Output::Delay:
        J.col(col).tail<3>() = -f_dot;
        break;
      case CoefficientSlot::Output::Gyro:
        *value = 1.0;
        J.col(col).head<3>() = zero.gyro_output(s) - g0;
        *value = 0.0;
        break;
      case CoefficientSlot::Output::Accel: {
        const double held = *value;
        *value = held + 1.0;
        J.col(col).tail<3>() = zero.accel_output(s) - a0;
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
