#include "filter/six_face/six_face.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <map>

#include "models/attitude.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

const char* const kAxis[3] = {"x", "y", "z"};

std::string fmt(const char* format, double a, double b = 0.0, double c = 0.0) {
  char buf[160];
  std::snprintf(buf, sizeof buf, format, a, b, c);
  return buf;
}

// Face k (0..5: +x -x +y -y +z -z up): its nominal up direction and two unit vectors across it.
Eigen::Vector3d face_up(int k) { return (k % 2 ? -1.0 : 1.0) * Eigen::Vector3d::Unit(k / 2); }
Eigen::Matrix<double, 3, 2> face_across(int k) {
  Eigen::Matrix<double, 3, 2> T;
  T.col(0) = Eigen::Vector3d::Unit((k / 2 + 1) % 3);
  T.col(1) = Eigen::Vector3d::Unit((k / 2 + 2) % 3);
  return T;
}

// A weighted linear least-squares problem: rows of H and z with their standard deviations
// (independent) or a block with a full covariance, solved whitened.
struct LinearProblem {
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> z;
  int n = 0;
  explicit LinearProblem(int unknowns) : n(unknowns) {}
  // A block of 3 rows with measurement covariance R (3x3, positive definite).
  void add_block(const Eigen::Matrix<double, 3, Eigen::Dynamic>& H, const Eigen::Vector3d& y,
                 const Eigen::Matrix3d& R) {
    const Eigen::Matrix3d W = R.llt().matrixL().solve(Eigen::Matrix3d::Identity());  // L^-1
    const Eigen::Matrix<double, 3, Eigen::Dynamic> Hw = W * H;
    const Eigen::Vector3d yw = W * y;
    for (int i = 0; i < 3; ++i) {
      rows.push_back(Hw.row(i));
      z.push_back(yw(i));
    }
  }
  void add_row(const Eigen::RowVectorXd& h, double y, double sigma) {
    rows.push_back(h / sigma);
    z.push_back(y / sigma);
  }
  // Solution, covariance and chi2 of the whitened residuals.
  void solve(Eigen::VectorXd& x, Eigen::MatrixXd& P, double& chi2) const {
    Eigen::MatrixXd H(static_cast<Eigen::Index>(rows.size()), n);
    Eigen::VectorXd y(static_cast<Eigen::Index>(rows.size()));
    for (std::size_t i = 0; i < rows.size(); ++i) {
      H.row(static_cast<Eigen::Index>(i)) = rows[i];
      y(static_cast<Eigen::Index>(i)) = z[i];
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(H);
    if (qr.rank() < n) throw SixFaceError("six-face: the parts do not determine the coefficients");
    x = qr.solve(y);
    const Eigen::MatrixXd N = H.transpose() * H;
    P = N.ldlt().solve(Eigen::MatrixXd::Identity(n, n));
    chi2 = (H * x - y).squaredNorm();
  }
};

struct Located {
  std::array<const PartStatistics*, 6> faces{};
  std::array<const PartStatistics*, 3> turns{};
};

Located locate(const std::vector<PartStatistics>& parts, const SixFaceOptions& o) {
  std::map<std::string, const PartStatistics*> by_label;
  for (const auto& p : parts) {
    if (by_label.count(p.label))
      throw SixFaceError("six-face: part '" + p.label + "' appears twice");
    by_label[p.label] = &p;
  }
  Located l;
  auto find = [&](const std::string& label, const char* what) {
    const auto it = by_label.find(label);
    if (it == by_label.end()) {
      std::string seen;
      for (const auto& [k, v] : by_label) seen += (seen.empty() ? "" : " ") + k;
      throw SixFaceError("six-face: no part labelled '" + label + "' (" + what +
                         "); the log's parts: " + (seen.empty() ? "none" : seen));
    }
    return it->second;
  };
  for (int k = 0; k < 6; ++k) {
    const std::string what =
        std::string("the face with ") + (k % 2 ? "-" : "+") + kAxis[k / 2] + " up";
    l.faces[static_cast<std::size_t>(k)] =
        find(o.declared.faces[static_cast<std::size_t>(k)], what.c_str());
  }
  for (int j = 0; j < 3; ++j) {
    const std::string what = std::string("the turn about ") + kAxis[j];
    l.turns[static_cast<std::size_t>(j)] =
        find(o.declared.turns[static_cast<std::size_t>(j)], what.c_str());
  }
  return l;
}

// Each face long enough and reading gravity along its declared axis.
void check_faces(const Located& l, const SixFaceOptions& o) {
  for (int k = 0; k < 6; ++k) {
    const PartStatistics& p = *l.faces[static_cast<std::size_t>(k)];
    if (p.duration < o.declared.min_rest)
      throw SixFaceError("six-face: face '" + p.label + "' lasts " + fmt("%.2f", p.duration) +
                         " s, shorter than the minimum rest of " +
                         fmt("%.2f", o.declared.min_rest) + " s");
    const Eigen::Vector3d f = p.mean_f;
    if (!(f.norm() > 0.0) || f.normalized().dot(face_up(k)) < std::cos(30.0 * units::deg)) {
      Eigen::Index axis = 0;
      f.cwiseAbs().maxCoeff(&axis);
      throw SixFaceError("six-face: face '" + p.label + "' is declared " + (k % 2 ? "-" : "+") +
                         kAxis[k / 2] + " up, but its specific force (" +
                         fmt("%.3f %.3f %.3f", f(0), f(1), f(2)) + " m/s^2) points along " +
                         (f(axis) < 0 ? "-" : "+") + kAxis[axis] +
                         ": labels swapped, an axis sign or the accelerometer columns?");
    }
  }
}

// The accelerometer fit (see the header), relinearized once about the first solution.
struct AccelFit {
  Eigen::Matrix3d A = Eigen::Matrix3d::Identity();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  Eigen::VectorXd d = Eigen::VectorXd::Zero(12);
  Eigen::MatrixXd P;  // of [A row-major (9), b (3), d (12)]
  double chi2 = 0.0;
  LinearProblem problem{24};  // the last pass's (the joint fit extends it with the gyros)
};

// Each face's variance of its means, rate [0..2] and f [3..5] (BlockScatter), from the faces'
// scatters pooled (one sensor, one hand): the gyros' over all six faces; each accelerometer's
// over the two faces where its axis is vertical, and apart over the four where it is horizontal
// (a hand's tremor tilts it there, gravity's projection on it changing to first order).
std::array<BlockScatter::Vector6d, 6> rest_noise(const Located& l, const SixFaceOptions& o,
                                                 Eigen::Vector3d& white_rate) {
  std::vector<const BlockScatter*> all;
  double duration = 0.0, count = 0.0;
  for (const auto* p : l.faces) {
    all.push_back(&p->scatter);
    duration += p->duration;
    count += static_cast<double>(p->count);
  }
  const double dt = duration / std::max(1.0, count), tau_min = o.declared.rest_correlation;
  const BlockScatter::Noise gyro = BlockScatter::fit(all, dt, tau_min);
  white_rate = gyro.white.head<3>();
  std::array<BlockScatter::Vector6d, 6> out{};
  for (std::size_t k = 0; k < 6; ++k)
    out[k].head<3>() = gyro.var_mean(std::max(l.faces[k]->duration, dt)).head<3>();
  for (Eigen::Index c = 0; c < 3; ++c) {
    std::vector<const BlockScatter*> vertical, horizontal;
    for (std::size_t k = 0; k < 6; ++k)
      (static_cast<Eigen::Index>(k / 2) == c ? vertical : horizontal).push_back(all[k]);
    const auto v = BlockScatter::fit(vertical, dt, tau_min);
    const auto h = BlockScatter::fit(horizontal, dt, tau_min);
    for (std::size_t k = 0; k < 6; ++k) {
      const BlockScatter::Noise& n = static_cast<Eigen::Index>(k / 2) == c ? v : h;
      out[k](c + 3) = n.var_mean(std::max(l.faces[k]->duration, dt))(c + 3);
    }
  }
  return out;
}

AccelFit fit_accel(const Located& l, double g, const SixFaceOptions& o,
                   const std::array<BlockScatter::Vector6d, 6>& noise) {
  const double sigma_p = o.declared.face_accuracy;
  AccelFit fit;
  for (int pass = 0; pass < 2; ++pass) {
    LinearProblem lp(24);
    for (int k = 0; k < 6; ++k) {
      const PartStatistics& p = *l.faces[static_cast<std::size_t>(k)];
      const auto T = face_across(k);
      const Eigen::Vector2d dk = fit.d.segment<2>(2 * static_cast<Eigen::Index>(k));
      const Eigen::Vector3d raw = face_up(k) + T * dk;
      const Eigen::Vector3d v = raw.normalized();
      // Second order: the tilt's unknown part shortens the mean up direction by E|dd|^2 / 2
      // and spreads it by its square (pass 2: from the first pass's posterior).
      double shrink = 1.0, spread = 0.0;
      if (pass == 1) {
        const Eigen::Matrix2d Pk = fit.P.block<2, 2>(12 + 2 * k, 12 + 2 * k);
        shrink = 1.0 - 0.5 * Pk.trace();
        spread = 0.5 * (Pk * Pk).trace();
      }
      Eigen::Matrix<double, 3, Eigen::Dynamic> H = Eigen::MatrixXd::Zero(3, 24);
      for (Eigen::Index r = 0; r < 3; ++r) H.block<1, 3>(r, 3 * r) = g * shrink * v.transpose();
      H.block<3, 3>(0, 9) = Eigen::Matrix3d::Identity();
      const Eigen::Matrix3d dv = (Eigen::Matrix3d::Identity() - v * v.transpose()) / raw.norm();
      H.block<3, 2>(0, 12 + 2 * k) = g * fit.A * dv * T;
      // Linearized about (A, d): y - (model at the point) + H x_point = H x.
      Eigen::VectorXd x0 = Eigen::VectorXd::Zero(24);
      for (Eigen::Index r = 0; r < 3; ++r) x0.segment<3>(3 * r) = fit.A.row(r).transpose();
      x0.segment<3>(9) = fit.b;
      x0.segment<12>(12) = fit.d;
      const Eigen::Vector3d model = g * shrink * fit.A * v + fit.b;
      const Eigen::Vector3d y = p.mean_f - model + H * x0;
      Eigen::Matrix3d R = noise[static_cast<std::size_t>(k)].tail<3>().cwiseMax(1e-14).asDiagonal();
      R += g * g * spread * v * v.transpose();
      lp.add_block(H, y, R);
    }
    for (int i = 0; i < 12; ++i) {
      Eigen::RowVectorXd h = Eigen::RowVectorXd::Zero(24);
      h(12 + i) = 1.0;
      lp.add_row(h, 0.0, sigma_p);
    }
    Eigen::VectorXd x;
    lp.solve(x, fit.P, fit.chi2);
    fit.problem = lp;
    for (Eigen::Index r = 0; r < 3; ++r) fit.A.row(r) = x.segment<3>(3 * r).transpose();
    fit.b = x.segment<3>(9);
    fit.d = x.segment<12>(12);
  }
  return fit;
}

// The gyro fit: G (row-major, 9) and b_g (3).
struct GyroFit {
  Eigen::Matrix3d G = Eigen::Matrix3d::Identity();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  Eigen::MatrixXd P;  // of [G row-major (9), b (3)]
  std::array<Eigen::Vector3d, 3> axes{};
  double earth_bound = 0.0;
  double chi2 = 0.0;
  Eigen::Matrix3d K = Eigen::Matrix3d::Zero();  // g-sensitivity (when estimated)
  Eigen::Matrix<double, 9, 9> P_K = Eigen::Matrix<double, 9, 9>::Zero();
};

// The calibrated specific-force direction averaged over `seconds` at the start (or end) of a
// turn's readings, and the variance of each of its components (rad^2).
Eigen::Vector3d edge_direction(const std::vector<ImuReading>& r, double seconds, bool start,
                               const AccelFit& acc, double& variance) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
  std::size_t n = 0;
  for (std::size_t k = 0; k < r.size(); ++k) {
    const ImuReading& x = start ? r[k] : r[r.size() - 1 - k];
    if (std::abs(x.t - (start ? r.front().t : r.back().t)) > seconds && n >= 2) break;
    sum += x.accel;
    sum2 += x.accel.cwiseProduct(x.accel);
    ++n;
  }
  const Eigen::Vector3d mean = sum / static_cast<double>(n);
  const Eigen::Vector3d var =
      (sum2 / static_cast<double>(n) - mean.cwiseProduct(mean)).cwiseMax(0.0);
  const Eigen::Vector3d f = acc.A.inverse() * (mean - acc.b);
  variance = var.sum() / 3.0 / static_cast<double>(n) / f.squaredNorm();
  return f.normalized();
}

// The turn's axis: the direction of the calibrated specific force (the vertical, in body axes)
// weighted by the rate about it, so that the sum of the body rates over the turn is
// theta * axis plus the net tilt between its ends, however the axis moves in the body while
// the hand turns (body rate = rate about the vertical times the vertical's direction, plus the
// tilting, which integrates to the net tilt).
Eigen::Vector3d turn_axis(const std::vector<ImuReading>& r, const AccelFit& acc,
                          const Eigen::Vector3d& b0) {
  const Eigen::Matrix3d A_inv = acc.A.inverse();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t k = 1; k < r.size(); ++k) {
    const Eigen::Vector3d u = (A_inv * (r[k].accel - acc.b)).normalized();
    sum += (r[k].gyro - b0).dot(u) * (r[k].t - r[k - 1].t) * u;
  }
  return sum.normalized();
}

// The joint fit: the accelerometers' problem extended by the gyros' rests and turns, unknowns
// [A (9), b (3), d (12), G (9), b_g (3)]. The turns' axes come from the calibrated
// accelerometers, so the gyro misalignments relative to the box carry the accelerometers' frame
// uncertainty (the faces' placement): each turn's equation is linearized in A and b too.
// With the g-sensitivity, 9 more: K row-major at kK.
constexpr int kG = 24, kBg = 33, kJoint = 36, kK = 36;

Eigen::RowVectorXd padded(const Eigen::RowVectorXd& row, int n) {
  Eigen::RowVectorXd out = Eigen::RowVectorXd::Zero(n);
  out.head(row.size()) = row;
  return out;
}

// One turn's equations (the body rates summed over it), linearized in A and b; returns its axis.
Eigen::Vector3d add_turn(LinearProblem& lp, const PartStatistics& p, const AccelFit& acc,
                         const Eigen::Vector3d& b0, const Eigen::Vector3d& pooled,
                         const SixFaceOptions& o) {
  const double omega = Earth::wgs84().omega_ie_n(0.0).norm();
  double var_s = 0.0, var_e = 0.0;
  const Eigen::Vector3d u_s = edge_direction(p.readings, o.declared.turn_edge, true, acc, var_s);
  const Eigen::Vector3d u_e = edge_direction(p.readings, o.declared.turn_edge, false, acc, var_e);
  Eigen::Vector3d a = turn_axis(p.readings, acc, b0);
  // The axis' derivatives with respect to A and b (central differences).
  Eigen::Matrix<double, 3, 12> J;
  for (int q = 0; q < 12; ++q) {
    AccelFit plus = acc, minus = acc;
    const double h = 1e-6;
    if (q < 9) {
      plus.A(q / 3, q % 3) += h;
      minus.A(q / 3, q % 3) -= h;
    } else {
      plus.b(q - 9) += h * 10.0;
      minus.b(q - 9) -= h * 10.0;
    }
    J.col(q) = (turn_axis(p.readings, plus, b0) - turn_axis(p.readings, minus, b0)) /
               (q < 9 ? 2.0 * h : 20.0 * h);
  }
  // Body rates summed over the turn: G (theta a + the net tilt u_e x u_s) + b_g T, linearized
  // about the accelerometers' solution (A0, b0) and G ~ I in the axis' term.
  const Eigen::Vector3d rotation_b = o.declared.turn_angle * a + u_e.cross(u_s);
  Eigen::Matrix<double, 3, Eigen::Dynamic> H = Eigen::MatrixXd::Zero(3, lp.n);
  for (Eigen::Index r = 0; r < 3; ++r) H.block<1, 3>(r, kG + 3 * r) = rotation_b.transpose();
  if (lp.n > kJoint) {  // K times the turn's summed specific force
    const Eigen::Vector3d f_sum = acc.A.inverse() * (p.mean_f - acc.b) * p.duration;
    for (Eigen::Index r = 0; r < 3; ++r) H.block<1, 3>(r, kK + 3 * r) = f_sum.transpose();
  }
  H.block<3, 12>(0, 0) = o.declared.turn_angle * J;
  H.block<3, 3>(0, kBg) = p.duration * Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 12, 1> x_acc;
  for (Eigen::Index r = 0; r < 3; ++r) x_acc.segment<3>(3 * r) = acc.A.row(r).transpose();
  x_acc.segment<3>(9) = acc.b;
  const Eigen::Vector3d y = p.integral_dtheta + o.declared.turn_angle * J * x_acc;
  Eigen::Matrix3d R = (pooled * p.duration).asDiagonal();  // white: W per s, summed over the turn
  R += std::pow(o.declared.turn_accuracy, 2) * a * a.transpose();
  R += (var_s + var_e) * (Eigen::Matrix3d::Identity() - a * a.transpose());
  R += std::pow(omega * p.duration, 2) / 3.0 * Eigen::Matrix3d::Identity();
  lp.add_block(H, y, R);
  return a;
}

GyroFit fit_gyro(const Located& l, AccelFit& acc, const SixFaceOptions& o) {
  GyroFit fit;
  const Eigen::Matrix3d A_inv = acc.A.inverse();
  const double omega = Earth::wgs84().omega_ie_n(0.0).norm();
  const double lat = o.site ? o.site->lat_rad : 0.0;
  Eigen::Vector3d pooled = Eigen::Vector3d::Zero(), b0 = Eigen::Vector3d::Zero();
  const auto noise = rest_noise(l, o, pooled);  // pooled: the white gyro noise W, (rad/s)^2 s
  for (const auto* p : l.faces) b0 += p->mean_rate / 6.0;
  LinearProblem lp(o.g_sensitivity ? kJoint + 9 : kJoint);
  for (std::size_t i = 0; i < acc.problem.rows.size(); ++i) {
    lp.rows.push_back(padded(acc.problem.rows[i], lp.n));
    lp.z.push_back(acc.problem.z[i]);
  }
  for (const auto* const& p : l.faces) {
    const Eigen::Vector3d up = (A_inv * (p->mean_f - acc.b)).normalized();
    Eigen::Matrix<double, 3, Eigen::Dynamic> H = Eigen::MatrixXd::Zero(3, lp.n);
    H.block<3, 3>(0, kBg) = Eigen::Matrix3d::Identity();
    if (lp.n > kJoint) {  // K times the rest's specific force
      const Eigen::Vector3d f = A_inv * (p->mean_f - acc.b);
      for (Eigen::Index r = 0; r < 3; ++r) H.block<1, 3>(r, kK + 3 * r) = f.transpose();
    }
    Eigen::Vector3d y = p->mean_rate;
    const auto k = static_cast<std::size_t>(&p - l.faces.data());
    Eigen::Matrix3d R = noise[k].head<3>().cwiseMax(1e-20).asDiagonal();
    if (o.site) {
      y -= omega * std::sin(lat) * up;  // the vertical part (G ~ I: second order)
      const double h2 = std::pow(omega * std::cos(lat), 2) / 2.0;
      R += h2 * (Eigen::Matrix3d::Identity() - up * up.transpose());
      fit.earth_bound = std::sqrt(h2);
    } else {
      R += omega * omega / 3.0 * Eigen::Matrix3d::Identity();
      fit.earth_bound = omega / std::sqrt(3.0);
    }
    lp.add_block(H, y, R);
  }
  for (int j = 0; j < 3; ++j)
    fit.axes[static_cast<std::size_t>(j)] =
        add_turn(lp, *l.turns[static_cast<std::size_t>(j)], acc, b0, pooled, o);
  Eigen::VectorXd x;
  Eigen::MatrixXd P;
  lp.solve(x, P, fit.chi2);
  for (Eigen::Index r = 0; r < 3; ++r) fit.G.row(r) = x.segment<3>(kG + 3 * r).transpose();
  fit.b = x.segment<3>(kBg);
  fit.P = P.block<12, 12>(kG, kG);
  if (lp.n > kJoint) {
    for (Eigen::Index r = 0; r < 3; ++r) fit.K.row(r) = x.segment<3>(kK + 3 * r).transpose();
    fit.P_K = P.block<9, 9>(kK, kK);
  }
  fit.P.block<3, 3>(9, 9) += std::pow(o.gyro_bias_instability, 2) * Eigen::Matrix3d::Identity();
  // The accelerometers as the joint fit has them (the gyros add next to nothing about them).
  for (Eigen::Index r = 0; r < 3; ++r) acc.A.row(r) = x.segment<3>(3 * r).transpose();
  acc.b = x.segment<3>(9);
  acc.d = x.segment<12>(12);
  acc.P = P.topLeftCorner(24, 24);
  acc.P.block<3, 3>(9, 9) += std::pow(o.accel_bias_instability, 2) * Eigen::Matrix3d::Identity();
  return fit;
}

// Each turn's integral (nominal scaling) within the tolerance of the declared angle about its
// declared axis.
void check_turns(const Located& l, const SixFaceOptions& o) {
  for (int j = 0; j < 3; ++j) {
    const PartStatistics& p = *l.turns[static_cast<std::size_t>(j)];
    if (p.readings.size() < 10)
      throw SixFaceError("six-face: turn '" + p.label + "' has " +
                         std::to_string(p.readings.size()) +
                         " readings kept (the accumulator keeps the turns' readings)");
    const double about = p.integral_dtheta(j);
    if (std::abs(about - o.declared.turn_angle) > o.turn_tolerance)
      throw SixFaceError("six-face: turn '" + p.label + "' integrates to " +
                         fmt("%.1f", about / units::deg) + " deg about " + kAxis[j] +
                         " (with the nominal scaling), declared " +
                         fmt("%.1f", o.declared.turn_angle / units::deg) + " deg (tolerance " +
                         fmt("%.1f", o.turn_tolerance / units::deg) +
                         " deg): a different turn, the other direction, or a wrong rate?");
    Eigen::Index axis = 0;
    p.mean_f.cwiseAbs().maxCoeff(&axis);
    if (axis != j || p.mean_f(j) < 0.0)
      throw SixFaceError("six-face: turn '" + p.label + "' is declared about " + kAxis[j] +
                         " with " + kAxis[j] + " up, but its mean specific force points along " +
                         (p.mean_f(axis) < 0 ? "-" : "+") + kAxis[axis]);
  }
}

}  // namespace

void BlockScatter::push_level(std::size_t k, const Vector6d& x) {
  if (k == 0) {
    ++count_;
    sum_ += x;
    sum2_ += x.cwiseProduct(x);
  }
  if (levels_.size() <= k) levels_.emplace_back();
  Level& l = levels_[k];
  if (l.has_last) {
    l.sum_d2 += (x - l.last).cwiseProduct(x - l.last);
    ++l.diffs;
  }
  l.last = x;
  l.has_last = true;
  if (!l.has_pending) {
    l.pending = x;
    l.has_pending = true;
    return;
  }
  l.has_pending = false;
  push_level(k + 1, 0.5 * (l.pending + x));  // levels_ may grow: `l` is not used after this
}

namespace {

// W / tau + B / tau^2 fitted to Allan variances y (weights: differences / model^2, twice), each
// term non-negative; returns (W, B).
Eigen::Vector2d fit_white_and_wander(const std::vector<double>& tau, const std::vector<double>& y,
                                     const std::vector<double>& m) {
  // An Allan variance from m differences scatters with variance 2 y^2 / m: weights m / model^2,
  // the model from the white-only (or wander-only) form pooled over the lengths to begin with
  // (weights from the observed values would favour the low ones). form 0: both terms, 1: W
  // alone, 2: B alone; returns (W, B, chi2).
  double m_all = 0.0, w0 = 0.0, b0 = 0.0;
  for (std::size_t i = 0; i < tau.size(); ++i) {
    m_all += m[i];
    w0 += m[i] * y[i] * tau[i];
    b0 += m[i] * y[i] * tau[i] * tau[i];
  }
  auto fit = [&](int form) {
    Eigen::Vector3d x(form == 2 ? 0.0 : w0 / m_all, form == 2 ? b0 / m_all : 0.0, 0.0);
    for (int pass = 0; pass < 3; ++pass) {
      Eigen::Matrix2d N = Eigen::Matrix2d::Zero();
      Eigen::Vector2d r = Eigen::Vector2d::Zero();
      for (std::size_t i = 0; i < tau.size(); ++i) {
        const double model = x(0) / tau[i] + x(1) / (tau[i] * tau[i]);
        const Eigen::Vector2d h(form == 2 ? 0.0 : 1.0 / tau[i],
                                form == 1 ? 0.0 : 1.0 / (tau[i] * tau[i]));
        const double w = m[i] / std::max(model * model, 1e-300);
        N += w * h * h.transpose();
        r += w * h * y[i];
      }
      if (form == 1) N(1, 1) = 1.0;
      if (form == 2) N(0, 0) = 1.0;
      const Eigen::Vector2d next = N.ldlt().solve(r);
      // A negative term would make the weights meaningless: keep the model positive.
      if (next(0) / tau.front() + next(1) / (tau.front() * tau.front()) <= 0.0) break;
      x.head<2>() = next;
    }
    x(2) = 0.0;
    for (std::size_t i = 0; i < tau.size(); ++i) {
      const double model = std::max(x(0) / tau[i] + x(1) / (tau[i] * tau[i]), 1e-300);
      x(2) += m[i] * std::pow(y[i] - model, 2) / (2.0 * model * model);
    }
    return x;
  };
  // White noise unless the other term is needed: the chi2 must drop by the 99 % point of chi2 on
  // 1 dof (6.63).
  const Eigen::Vector3d white = fit(1);
  if (tau.size() < 3) return white.head<2>().cwiseMax(0.0);
  const Eigen::Vector3d both = fit(0), wander = fit(2);
  if (both(0) >= 0.0 && both(1) >= 0.0 && white(2) - both(2) > 6.63) return both.head<2>();
  if (white(2) - wander(2) > 6.63) return wander.head<2>().cwiseMax(0.0);
  return white.head<2>().cwiseMax(0.0);
}

}  // namespace

BlockScatter::Vector6d BlockScatter::Noise::var_mean(double T) const {
  return white / T + 2.0 / 3.0 * wander / (T * T);
}

BlockScatter::Noise BlockScatter::fit(const std::vector<const BlockScatter*>& parts, double dt,
                                      double tau_min) {
  Noise out;
  std::size_t count = 0, depth = 0;
  Vector6d sum = Vector6d::Zero(), sum2 = Vector6d::Zero();
  for (const auto* p : parts) {
    count += p->count_;
    sum += p->sum_;
    sum2 += p->sum2_;
    depth = std::max(depth, p->levels_.size());
  }
  if (count < 8) {  // the readings' variance, as white noise
    const double n = static_cast<double>(count);
    if (count > 1) out.white = (sum2 - sum.cwiseProduct(sum) / n) / (n - 1.0) * dt;
    return out;
  }
  // Each block length's differences, pooled over the parts.
  std::vector<Vector6d> d2(depth, Vector6d::Zero());
  std::vector<std::size_t> diffs(depth, 0);
  for (const auto* p : parts)
    for (std::size_t k = 0; k < p->levels_.size(); ++k) {
      d2[k] += p->levels_[k].sum_d2;
      diffs[k] += p->levels_[k].diffs;
    }
  // The lengths to fit: tau >= tau_min with at least 3 differences in all (the longest ones
  // separate the two terms); fewer than three such lengths, the longest two or three with at
  // least 3 differences.
  std::vector<std::size_t> use;
  for (std::size_t k = 0; k < depth; ++k)
    if (diffs[k] >= 3 && std::ldexp(dt, static_cast<int>(k)) >= tau_min) use.push_back(k);
  if (use.size() < 3) {
    use.clear();
    for (std::size_t k = depth; k-- > 0 && use.size() < 3;)
      if (diffs[k] >= 3) use.push_back(k);
  }
  for (Eigen::Index c = 0; c < 6; ++c) {
    std::vector<double> tau, y, m;
    for (const std::size_t k : use) {
      tau.push_back(std::ldexp(dt, static_cast<int>(k)));
      y.push_back(d2[k](c) / (2.0 * static_cast<double>(diffs[k])));
      m.push_back(static_cast<double>(diffs[k]));
    }
    const Eigen::Vector2d wb = fit_white_and_wander(tau, y, m);
    out.white(c) = wb(0);
    out.wander(c) = wb(1);
  }
  return out;
}

void PartAccumulator::close() {
  if (parts_.empty() || current_.empty()) return;
  PartStatistics& p = parts_.back();
  const double n = static_cast<double>(p.count);
  if (p.count > 1) {
    p.var_rate = m2_rate_ / (n - 1.0);
    p.var_f = m2_f_ / (n - 1.0);
  }
}

void PartAccumulator::push(const ImuSample& s, const std::string& label) {
  if (label != current_) {
    close();
    current_ = label;
    if (label.empty()) return;
    for (const auto& p : parts_)
      if (p.label == label)
        throw SixFaceError("six-face: part '" + label + "' comes back at t = " + fmt("%.3f", s.t) +
                           " s after other parts (it ended at " + fmt("%.3f", p.t_end) +
                           " s): each part must be one stretch");
    parts_.emplace_back();
    parts_.back().label = label;
    keeping_ = std::find(keep_.begin(), keep_.end(), label) != keep_.end();
    parts_.back().t_start = s.t - s.dt;
    m2_rate_.setZero();
    m2_f_.setZero();
  }
  if (label.empty()) return;
  if (!(s.dt > 0.0)) throw SixFaceError("six-face: a sample without a positive interval");
  PartStatistics& p = parts_.back();
  const Eigen::Vector3d w = s.dtheta_b / s.dt, f = s.dv_b / s.dt;
  ++p.count;
  const double n = static_cast<double>(p.count);
  const Eigen::Vector3d dw = w - p.mean_rate, df = f - p.mean_f;
  p.mean_rate += dw / n;
  p.mean_f += df / n;
  m2_rate_ += dw.cwiseProduct(w - p.mean_rate);
  m2_f_ += df.cwiseProduct(f - p.mean_f);
  p.integral_dtheta += s.dtheta_b;
  BlockScatter::Vector6d x;
  x << w, f;
  p.scatter.push(x);
  if (keeping_) p.readings.push_back({s.t, f, w});
  p.duration += s.dt;
  p.t_end = s.t;
  close();  // keeps the variances current (cheap)
}

namespace {

// The 24 base coefficients from the two fits, catalog order.
std::vector<SixFaceCoefficient> coefficients_of(const AccelFit& a, const GyroFit& g,
                                                bool g_sensitivity) {
  std::vector<SixFaceCoefficient> out;
  for (const auto& info : coefficient_catalog()) {
    const bool gyro = info.family.rfind("gyro.", 0) == 0;
    const std::string kind = info.family.substr(info.family.find('.') + 1);
    if (info.name.size() <= info.family.size()) continue;  // a family of one (time_delay)
    const std::string comp = info.name.substr(info.family.size() + 1);
    if (g_sensitivity && info.family == "gyro.g_sensitivity") {
      const int i = comp[0] - 'x', j = comp[1] - 'x';
      out.push_back({info.name, g.K(i, j), std::sqrt(std::max(0.0, g.P_K(3 * i + j, 3 * i + j)))});
      continue;
    }
    if (kind != "bias" && kind != "scale" && kind != "misalignment") continue;
    const Eigen::Matrix3d& M = gyro ? g.G : a.A;
    const Eigen::MatrixXd& P = gyro ? g.P : a.P;
    int index = 0;
    double value = 0.0;
    if (kind == "bias") {
      const int i = comp[0] - 'x';
      index = 9 + i;
      value = gyro ? g.b(i) : a.b(i);
    } else {
      const int i = comp[0] - 'x', j = kind == "scale" ? i : comp[1] - 'x';
      index = 3 * i + j;
      value = M(i, j) - (i == j ? 1.0 : 0.0);
    }
    out.push_back({info.name, value, std::sqrt(std::max(0.0, P(index, index)))});
  }
  return out;
}

// K against zero by its covariance (Wald, 9 dof).
GSensitivityTest g_sensitivity_test(const GyroFit& g, double alpha) {
  GSensitivityTest t;
  t.dof = 9;
  t.K = g.K;
  Eigen::Matrix<double, 9, 1> k;
  for (int i = 0; i < 9; ++i) {
    k(i) = g.K(i / 3, i % 3);
    t.K_sigma(i / 3, i % 3) = std::sqrt(std::max(0.0, g.P_K(i, i)));
  }
  chi2_verdict(t, "wald", k.dot(g.P_K.ldlt().solve(k)));
  mark_significant(t, alpha);
  const boost::math::chi_squared chi2(t.dof);
  t.detection_limit = std::sqrt(boost::math::quantile(chi2, 1.0 - alpha)) * t.K_sigma.maxCoeff();
  return t;
}

}  // namespace

std::vector<PartStatistics> read_parts(const Session& session) {
  const FerrarisDeclaration& d = session.six_face ? *session.six_face : FerrarisDeclaration{};
  LogReader reader(session.log);
  PartAccumulator parts({d.turns.begin(), d.turns.end()});
  ImuSample s;
  while (reader.next(s)) {
    if (s.label < 0)
      throw LogError(session.log.file, reader.line(),
                     "a six-face log needs a label column (columns = ... label ...): the part "
                     "each sample belongs to");
    try {
      parts.push(s, reader.labels()[static_cast<std::size_t>(s.label)]);
    } catch (const SixFaceError& e) {
      throw LogError(session.log.file, reader.line(), e.what());
    }
  }
  return parts.parts();
}

SixFaceOptions six_face_options(const Session& session) {
  SixFaceOptions o;
  if (session.six_face) o.declared = *session.six_face;
  o.gravity = session.gravity;
  if (session.has_site) o.site = session.site;
  if (!session.sensor_file.empty()) {
    const SensorProfile profile = SensorProfile::load(session.sensor_file);
    o.gyro_bias_instability = profile.noise.gyro.bias_instability;
    o.accel_bias_instability = profile.noise.accel.bias_instability;
  }
  return o;
}

SixFaceResult six_face_calibrate(const std::vector<PartStatistics>& parts,
                                 const SixFaceOptions& o) {
  if (!(o.declared.face_accuracy > 0.0 && o.declared.face_accuracy < 20.0 * units::deg))
    throw SixFaceError("six-face: the face accuracy must be within 0 and 20 deg");
  if (!(o.declared.turn_accuracy > 0.0 && o.declared.turn_accuracy < 45.0 * units::deg))
    throw SixFaceError("six-face: the turn accuracy must be within 0 and 45 deg");
  if (!(std::abs(o.declared.turn_angle) > 10.0 * units::deg))
    throw SixFaceError("six-face: the declared turn angle must be at least 10 deg");
  SixFaceResult r;
  r.gravity = o.gravity > 0.0 ? o.gravity
              : o.site        ? Earth::wgs84().gravity_n(o.site->lat_rad, o.site->h_m).norm()
                              : 0.0;
  if (!(r.gravity > 0.0))
    throw SixFaceError("six-face: give the site ([site] latitude) or the gravity");
  const Located l = locate(parts, o);
  check_faces(l, o);
  check_turns(l, o);
  Eigen::Vector3d white_rate;
  AccelFit acc = fit_accel(l, r.gravity, o, rest_noise(l, o, white_rate));
  const GyroFit gyr = fit_gyro(l, acc, o);
  r.accel_chi2 = acc.chi2;
  r.accel_dof = 18 + 12 - 24;
  r.earth_rate_bound = gyr.earth_bound;
  r.coefficients = coefficients_of(acc, gyr, o.g_sensitivity);
  if (o.g_sensitivity) r.g_test = g_sensitivity_test(gyr, o.alpha);
  for (const auto& c : r.coefficients) {
    const auto& cat = coefficient_catalog();
    for (std::size_t i = 0; i < cat.size(); ++i)
      if (cat[i].name == c.name) r.model.set(c.name, c.value / cat[i].si_per_unit);
  }
  const Eigen::Matrix3d A_inv = acc.A.inverse(), G_inv = gyr.G.inverse();
  for (int k = 0; k < 6; ++k) {
    const PartStatistics& p = *l.faces[static_cast<std::size_t>(k)];
    SixFaceFace f;
    f.label = p.label;
    f.duration = p.duration;
    f.tilt = acc.d.segment<2>(2 * static_cast<Eigen::Index>(k));
    f.tilt_sigma = acc.P.block<2, 2>(12 + 2 * k, 12 + 2 * k).diagonal().cwiseSqrt();
    f.gravity_error = (A_inv * (p.mean_f - acc.b)).norm() - r.gravity;
    r.faces.push_back(f);
  }
  for (int j = 0; j < 3; ++j) {
    const PartStatistics& p = *l.turns[static_cast<std::size_t>(j)];
    const Eigen::Vector3d& a = gyr.axes[static_cast<std::size_t>(j)];
    r.turns.push_back(
        {p.label, p.duration, a.dot(G_inv * (p.integral_dtheta - gyr.b * p.duration)), a});
  }
  double mis = 0.0;
  for (const auto& c : r.coefficients)
    if (c.name.rfind("accel.misalignment", 0) == 0) mis = std::max(mis, c.sigma);
  r.undetermined = {
      "accel.misalignment: relative to the box's faces only to the placement accuracy (sigma up "
      "to " +
          fmt("%.0f", mis / units::arcsec) + " arcsec from the faces' " +
          fmt("%.2f", o.declared.face_accuracy / units::deg) +
          " deg): a face's tilt and the misalignment it reads are one unknown",
      "gyro.scale: no better than the turns' total angle (" +
          fmt("%.2f", o.declared.turn_accuracy / units::deg) + " deg of " +
          fmt("%.0f", o.declared.turn_angle / units::deg) + " deg: " +
          fmt("%.3f", 100.0 * o.declared.turn_accuracy / std::abs(o.declared.turn_angle)) +
          " %), which no gravity reference sees",
      "gyro.bias: the Earth rate not modelled is noise of " +
          fmt("%.4f", r.earth_rate_bound / units::deg_per_s) + " deg/s per axis (" +
          fmt("%.1f", r.earth_rate_bound / units::deg * 3600.0) + " deg/h)" +
          (o.site ? " (horizontal part; the vertical one is modelled)" : " (no site given)"),
      "extended terms (K2, scale asymmetry, lever arms, time delay, drift) are not determined by "
      "six rests and three turns"};
  return r;
}

}  // namespace sinscal
