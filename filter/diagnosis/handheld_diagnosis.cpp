#include "filter/diagnosis/handheld_diagnosis.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "models/earth.hpp"

namespace sinscal {

using namespace diagnosis_detail;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

Eigen::Matrix<double, 3, 2> tangent(const Eigen::Vector3d& u) {
  Eigen::Index smallest;
  u.cwiseAbs().minCoeff(&smallest);
  const Eigen::Vector3d e1 = u.cross(Eigen::Vector3d::Unit(smallest)).normalized();
  Eigen::Matrix<double, 3, 2> E;
  E.col(0) = e1;
  E.col(1) = u.cross(e1).normalized();
  return E;
}

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v(2), v(1), v(2), 0.0, -v(0), -v(1), v(0), 0.0;
  return S;
}

const CoefficientFamily& family_of(int catalog) {
  return coefficient_family_info(coefficient_catalog()[static_cast<std::size_t>(catalog)].family);
}

// The calibration's estimated base coefficients (catalog indices), then every component of the
// extended families (all of them: the columns a candidate may take).
std::vector<int> design_columns(const TableFreeResult& cal) {
  const auto& cat = coefficient_catalog();
  std::vector<int> out;
  for (std::size_t k = 0; k < cat.size(); ++k)
    if (std::find(cal.covariance_names.begin(), cal.covariance_names.end(), cat[k].name) !=
        cal.covariance_names.end())
      out.push_back(static_cast<int>(k));
  for (std::size_t k = 0; k < cat.size(); ++k)
    if (!coefficient_family_info(cat[k].family).base) out.push_back(static_cast<int>(k));
  return out;
}

// One pose's data and its prediction rows (unwhitened) for the held-out error.
struct PoseRows {
  int index = 0;
  double t = 0.0;  // s since the first reading, mid-pose
  Eigen::Vector3d u;
  Eigen::Matrix<double, 3, 2> E;
  double gravity = 0.0, gravity_sigma = 0.0;  // |f| - g and its sigma
  Eigen::RowVectorXd gravity_grad;            // per coefficient column
  Eigen::Vector3d rate, rate_sigma;
  Eigen::MatrixXd rate_grad;  // 3 x coefficient columns
};

struct Solution {
  Eigen::VectorXd delta;  // over the subset
  Eigen::MatrixXd inverse;
  double chi2 = 0.0;
};

// The linearized, whitened table-free problem with every candidate column: residuals r0 + J d.
class HandheldDesign {
 public:
  HandheldDesign(const std::vector<ImuReading>& r, const TableFreeResult& cal,
                 const TableFreeOptions& o)
      : r_(r), cal_(cal), columns_(design_columns(cal)) {
    Omega_ = Earth::wgs84().rate();
    omega_v_ = o.site ? Omega_ * std::sin(o.site->lat_rad) : 0.0;
    omega_h_ = o.site ? Omega_ * std::cos(o.site->lat_rad) : 0.0;
    has_site_ = o.site.has_value();
    const auto& cat = coefficient_catalog();
    for (std::size_t k = 0; k < columns_.size(); ++k)
      if (coefficient_family_info(cat[static_cast<std::size_t>(columns_[k])].family).output ==
          FamilyOutput::Gyro)
        gyro_columns_.push_back(static_cast<int>(k));
    const auto P = static_cast<Eigen::Index>(cal.poses.size());
    const auto C = static_cast<Eigen::Index>(columns_.size());
    rows_ = 6 * P + 2 * (P - 1);
    J_ = Eigen::MatrixXd::Zero(rows_, C + 2 * P);
    r0_ = Eigen::VectorXd::Zero(rows_);
    for (Eigen::Index p = 0; p < P; ++p) pose_rows(p);
    for (Eigen::Index p = 0; p + 1 < P; ++p) turn_rows(p);
    M_ = J_.transpose() * J_;
    v_ = J_.transpose() * r0_;
    rr_ = r0_.squaredNorm();
  }

  const std::vector<int>& columns() const { return columns_; }
  Eigen::Index coefficient_columns() const { return static_cast<Eigen::Index>(columns_.size()); }
  Eigen::Index poses() const { return static_cast<Eigen::Index>(cal_.poses.size()); }
  Eigen::Index rows() const { return rows_; }
  const std::vector<PoseRows>& pose_data() const { return pose_; }
  const Eigen::MatrixXd& J() const { return J_; }
  const Eigen::VectorXd& r0() const { return r0_; }
  const Eigen::MatrixXd& M() const { return M_; }
  // The turn into pose p's sigma: its noise integrated, times the calibration's turns' factor.
  double turn_sigma(Eigen::Index p) const {
    return cal_.poses[static_cast<std::size_t>(p)].turn_sigma *
           std::max(1.0, cal_.turn_fit.sigma_scale);
  }
  Eigen::Index turn_row(Eigen::Index p) const { return 6 * poses() + 2 * p; }  // into pose p+1

  // Positions (in J) of catalog coefficients, then every pose-direction column.
  std::vector<Eigen::Index> subset(const std::vector<int>& catalog) const {
    std::vector<Eigen::Index> s;
    s.reserve(catalog.size() + static_cast<std::size_t>(2 * poses()));
    for (int c : catalog) s.push_back(position(c));
    for (Eigen::Index k = 0; k < 2 * poses(); ++k) s.push_back(coefficient_columns() + k);
    return s;
  }
  Eigen::Index position(int catalog) const {
    const auto it = std::find(columns_.begin(), columns_.end(), catalog);
    if (it == columns_.end()) throw std::logic_error("handheld diagnosis: no column");
    return it - columns_.begin();
  }

  // Least squares over the subset, without the rows [skip0, skip1).
  Solution solve(const std::vector<Eigen::Index>& s, Eigen::Index skip0 = 0,
                 Eigen::Index skip1 = 0) const {
    const auto n = static_cast<Eigen::Index>(s.size());
    Eigen::MatrixXd N(n, n);
    Eigen::VectorXd b(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      b(i) = v_(s[static_cast<std::size_t>(i)]);
      for (Eigen::Index j = 0; j < n; ++j)
        N(i, j) = M_(s[static_cast<std::size_t>(i)], s[static_cast<std::size_t>(j)]);
    }
    double rr = rr_;
    if (skip1 > skip0) {
      Eigen::MatrixXd Js(skip1 - skip0, n);
      for (Eigen::Index j = 0; j < n; ++j)
        Js.col(j) = J_.block(skip0, s[static_cast<std::size_t>(j)], skip1 - skip0, 1);
      const Eigen::VectorXd rs = r0_.segment(skip0, skip1 - skip0);
      N -= Js.transpose() * Js;
      b -= Js.transpose() * rs;
      rr -= rs.squaredNorm();
    }
    N.diagonal() += 1e-12 * N.diagonal().cwiseAbs() + Eigen::VectorXd::Constant(n, 1e-300);
    Solution out;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(N);
    out.delta = -ldlt.solve(b);
    out.chi2 = rr + b.dot(out.delta);
    if (skip1 == skip0) out.inverse = ldlt.solve(Eigen::MatrixXd::Identity(n, n));
    return out;
  }

 private:
  void pose_rows(Eigen::Index p);
  void turn_rows(Eigen::Index p);
  void pose_statistics(const TableFreePoseFit& pf, Eigen::Vector3d& ya, Eigen::Vector3d& yg) const;

  const std::vector<ImuReading>& r_;
  const TableFreeResult& cal_;
  std::vector<int> columns_;
  std::vector<int> gyro_columns_;  // positions in columns_ of the gyro-output coefficients
  double Omega_ = 0.0, omega_v_ = 0.0, omega_h_ = 0.0;
  bool has_site_ = false;
  Eigen::Index rows_ = 0;
  Eigen::MatrixXd J_, M_;
  Eigen::VectorXd r0_, v_;
  double rr_ = 0.0;
  std::vector<PoseRows> pose_;
};

void HandheldDesign::pose_statistics(const TableFreePoseFit& pf, Eigen::Vector3d& ya,
                                     Eigen::Vector3d& yg) const {
  ya.setZero();
  yg.setZero();
  for (std::size_t k = pf.first; k <= pf.last; ++k) {
    ya += r_[k].accel;
    yg += r_[k].gyro;
  }
  const double n = static_cast<double>(pf.last - pf.first + 1);
  ya /= n;
  yg /= n;
}

// Pose p: its mean specific force and rate against the model at u_p, whitened with the
// calibration's noise; and the gravity-magnitude residual and rate at rest for prediction.
void HandheldDesign::pose_rows(Eigen::Index p) {
  const TableFreePoseFit& pf = cal_.poses[static_cast<std::size_t>(p)];
  const ImuErrorModel& m = cal_.model;
  const double g = cal_.gravity, n = static_cast<double>(pf.count);
  Eigen::Vector3d ya, yg;
  pose_statistics(pf, ya, yg);
  PoseRows d;
  d.index = pf.index;
  d.t = 0.5 * (pf.t_start + pf.t_end) - r_.front().t;
  d.u = pf.direction;
  d.E = tangent(d.u);
  KinematicSample s;
  s.f_ib_b = g * d.u;
  s.omega_ib_b = omega_v_ * d.u;
  s.t = d.t;
  ImuErrorModel::JacobianColumns J6;
  m.jacobian(s, Eigen::Vector3d::Zero(), columns_, J6);
  // The pose means' noise as the calibration completed it: white plus each triad's bias wander.
  const Eigen::Vector3d va = cal_.accel_noise.cwiseAbs2() / n +
                             Eigen::Vector3d::Constant(std::pow(cal_.accel_fit.wander, 2));
  Eigen::Matrix3d cov = (cal_.gyro_noise.cwiseAbs2() / n).asDiagonal();
  cov += std::pow(cal_.gyro_rest_fit.wander, 2) * Eigen::Matrix3d::Identity();
  cov += has_site_ ? Eigen::Matrix3d(omega_h_ * omega_h_ / 2.0 *
                                     (Eigen::Matrix3d::Identity() - d.u * d.u.transpose()))
                   : Eigen::Matrix3d(Omega_ * Omega_ / 3.0 * Eigen::Matrix3d::Identity());
  const Eigen::Matrix3d Wa = va.cwiseSqrt().cwiseInverse().asDiagonal();
  const Eigen::Matrix3d Wg = Eigen::Matrix3d(cov.llt().matrixL()).inverse();
  const Eigen::Index row = 6 * p, C = coefficient_columns();
  r0_.segment<3>(row) = Wa * (m.accel_output(s) - ya);
  r0_.segment<3>(row + 3) = Wg * (m.gyro_output(s) - yg);
  J_.block(row, 0, 3, C) = Wa * J6.bottomRows<3>();
  J_.block(row + 3, 0, 3, C) = Wg * J6.topRows<3>();
  J_.block<3, 2>(row, C + 2 * p) = Wa * m.accel.linear() * g * d.E;
  J_.block<3, 2>(row + 3, C + 2 * p) =
      Wg * (omega_v_ * m.gyro.linear() + g * m.gyro_g_sensitivity) * d.E;
  // Corrected mean specific force and rate at rest, and their sensitivities.
  const Eigen::Matrix3d Ai = m.accel.linear().inverse(), Gi = m.gyro.linear().inverse();
  const Eigen::Vector3d f = Ai * (ya - m.accel.bias);
  const Eigen::Vector3d fh = f.normalized();
  d.gravity = f.norm() - g;
  d.gravity_sigma = std::sqrt(fh.cwiseAbs2().dot(va));
  d.gravity_grad = -fh.transpose() * Ai * J6.bottomRows<3>();
  d.rate = Gi * (yg - m.gyro.bias - m.gyro_g_sensitivity * f) - omega_v_ * fh;
  d.rate_sigma = cov.diagonal().cwiseSqrt();
  d.rate_grad = -Gi * J6.topRows<3>();
  pose_.push_back(std::move(d));
}

// The turn from pose p to p+1: the corrected rates integrated (rotation vectors with the
// two-sample coning term), the predicted gravity direction against pose p+1's, and the
// sensitivity of the end attitude to each gyro column: d theta = C^T sum_k C_k d omega_k dt.
void HandheldDesign::turn_rows(Eigen::Index p) {
  const auto& from = cal_.poses[static_cast<std::size_t>(p)];
  const auto& to = cal_.poses[static_cast<std::size_t>(p + 1)];
  const ImuErrorModel& m = cal_.model;
  const Eigen::Index C = coefficient_columns();
  std::vector<int> gyro_catalog;
  for (int k : gyro_columns_) gyro_catalog.push_back(columns_[static_cast<std::size_t>(k)]);
  const Eigen::Matrix3d Gi = m.gyro.linear().inverse();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  Eigen::Vector3d prev = Eigen::Vector3d::Zero();
  Eigen::MatrixXd S = Eigen::MatrixXd::Zero(3, static_cast<Eigen::Index>(gyro_catalog.size()));
  ImuErrorModel::JacobianColumns J6;
  for (std::size_t k = from.last + 1; k <= to.first; ++k) {
    const double dt = r_[k].t - r_[k - 1].t;
    KinematicSample s;
    m.compensate(r_[k].gyro, r_[k].accel, Eigen::Vector3d::Zero(), s.omega_ib_b, s.f_ib_b,
                 r_[k].t - r_.front().t);
    s.t = r_[k].t - r_.front().t;
    const Eigen::Vector3d phi = s.omega_ib_b * dt;
    const Eigen::Vector3d v = phi + prev.cross(phi) / 12.0;
    prev = phi;
    const double a = v.norm();
    if (a > 0.0) q = q * Eigen::Quaterniond(Eigen::AngleAxisd(a, v / a));
    m.jacobian(s, Eigen::Vector3d::Zero(), gyro_catalog, J6);
    S -= q.toRotationMatrix() * Gi * J6.topRows<3>() * dt;
  }
  q.normalize();
  const Eigen::Matrix3d Cm = q.toRotationMatrix();
  const Eigen::Vector3d pred = Cm.transpose() * from.direction;
  const Eigen::Matrix<double, 3, 2> Eto = tangent(to.direction);
  const double w = 1.0 / turn_sigma(p + 1);
  const Eigen::Index row = turn_row(p);
  r0_.segment<2>(row) = w * Eto.transpose() * (pred - to.direction);
  const Eigen::MatrixXd dtheta = w * Eto.transpose() * skew(pred) * Cm.transpose() * S;
  for (std::size_t j = 0; j < gyro_columns_.size(); ++j)
    J_.block<2, 1>(row, gyro_columns_[j]) = dtheta.col(static_cast<Eigen::Index>(j));
  J_.block<2, 2>(row, C + 2 * p) =
      w * Eto.transpose() * Cm.transpose() * pose_[static_cast<std::size_t>(p)].E;
  J_.block<2, 2>(row, C + 2 * (p + 1)) = -w * Eigen::Matrix2d::Identity();
}

}  // namespace

namespace {

// Fits of parameter sets on one design.
class HandheldFitter {
 public:
  HandheldFitter(const HandheldDesign& d, const TableFreeResult& cal) : d_(d) {
    ImuErrorModel m = cal.model;
    values_ = m.vector();
  }

  const HandheldDesign& design() const { return d_; }

  FitFigures figures(const std::vector<int>& params, bool heldout) const {
    const auto s = d_.subset(params);
    const Solution sol = d_.solve(s);
    FitFigures f;
    const auto k = static_cast<Eigen::Index>(params.size());
    f.fit.parameters = params;
    f.fit.rank = static_cast<int>(s.size());
    f.fit.dof = static_cast<int>(d_.rows()) - f.fit.rank;
    f.chi2 = sol.chi2;
    f.fit.chi2_per_dof = f.fit.dof > 0 ? f.chi2 / f.fit.dof : kNaN;
    f.fit.theta.resize(k);
    for (Eigen::Index i = 0; i < k; ++i)
      f.fit.theta(i) = values_(params[static_cast<std::size_t>(i)]) + sol.delta(i);
    f.fit.cov = sol.inverse.topLeftCorner(k, k) * noise_scale(f);
    f.fit.observable.assign(params.size(), true);
    residual_figures(s, sol.delta, f);
    f.log_likelihood = -0.5 * f.chi2;
    f.bic = f.chi2 + f.fit.rank * std::log(static_cast<double>(d_.rows()));
    f.heldout = f.heldout_accel = f.heldout_gyro = f.heldout_turn = kNaN;
    if (heldout) heldout_figures(s, f);
    return f;
  }

  // The noise model is rescaled by the fit's own residual when it rejects it (the F test's
  // case): chi2 beyond its 99 % quantile.
  static double noise_scale(const FitFigures& f) {
    if (f.fit.dof <= 0) return 1.0;
    const double q99 = boost::math::quantile(boost::math::chi_squared(f.fit.dof), 0.99);
    return f.chi2 > q99 ? f.fit.chi2_per_dof : 1.0;
  }

  // The residual after `delta` over the subset s: the full delta over every design column.
  Eigen::VectorXd full(const std::vector<Eigen::Index>& s, const Eigen::VectorXd& delta) const {
    Eigen::VectorXd x = Eigen::VectorXd::Zero(d_.J().cols());
    for (std::size_t i = 0; i < s.size(); ++i) x(s[i]) = delta(static_cast<Eigen::Index>(i));
    return x;
  }

  double gravity(std::size_t p, const Eigen::VectorXd& x) const {
    const auto& pr = d_.pose_data()[p];
    return pr.gravity + pr.gravity_grad.dot(x.head(d_.coefficient_columns()));
  }
  Eigen::Vector3d rate(std::size_t p, const Eigen::VectorXd& x) const {
    const auto& pr = d_.pose_data()[p];
    return pr.rate + pr.rate_grad * x.head(d_.coefficient_columns());
  }
  // The turn into pose p+1 after x: whitened components.
  Eigen::Vector2d turn(Eigen::Index p, const Eigen::VectorXd& x) const {
    const Eigen::Index row = d_.turn_row(p);
    return d_.r0().segment<2>(row) + d_.J().middleRows(row, 2) * x;
  }

 private:
  void residual_figures(const std::vector<Eigen::Index>& s, const Eigen::VectorXd& delta,
                        FitFigures& f) const {
    const Eigen::VectorXd x = full(s, delta);
    double g2 = 0.0, w2 = 0.0, t2 = 0.0;
    const auto P = static_cast<std::size_t>(d_.poses());
    for (std::size_t p = 0; p < P; ++p) {
      g2 += std::pow(gravity(p, x), 2);
      w2 += rate(p, x).squaredNorm();
      if (p + 1 < P)
        t2 += std::pow(turn(static_cast<Eigen::Index>(p), x).norm() *
                           d_.turn_sigma(static_cast<Eigen::Index>(p + 1)),
                       2);
    }
    f.accel_rms = std::sqrt(g2 / static_cast<double>(P));
    f.gyro_rms = std::sqrt(w2 / (3.0 * static_cast<double>(P)));
    f.turn_rms = P > 1 ? std::sqrt(t2 / static_cast<double>(P - 1)) : 0.0;
  }

  // Leave one pose (its six rows) or one turn (its two) out, predict it.
  void heldout_figures(const std::vector<Eigen::Index>& s, FitFigures& f) const {
    double z2 = 0.0, g2 = 0.0, w2 = 0.0, t2 = 0.0;
    int nz = 0;
    const Eigen::Index P = d_.poses();
    for (Eigen::Index p = 0; p < P; ++p) {
      const auto pi = static_cast<std::size_t>(p);
      const Eigen::VectorXd x = full(s, d_.solve(s, 6 * p, 6 * p + 6).delta);
      const double g = gravity(pi, x);
      const Eigen::Vector3d w = rate(pi, x);
      const auto& pr = d_.pose_data()[pi];
      z2 += std::pow(g / pr.gravity_sigma, 2) + w.cwiseQuotient(pr.rate_sigma).squaredNorm();
      nz += 4;
      g2 += g * g;
      w2 += w.squaredNorm();
    }
    for (Eigen::Index p = 0; p + 1 < P; ++p) {
      const Eigen::Index row = d_.turn_row(p);
      const Eigen::VectorXd x = full(s, d_.solve(s, row, row + 2).delta);
      const Eigen::Vector2d t = turn(p, x);
      z2 += t.squaredNorm();
      nz += 2;
      t2 += t.squaredNorm() * std::pow(d_.turn_sigma(p + 1), 2);
    }
    f.heldout = std::sqrt(z2 / nz);
    f.heldout_chi2 = z2;
    f.heldout_accel = std::sqrt(g2 / static_cast<double>(P));
    f.heldout_gyro = std::sqrt(w2 / (3.0 * static_cast<double>(P)));
    f.heldout_turn = P > 1 ? std::sqrt(t2 / static_cast<double>(P - 1)) : 0.0;
    f.heldout_dwells = static_cast<int>(P);
  }

  const HandheldDesign& d_;
  Eigen::VectorXd values_;  // the calibration's coefficients, catalog order (SI)
};

// The poses a candidate needs: accelerometer terms are seen through the gravity magnitude, one
// equation per pose (9 base unknowns + k + 1); gyro terms through the turns, two equations each
// (9 base unknowns + k, plus one, and one more pose than turns).
int poses_needed(const CoefficientFamily& f, int k) {
  if (f.output == FamilyOutput::Gyro) return (9 + k + 1 + 1) / 2 + 1;
  return 9 + k + 1;
}

std::string poses_message(const CoefficientFamily& f, int k, int needed, int found) {
  std::ostringstream m;
  m << "candidate " << f.name << " (" << k << " coefficient" << (k == 1 ? "" : "s")
    << ") needs at least " << needed << " poses ("
    << (f.output == FamilyOutput::Gyro
            ? "9 base gyro unknowns plus its own from two equations per turn"
            : "9 base accelerometer unknowns plus its own, one gravity-magnitude equation per pose")
    << ", and one more); found " << found;
  return m.str();
}

// One component as a candidate against the current model: its smallest principal angle to the
// model's columns and its detection sigma.
CandidateTest separability(const HandheldFitter& fit, const std::vector<int>& current,
                           const Eigen::MatrixXd& current_inverse, double scale, int component,
                           const HandheldDiagnosisOptions& o) {
  const HandheldDesign& d = fit.design();
  const CoefficientFamily& info = family_of(component);
  CandidateTest c;
  c.family = info.name;
  c.separated_by = info.separated_by;
  const auto s = d.subset(current);
  const Eigen::Index pc = d.position(component);
  Eigen::VectorXd m0c(static_cast<Eigen::Index>(s.size()));
  for (std::size_t i = 0; i < s.size(); ++i) m0c(static_cast<Eigen::Index>(i)) = d.M()(s[i], pc);
  const double mcc = d.M()(pc, pc);
  const Eigen::VectorXd beta = current_inverse * m0c;
  const double perp = std::max(0.0, mcc - m0c.dot(beta));
  const double sine = mcc > 0.0 ? std::sqrt(perp / mcc) : 0.0;
  const double sigma = perp > 0.0 ? std::sqrt(scale / perp) : INFINITY;
  const bool ok = sine >= o.min_angle_sine && sigma < o.plausible_ratio * info.default_prior;
  (ok ? c.separable : c.aliased).push_back(component);
  if (!ok && mcc > 0.0) {
    Eigen::Index worst = 0;
    (beta.cwiseAbs().cwiseProduct(Eigen::VectorXd(Eigen::VectorXd::NullaryExpr(
         beta.size(),
         [&](Eigen::Index i) {
           return std::sqrt(d.M()(s[static_cast<std::size_t>(i)], s[static_cast<std::size_t>(i)]));
         }))))
        .maxCoeff(&worst);
    c.aliased_with = static_cast<std::size_t>(worst) < current.size()
                         ? coefficient_catalog()[static_cast<std::size_t>(
                                                     current[static_cast<std::size_t>(worst)])]
                               .name
                         : std::string("the poses' gravity directions");
  } else if (!ok) {
    c.aliased_with = "nothing: the poses and turns do not excite it";
  }
  return c;
}

void test_candidate(const HandheldFitter& fit, const std::vector<int>& current,
                    const FitFigures& now, CandidateTest& c) {
  test_extension(current, now, c,
                 [&](const std::vector<int>& with) { return fit.figures(with, false); });
}

// Every family's separable components together (an effect on every axis shows only partly in
// each one alone), for the families the poses suffice for.
void add_family_candidates(const HandheldFitter& fit, const std::vector<int>& current,
                           const FitFigures& now, int poses, std::vector<std::string>* refused,
                           std::vector<CandidateTest>& round) {
  const auto admit = [&](const std::string& family, int k) {
    const CoefficientFamily& info = coefficient_family_info(family);
    if (poses >= poses_needed(info, k)) return true;
    if (refused && refused->empty())
      refused->push_back(poses_message(info, k, poses_needed(info, k), poses));
    return false;
  };
  sinscal::add_family_candidates<CandidateTest>(
      round, admit, [&](CandidateTest& all) { test_candidate(fit, current, now, all); });
}

struct RoundContext {
  const HandheldFitter& fit;
  const HandheldDiagnosisOptions& o;
  int poses;
  std::vector<std::string>* refused;
};

std::vector<CandidateTest> run_round(const RoundContext& ctx, const std::vector<int>& current,
                                     const FitFigures& now) {
  const auto s = ctx.fit.design().subset(current);
  const Eigen::MatrixXd inverse = ctx.fit.design().solve(s).inverse;
  const double scale = HandheldFitter::noise_scale(now);
  std::vector<CandidateTest> round;
  for (int component : diagnosis_detail::candidate_components(ctx.o.candidates, current)) {
    const CoefficientFamily& info = family_of(component);
    CandidateTest c = separability(ctx.fit, current, inverse, scale, component, ctx.o);
    const int needed = poses_needed(info, 1);
    if (!c.separable.empty() && ctx.poses < needed) {
      c.aliased = c.separable;
      c.separable.clear();
      c.aliased_with = "too few poses: " + poses_message(info, 1, needed, ctx.poses);
      if (!ctx.o.candidates.empty() && ctx.refused->empty())
        ctx.refused->push_back(poses_message(info, 1, needed, ctx.poses));
    }
    if (!c.separable.empty()) test_candidate(ctx.fit, current, now, c);
    round.push_back(std::move(c));
  }
  add_family_candidates(ctx.fit, current, now, ctx.poses,
                        ctx.o.candidates.empty() ? nullptr : ctx.refused, round);
  return round;
}

}  // namespace

namespace {

void fill_pose_residuals(const HandheldFitter& fit, const std::vector<int>& params,
                         std::vector<PoseResidual>& out, bool after) {
  const HandheldDesign& d = fit.design();
  const auto s = d.subset(params);
  const Eigen::VectorXd x = fit.full(s, d.solve(s).delta);
  const auto P = static_cast<std::size_t>(d.poses());
  out.resize(P);
  for (std::size_t p = 0; p < P; ++p) {
    const auto& pr = d.pose_data()[p];
    PoseResidual& r = out[p];
    r.pose = pr.index;
    r.t_mid = pr.t;
    r.gravity_sigma = pr.gravity_sigma;
    r.rate_sigma = pr.rate_sigma;
    (after ? r.gravity_after : r.gravity_before) = fit.gravity(p, x);
    (after ? r.rate_after : r.rate_before) = fit.rate(p, x);
    double turn = kNaN;
    if (p > 0) {
      const auto t = static_cast<Eigen::Index>(p - 1);
      r.turn_sigma = d.turn_sigma(static_cast<Eigen::Index>(p));
      turn = fit.turn(t, x).norm() * r.turn_sigma;
    } else {
      r.turn_sigma = kNaN;
    }
    (after ? r.turn_after : r.turn_before) = turn;
  }
}

void noise_of_longest_pose(const std::vector<ImuReading>& r, const TableFreeResult& cal,
                           const HandheldDiagnosisOptions& o, HandheldDiagnosis& out) {
  const TableFreePoseFit* longest = &cal.poses.front();
  for (const auto& p : cal.poses)
    if (p.count > longest->count) longest = &p;
  try {
    out.allan = stretch_allan(r, longest->first, longest->last, o.alpha);
  } catch (const AllanError& e) {
    if (o.noise_requested)
      out.refused.push_back("the noise candidates need a longer static pose: the longest, pose " +
                            std::to_string(longest->index) + ", has " +
                            std::to_string(longest->count) + " readings (" + e.what() + ")");
    return;
  }
  out.has_allan = true;
  out.noise_pose = longest->index;
  out.noise = noise_candidates(out.allan, o.alpha);
}

void check_options(const TableFreeResult& cal, const std::vector<ImuReading>& r,
                   const HandheldDiagnosisOptions& o) {
  if (!(o.alpha > 0.0 && o.alpha < 1.0) || !(o.min_angle_sine > 0.0 && o.min_angle_sine < 1.0) ||
      !(o.plausible_ratio > 1.0) || o.max_findings < 1)
    throw std::invalid_argument(
        "hand-held diagnosis: alpha and min_angle_sine must be in (0, 1), plausible_ratio above "
        "1, max_findings at least 1");
  if (cal.poses.size() < 3)
    throw std::invalid_argument("hand-held diagnosis: needs at least 3 poses; found " +
                                std::to_string(cal.poses.size()));
  for (const auto& p : cal.poses)
    if (p.last >= r.size() || p.first > p.last || !(p.direction.norm() > 0.5))
      throw std::invalid_argument(
          "hand-held diagnosis: the calibration's poses do not match the readings");
  for (const auto& f : o.candidates) {
    if (f.empty()) continue;  // a list of "" alone: no coefficient family
    const CoefficientFamily& info = coefficient_family_info(f);  // throws for unknown names
    if (info.base)
      throw std::invalid_argument("hand-held diagnosis: " + f +
                                  " is a base family, in the model already");
  }
}

}  // namespace

HandheldDiagnosis diagnose_handheld(const std::vector<ImuReading>& readings,
                                    const TableFreeResult& cal, const TableFreeOptions& options,
                                    const HandheldDiagnosisOptions& o) {
  check_options(cal, readings, o);
  const HandheldDesign design(readings, cal, options);
  const HandheldFitter fit(design, cal);
  HandheldDiagnosis out;
  out.rows = static_cast<int>(design.rows());
  out.turns = static_cast<int>(design.poses()) - 1;
  DiagnosisReport& rep = out.report;
  rep.alpha = o.alpha;
  rep.inputs = out.rows;
  rep.initial_parameters.assign(
      design.columns().begin(),
      design.columns().begin() + static_cast<std::ptrdiff_t>(cal.covariance_names.size()));
  rep.initial = fit.figures(rep.initial_parameters, true);
  const RoundContext ctx{fit, o, static_cast<int>(design.poses()), &out.refused};
  // The held-out figures (a refit per held-out pose) only for the round's best.
  auto add_heldout = [&](const std::vector<int>& with, CandidateTest& best) {
    static_cast<HeldoutFigures&>(best.with) = fit.figures(with, true);
  };
  run_rounds(
      rep, o.max_findings,
      [&](const std::vector<int>& current, const FitFigures& now) {
        return run_round(ctx, current, now);
      },
      add_heldout);
  fill_pose_residuals(fit, rep.initial_parameters, out.poses, false);
  fill_pose_residuals(fit, rep.final_parameters, out.poses, true);
  if (o.noise) noise_of_longest_pose(readings, cal, o, out);
  return out;
}

ImuErrorModel diagnosed_model(const HandheldDiagnosis& d, const TableFreeResult& cal) {
  ImuErrorModel m = cal.model;
  auto refs = m.coefficient_refs();
  const Stage2Result& fit = d.report.final_fit.fit;
  for (std::size_t k = 0; k < fit.parameters.size(); ++k)
    *refs[static_cast<std::size_t>(fit.parameters[k])].second =
        fit.theta(static_cast<Eigen::Index>(k));
  return m;
}

AllanAnalysis stretch_allan(const std::vector<ImuReading>& r, std::size_t first, std::size_t last,
                            double alpha) {
  if (last >= r.size() || last <= first) throw AllanError("Allan deviation: empty stretch");
  std::vector<double> dts;
  for (std::size_t k = first + 1; k <= last; ++k) dts.push_back(r[k].t - r[k - 1].t);
  std::nth_element(dts.begin(), dts.begin() + static_cast<std::ptrdiff_t>(dts.size() / 2),
                   dts.end());
  const double dt = dts[dts.size() / 2];
  std::vector<ImuSample> samples;
  for (std::size_t k = first; k <= last; ++k) {
    ImuSample s;
    s.dt = dt;
    s.t = static_cast<double>(k - first + 1) * dt;
    s.dtheta_b = r[k].gyro * dt;
    s.dv_b = r[k].accel * dt;
    samples.push_back(s);
  }
  AllanOptions o;
  o.confidence = noise_confidence(samples.size(), alpha);
  return analyse_allan(samples, o);
}

double noise_confidence(std::size_t samples, double alpha) {
  int points = 0;
  for (std::size_t m = 1; static_cast<double>(m) <= 0.25 * static_cast<double>(samples); m *= 2)
    ++points;
  const int tested = points - (points + 1) / 2;  // the long cluster times of each channel
  return 1.0 - 2.0 * alpha / (6.0 * std::max(1, tested));
}

namespace {

// The white-noise-only model of a channel: N from the median of ADEV sqrt(tau) over the first
// half of the cluster times (the most precise; a flicker floor or a random walk lifts only the
// long ones).
double white_only(const std::vector<AllanPoint>& pts) {
  std::vector<double> n;
  for (std::size_t k = 0; k < std::max<std::size_t>(1, (pts.size() + 1) / 2); ++k)
    n.push_back(pts[k].adev * std::sqrt(pts[k].tau));
  std::nth_element(n.begin(), n.begin() + static_cast<std::ptrdiff_t>(n.size() / 2), n.end());
  return n[n.size() / 2];
}

NoiseCandidate noise_channel(const std::vector<AllanPoint>& pts, const AllanFit& fit,
                             const std::string& channel) {
  NoiseCandidate c;
  c.channel = channel;
  if (pts.empty()) return c;
  const double N = white_only(pts);
  double worst_tau = pts.back().tau;
  // The long cluster times only: the short ones set N.
  c.points = static_cast<int>(pts.size() - (pts.size() + 1) / 2);
  for (std::size_t k = (pts.size() + 1) / 2; k < pts.size(); ++k) {
    const AllanPoint& p = pts[k];
    const double white = N / std::sqrt(p.tau);
    const double ratio = p.adev / white;
    if (p.adev_low > white && !c.significant) {
      c.significant = true;
      c.tau = p.tau;
    }
    if (ratio > c.ratio) {
      c.ratio = ratio;
      if (!c.significant) worst_tau = p.tau;
    }
  }
  const double at = c.significant ? c.tau : worst_tau;
  const bool walk = fit.valid && fit.term_variance(AllanTerm::RandomWalk, at) >
                                     fit.term_variance(AllanTerm::BiasInstability, at);
  c.effect = walk ? "noise.rate_random_walk" : "noise.bias_instability";
  c.value = walk ? fit.random_walk : fit.floor_bias_instability;
  c.sigma = walk ? fit.random_walk_sigma : fit.bias_instability_sigma;
  return c;
}

}  // namespace

double white_only_deviation(const std::vector<AllanPoint>& points) { return white_only(points); }

std::vector<NoiseCandidate> noise_candidates(const AllanAnalysis& a, double alpha) {
  const double confidence = noise_confidence(a.samples, alpha);
  std::vector<NoiseCandidate> out;
  out.reserve(6);
  const char* axis[3] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i)
    out.push_back(noise_channel(a.gyro[static_cast<std::size_t>(i)],
                                a.gyro_fit[static_cast<std::size_t>(i)],
                                std::string("gyro.") + axis[i]));
  for (int i = 0; i < 3; ++i)
    out.push_back(noise_channel(a.accel[static_cast<std::size_t>(i)],
                                a.accel_fit[static_cast<std::size_t>(i)],
                                std::string("accel.") + axis[i]));
  for (auto& c : out) c.confidence = confidence;
  return out;
}

}  // namespace sinscal
