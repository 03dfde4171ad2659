#include "filter/table_free/table_free.hpp"

#include <ceres/ceres.h>
#include <ceres/sphere_manifold.h>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <sstream>

#include "models/units.hpp"

namespace sinscal {
namespace {

// Parameter blocks.
//   accel (9): b_x b_y b_z, k_x k_y k_z, m_yx m_zx m_zy   (A lower triangular)
//   gyro bias (3): b_x b_y b_z
//   gyro linear (9): k_x k_y k_z, m_xy m_xz m_yx m_yz m_zx m_zy
//   u_p (3): unit gravity-opposite direction (direction of the specific force) of pose p, body
constexpr int kAccel = 9, kGyroBias = 3, kGyroLin = 9;
constexpr int kVarianceRounds = 10;  // of the joint fit's part weights

// The error model's linear part, I + diag(k) + M (models/imu_error_model.hpp), in the
// parametrisation of the blocks above, for any scalar type (Ceres Jets).
template <class T>
void accel_matrix(const T* a, T A[3][3]) {
  A[0][0] = T(1.0) + a[3];
  A[0][1] = T(0.0);
  A[0][2] = T(0.0);
  A[1][0] = a[6];
  A[1][1] = T(1.0) + a[4];
  A[1][2] = T(0.0);
  A[2][0] = a[7];
  A[2][1] = a[8];
  A[2][2] = T(1.0) + a[5];
}

template <class T>
void gyro_matrix(const T* g, T G[3][3]) {
  G[0][0] = T(1.0) + g[0];
  G[1][1] = T(1.0) + g[1];
  G[2][2] = T(1.0) + g[2];
  G[0][1] = g[3];
  G[0][2] = g[4];
  G[1][0] = g[5];
  G[1][2] = g[6];
  G[2][0] = g[7];
  G[2][1] = g[8];
}

template <class T>
void inverse3(const T M[3][3], T R[3][3]) {
  const T c00 = M[1][1] * M[2][2] - M[1][2] * M[2][1];
  const T c01 = M[1][2] * M[2][0] - M[1][0] * M[2][2];
  const T c02 = M[1][0] * M[2][1] - M[1][1] * M[2][0];
  const T inv_det = T(1.0) / (M[0][0] * c00 + M[0][1] * c01 + M[0][2] * c02);
  R[0][0] = c00 * inv_det;
  R[1][0] = c01 * inv_det;
  R[2][0] = c02 * inv_det;
  R[0][1] = (M[0][2] * M[2][1] - M[0][1] * M[2][2]) * inv_det;
  R[1][1] = (M[0][0] * M[2][2] - M[0][2] * M[2][0]) * inv_det;
  R[2][1] = (M[0][1] * M[2][0] - M[0][0] * M[2][1]) * inv_det;
  R[0][2] = (M[0][1] * M[1][2] - M[0][2] * M[1][1]) * inv_det;
  R[1][2] = (M[0][2] * M[1][0] - M[0][0] * M[1][2]) * inv_det;
  R[2][2] = (M[0][0] * M[1][1] - M[0][1] * M[1][0]) * inv_det;
}

/// Quaternion (w, x, y, z) of a rotation vector: series in theta^2 below 0.1 rad (exact to
/// rounding there and smooth through zero for autodiff), closed form above.
template <class T>
void quat_of_rotvec(const T v[3], T q[4]) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T t2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
  T c, s;  // cos(theta / 2), sin(theta / 2) / theta
  if (t2 < T(0.01)) {
    c = T(1.0) - t2 / 8.0 + t2 * t2 / 384.0 - t2 * t2 * t2 / 46080.0;
    s = T(0.5) - t2 / 48.0 + t2 * t2 / 3840.0 - t2 * t2 * t2 / 645120.0;
  } else {
    const T th = sqrt(t2);
    c = cos(th / 2.0);
    s = sin(th / 2.0) / th;
  }
  q[0] = c;
  q[1] = s * v[0];
  q[2] = s * v[1];
  q[3] = s * v[2];
}

template <class T>
void quat_mul(const T a[4], const T b[4], T out[4]) {
  out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

/// Rotation C_{b(end)}^{b(start)} over readings (k0, k1] of the gyro rates calibrated with the
/// gyro blocks: rotation vectors of the compensated increments with the two-sample coning term
/// (phi_k + phi_{k-1} x phi_k / 12), chained as quaternions. Returns the row-major matrix.
template <class T>
void integrate_turn(const std::vector<ImuReading>& r, std::size_t k0, std::size_t k1, const T* bias,
                    const T* lin, T C[3][3]) {
  T G[3][3], Gi[3][3];
  gyro_matrix(lin, G);
  inverse3(G, Gi);
  T q[4] = {T(1.0), T(0.0), T(0.0), T(0.0)};
  T prev[3] = {T(0.0), T(0.0), T(0.0)};
  for (std::size_t k = k0 + 1; k <= k1; ++k) {
    const double dt = r[k].t - r[k - 1].t;
    T d[3], phi[3];
    for (int i = 0; i < 3; ++i) d[i] = (T(r[k].gyro(i)) - bias[i]) * dt;
    for (int i = 0; i < 3; ++i) phi[i] = Gi[i][0] * d[0] + Gi[i][1] * d[1] + Gi[i][2] * d[2];
    T v[3] = {phi[0] + (prev[1] * phi[2] - prev[2] * phi[1]) / 12.0,
              phi[1] + (prev[2] * phi[0] - prev[0] * phi[2]) / 12.0,
              phi[2] + (prev[0] * phi[1] - prev[1] * phi[0]) / 12.0};
    T dq[4], qn[4];
    quat_of_rotvec(v, dq);
    quat_mul(q, dq, qn);
    for (int i = 0; i < 4; ++i) q[i] = qn[i];
    for (int i = 0; i < 3; ++i) prev[i] = phi[i];
  }
  using std::sqrt;
  const T norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (auto& x : q) x = x / norm;
  const T &w = q[0], &x = q[1], &y = q[2], &z = q[3];
  C[0][0] = T(1.0) - 2.0 * (y * y + z * z);
  C[0][1] = 2.0 * (x * y - w * z);
  C[0][2] = 2.0 * (x * z + w * y);
  C[1][0] = 2.0 * (x * y + w * z);
  C[1][1] = T(1.0) - 2.0 * (x * x + z * z);
  C[1][2] = 2.0 * (y * z - w * x);
  C[2][0] = 2.0 * (x * z - w * y);
  C[2][1] = 2.0 * (y * z + w * x);
  C[2][2] = T(1.0) - 2.0 * (x * x + y * y);
}

/// Stage 1: |A^-1 (y - b)| = g.
struct GravityMagnitudeCost {
  Eigen::Vector3d y;
  double g, inv_sigma;
  template <class T>
  bool operator()(const T* a, T* res) const {
    T A[3][3];
    accel_matrix(a, A);
    // Forward substitution (A lower triangular).
    T f[3];
    f[0] = (T(y(0)) - a[0]) / A[0][0];
    f[1] = (T(y(1)) - a[1] - A[1][0] * f[0]) / A[1][1];
    f[2] = (T(y(2)) - a[2] - A[2][0] * f[0] - A[2][1] * f[1]) / A[2][2];
    using std::sqrt;
    res[0] = (sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]) - g) * inv_sigma;
    return true;
  }
};

/// Joint: the pose's mean specific force, y_a - (A g u + b_a), whitened per axis.
struct AccelPoseCost {
  Eigen::Vector3d y, inv_sigma;
  double g;
  template <class T>
  bool operator()(const T* a, const T* u, T* res) const {
    T A[3][3];
    accel_matrix(a, A);
    for (int i = 0; i < 3; ++i)
      res[i] =
          (T(y(i)) - a[i] - g * (A[i][0] * u[0] + A[i][1] * u[1] + A[i][2] * u[2])) * inv_sigma(i);
    return true;
  }
};

/// Joint: the pose's mean rate, y_g - (b_g + G w_v), w_v = Omega sin(lat) u (the Earth rate's
/// vertical part), whitened with the pose's covariance (noise plus horizontal Earth rate).
struct GyroPoseCost {
  Eigen::Vector3d y;
  Eigen::Matrix3d W;  // inverse Cholesky factor of the covariance
  double omega_v;     // Omega sin(lat), rad/s (0 without a site)
  template <class T>
  bool operator()(const T* b, const T* lin, const T* u, T* res) const {
    T G[3][3];
    gyro_matrix(lin, G);
    T e[3];
    for (int i = 0; i < 3; ++i)
      e[i] = T(y(i)) - b[i] - omega_v * (G[i][0] * u[0] + G[i][1] * u[1] + G[i][2] * u[2]);
    for (int i = 0; i < 3; ++i) res[i] = W(i, 0) * e[0] + W(i, 1) * e[1] + W(i, 2) * e[2];
    return true;
  }
};

/// A turn between two poses: the tangent components of R^T u_from - u_to, over sigma.
class TurnCost : public ceres::SizedCostFunction<2, kGyroBias, kGyroLin, 3, 3> {
 public:
  TurnCost(const std::vector<ImuReading>& r, std::size_t k0, std::size_t k1,
           const Eigen::Matrix<double, 3, 2>& E, double inv_sigma)
      : r_(r), k0_(k0), k1_(k1), Et_(E.transpose() * inv_sigma) {}

  using Map23 = Eigen::Map<Eigen::Matrix<double, 2, 3, Eigen::RowMajor>>;
  using Map29 = Eigen::Map<Eigen::Matrix<double, 2, 9, Eigen::RowMajor>>;

  bool Evaluate(double const* const* p, double* res, double** jac) const override {
    const double* u_from = p[2];
    const double* u_to = p[3];
    double C[3][3];
    const bool need_gyro = jac != nullptr && (jac[0] != nullptr || jac[1] != nullptr);
    using Jet = ceres::Jet<double, kGyroBias + kGyroLin>;
    Jet CJ[3][3];
    if (need_gyro) {
      Jet b[3], lin[9];
      for (int i = 0; i < 3; ++i) b[i] = Jet(p[0][i], i);
      for (int i = 0; i < 9; ++i) lin[i] = Jet(p[1][i], 3 + i);
      integrate_turn(r_, k0_, k1_, b, lin, CJ);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) C[i][j] = CJ[i][j].a;
    } else {
      integrate_turn(r_, k0_, k1_, p[0], p[1], C);
    }
    // Predicted direction at the end: C^T u_from.
    Eigen::Vector3d pred, d;
    for (int j = 0; j < 3; ++j)
      pred(j) = C[0][j] * u_from[0] + C[1][j] * u_from[1] + C[2][j] * u_from[2];
    for (int j = 0; j < 3; ++j) d(j) = pred(j) - u_to[j];
    const Eigen::Vector2d rr = Et_ * d;
    res[0] = rr(0);
    res[1] = rr(1);
    if (jac == nullptr) return true;
    if (need_gyro) {
      // d pred_j / d theta = sum_i dC[i][j] u_from[i]
      Eigen::Matrix<double, 3, 12> dpred = Eigen::Matrix<double, 3, 12>::Zero();
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) dpred.row(j) += u_from[i] * CJ[i][j].v.transpose();
      const Eigen::Matrix<double, 2, 12> J = Et_ * dpred;
      if (jac[0] != nullptr) Map23{jac[0]} = J.leftCols<3>();
      if (jac[1] != nullptr) Map29{jac[1]} = J.rightCols<9>();
    }
    if (jac[2] != nullptr) {
      Eigen::Matrix3d Ct;
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) Ct(j, i) = C[i][j];
      Map23{jac[2]} = Et_ * Ct;
    }
    if (jac[3] != nullptr) Map23{jac[3]} = -Et_;
    return true;
  }

 private:
  const std::vector<ImuReading>& r_;
  std::size_t k0_, k1_;
  Eigen::Matrix<double, 2, 3> Et_;
};

Eigen::Matrix<double, 3, 2> tangent_basis(const Eigen::Vector3d& u) {
  Eigen::Index smallest;
  u.cwiseAbs().minCoeff(&smallest);
  const Eigen::Vector3d e1 = u.cross(Eigen::Vector3d::Unit(smallest)).normalized();
  Eigen::Matrix<double, 3, 2> E;
  E.col(0) = e1;
  E.col(1) = u.cross(e1).normalized();
  return E;
}

ceres::Solver::Options solver_options(int max_iterations) {
  ceres::Solver::Options o;
  o.linear_solver_type = ceres::DENSE_QR;
  o.max_num_iterations = max_iterations;
  o.function_tolerance = 1e-12;
  o.gradient_tolerance = 1e-14;
  o.parameter_tolerance = 1e-12;
  o.num_threads = 1;
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  return o;
}

TableFreeStage run(ceres::Problem& problem, int max_iterations, const char* stage) {
  ceres::Solver::Summary s;
  ceres::Solve(solver_options(max_iterations), &problem, &s);
  if (!s.IsSolutionUsable())
    throw TableFreeError(
        TableFreeError::Kind::SolveFailed,
        std::string("table-free calibration: the ") + stage + " stage failed: " + s.message);
  TableFreeStage st;
  st.iterations = s.num_successful_steps + s.num_unsuccessful_steps;
  st.converged = s.termination_type == ceres::CONVERGENCE;
  st.message = s.message;
  st.chi2 = 2.0 * s.final_cost;
  st.residuals = s.num_residuals_reduced;
  st.parameters = s.num_effective_parameters_reduced;
  return st;
}

struct PoseData {
  const Pose* pose;
  std::size_t first, last;  // trimmed
  Eigen::Vector3d accel, gyro, accel_std, gyro_std;
  double n;
};

using Kind = TableFreeError::Kind;

// Turns: from the last reading of pose p's trimmed stretch to the first of pose p+1's.
struct Turn {
  std::size_t k0, k1;
  Eigen::Matrix<double, 3, 2> E;
  double inv_sigma;
};

// The index of each catalog coefficient in the block vector [accel(9), gyro bias(3), gyro lin(9)],
// in catalog order: gyro bias, scale, misalignment; accel bias, scale, misalignment.
struct Slot {
  const char* name;
  int index;  // -1: fixed by convention
};
constexpr Slot kSlots[24] = {
    {"gyro.bias.x", 9},
    {"gyro.bias.y", 10},
    {"gyro.bias.z", 11},
    {"gyro.scale.x", 12},
    {"gyro.scale.y", 13},
    {"gyro.scale.z", 14},
    {"gyro.misalignment.xy", 15},
    {"gyro.misalignment.xz", 16},
    {"gyro.misalignment.yx", 17},
    {"gyro.misalignment.yz", 18},
    {"gyro.misalignment.zx", 19},
    {"gyro.misalignment.zy", 20},
    {"accel.bias.x", 0},
    {"accel.bias.y", 1},
    {"accel.bias.z", 2},
    {"accel.scale.x", 3},
    {"accel.scale.y", 4},
    {"accel.scale.z", 5},
    {"accel.misalignment.xy", -1},
    {"accel.misalignment.xz", -1},
    {"accel.misalignment.yx", 6},
    {"accel.misalignment.yz", -1},
    {"accel.misalignment.zx", 7},
    {"accel.misalignment.zy", 8},
};

// The three stages of the table-free calibration over one record and its poses: the
// accelerometers from the gravity magnitude, the gyros from the turns, then the joint
// maximum-likelihood refinement with per-pose gravity directions.
class TableFreeSolver {
 public:
  TableFreeSolver(const std::vector<ImuReading>& r, const TableFreeOptions& o, TableFreeResult& out)
      : r_(r), o_(o), out_(out) {}

  void solve(const std::vector<Pose>& poses) {
    set_earth();
    check_readings();
    pose_data(poses);
    check_directions();
    pooled_noise();
    solve_accelerometers();
    make_turns();
    solve_gyros();
    solve_joint();
    pose_fits();
  }

 private:
  void set_earth() {
    if (o_.gravity > 0.0) {
      out_.gravity = o_.gravity;
    } else if (o_.site) {
      out_.gravity = Earth::wgs84().gravity_n(o_.site->lat_rad, o_.site->h_m).norm();
    } else {
      throw TableFreeError(Kind::BadInput,
                           "table-free calibration: give the local gravity or the site");
    }
    g_ = out_.gravity;
    Omega_ = Earth::wgs84().rate();
    omega_v_ = o_.site ? Omega_ * std::sin(o_.site->lat_rad) : 0.0;
    omega_h_ = o_.site ? Omega_ * std::cos(o_.site->lat_rad) : 0.0;
    if (!(o_.edge_trim >= 0.0) || !(o_.min_pose > 0.0) || o_.min_poses < 10 ||
        o_.max_iterations < 1)
      throw TableFreeError(Kind::BadInput,
                           "table-free calibration: options out of range (min_poses must be at "
                           "least 10: 9 accelerometer unknowns and one residual)");
  }

  void check_readings() const {
    for (std::size_t k = 0; k < r_.size(); ++k) {
      if (!r_[k].accel.allFinite() || !r_[k].gyro.allFinite() || !std::isfinite(r_[k].t))
        throw TableFreeError(Kind::BadInput, "table-free calibration: reading " +
                                                 std::to_string(k + 1) + " is not finite");
      if (k > 0 && !(r_[k].t > r_[k - 1].t))
        throw TableFreeError(
            Kind::BadInput,
            "table-free calibration: times do not increase at reading " + std::to_string(k + 1));
    }
  }

  // Poses: in order, inside the record, trimmed, long enough.
  void pose_data(const std::vector<Pose>& poses) {
    if (static_cast<int>(poses.size()) < o_.min_poses) {
      std::ostringstream m;
      m << "table-free calibration needs at least " << o_.min_poses
        << " static poses (the accelerometer triad has 9 unknowns, one equation per pose); found "
        << poses.size();
      throw TableFreeError(Kind::TooFewPoses, m.str());
    }
    std::ostringstream too_short;
    for (std::size_t p = 0; p < poses.size(); ++p) {
      const Pose& ps = poses[p];
      if (ps.last >= r_.size() || ps.last <= ps.first || (p > 0 && ps.first <= poses[p - 1].last))
        throw TableFreeError(Kind::BadInput,
                             "table-free calibration: pose " + std::to_string(ps.index) +
                                 " is outside the readings or overlaps the previous one");
      std::size_t a = ps.first, b = ps.last;
      while (a < b && r_[a].t < r_[ps.first].t + o_.edge_trim) ++a;
      while (b > a && r_[b].t > r_[ps.last].t - o_.edge_trim) --b;
      if (r_[b].t - r_[a].t < o_.min_pose) {
        too_short << (too_short.tellp() > 0 ? ", " : "") << ps.index << " ("
                  << r_[ps.last].t - r_[ps.first].t << " s)";
        continue;
      }
      PoseData d;
      d.pose = &ps;
      d.first = a;
      d.last = b;
      d.n = static_cast<double>(b - a + 1);
      reading_statistics(r_, a, b, d.accel, d.gyro, d.accel_std, d.gyro_std);
      pd_.push_back(d);
    }
    if (too_short.tellp() > 0) {
      std::ostringstream m;
      m << "table-free calibration: poses too short for their means (need " << o_.min_pose
        << " s after cutting " << o_.edge_trim << " s at each end): " << too_short.str();
      throw TableFreeError(Kind::PoseTooShort, m.str());
    }
  }

  // The accelerometer triad is observable only if gravity points along every axis in some pose:
  // directions all near one plane leave the scale factor normal to it undetermined.
  void check_directions() const {
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    for (const auto& d : pd_) {
      const Eigen::Vector3d u0 = d.accel.normalized();
      S += u0 * u0.transpose() / static_cast<double>(pd_.size());
    }
    const double smallest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(S).eigenvalues()(0);
    if (smallest < 1e-3) {
      std::ostringstream m;
      m << "table-free calibration: the poses' gravity directions lie within "
        << std::asin(std::sqrt(smallest)) / units::deg
        << " deg (RMS) of one plane: the accelerometer triad is not observable; turn the unit "
           "so that every axis points up and down in some poses";
      throw TableFreeError(Kind::SolveFailed, m.str());
    }
  }

  // Noise per reading, pooled over the poses; rate noise density from the sample interval.
  void pooled_noise() {
    va_ = Eigen::Vector3d::Zero();
    vg_ = Eigen::Vector3d::Zero();
    double dof_sum = 0.0, t_sum = 0.0;
    for (const auto& d : pd_) {
      va_ += (d.n - 1.0) * d.accel_std.cwiseAbs2();
      vg_ += (d.n - 1.0) * d.gyro_std.cwiseAbs2();
      dof_sum += d.n - 1.0;
      t_sum += r_[d.last].t - r_[d.first].t;
    }
    va_ /= dof_sum;
    vg_ /= dof_sum;
    // Quantized noise-free data may rest without any variance: floor at rounding level.
    for (int i = 0; i < 3; ++i) {
      va_(i) = std::max(va_(i), 1e-30 + 1e-24 * g_ * g_);
      vg_(i) = std::max(vg_(i), 1e-30);
    }
    out_.accel_noise = va_.cwiseSqrt();
    out_.gyro_noise = vg_.cwiseSqrt();
    const double dt_mean = t_sum / dof_sum;
    mean_count_ = 0.0;
    for (const auto& d : pd_) mean_count_ += d.n / static_cast<double>(pd_.size());
    rate_psd_ = vg_.mean() * dt_mean;  // rad^2/s: per-axis angle variance per second
  }

  TriadErrors accel_errors() const {
    TriadErrors e;
    e.bias = Eigen::Vector3d(a_[0], a_[1], a_[2]);
    e.scale = Eigen::Vector3d(a_[3], a_[4], a_[5]);
    e.misalignment(1, 0) = a_[6];
    e.misalignment(2, 0) = a_[7];
    e.misalignment(2, 1) = a_[8];
    return e;
  }

  // Stage 1: accelerometers from the gravity magnitude; the poses' directions from them.
  void solve_accelerometers() {
    ceres::Problem problem;
    for (const auto& d : pd_) {
      const Eigen::Vector3d dir = d.accel.normalized();
      const double sigma = std::sqrt(dir.cwiseAbs2().dot(va_) / d.n);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<GravityMagnitudeCost, 1, kAccel>(
                                   new GravityMagnitudeCost{d.accel, g_, 1.0 / sigma}),
                               nullptr, a_);
    }
    out_.accel_stage = run(problem, o_.max_iterations, "accelerometer");
    const TriadErrors accel_est = accel_errors();
    u_.resize(pd_.size());
    for (std::size_t p = 0; p < pd_.size(); ++p)
      u_[p] = accel_est.invert_step(pd_[p].accel, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero())
                  .normalized();
  }

  void make_turns() {
    for (std::size_t p = 0; p + 1 < pd_.size(); ++p) {
      Turn t;
      t.k0 = pd_[p].last;
      t.k1 = pd_[p + 1].first;
      const double T = r_[t.k1].t - r_[t.k0].t;
      const double earth =
          o_.site ? omega_h_ * omega_h_ * T * T / 2.0 : Omega_ * Omega_ * T * T / 3.0;
      t.E = tangent_basis(u_[p + 1]);
      t.inv_sigma = 1.0 / std::sqrt(rate_psd_ * T + earth);
      turns_.push_back(t);
    }
  }

  void add_turns(ceres::Problem& problem, double factor = 1.0) {
    turn_ids_.clear();
    for (std::size_t p = 0; p + 1 < pd_.size(); ++p)
      turn_ids_.push_back(problem.AddResidualBlock(
          new TurnCost(r_, turns_[p].k0, turns_[p].k1, turns_[p].E, turns_[p].inv_sigma),
          weight(factor), gb_, gl_, u_[p].data(), u_[p + 1].data()));
  }

  // Stage 2: gyro bias from the poses' mean rates, then the gyro matrix from the turns.
  void solve_gyros() {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double n = 0.0;
    for (std::size_t p = 0; p < pd_.size(); ++p) {
      sum += pd_[p].n * (pd_[p].gyro - omega_v_ * u_[p]);
      n += pd_[p].n;
    }
    for (int i = 0; i < 3; ++i) gb_[i] = sum(i) / n;
    ceres::Problem problem;
    add_turns(problem);
    problem.SetParameterBlockConstant(gb_);
    for (auto& v : u_) problem.SetParameterBlockConstant(v.data());
    out_.gyro_stage = run(problem, o_.max_iterations, "gyro");
  }

  // Stage 3: joint refinement. The noise model of each part is completed from its own
  // residuals (variance components, docs/methods/table-free.md "Sigmas and the fit gate"): the
  // static poses' means by an additive bias wander per triad (the fit takes one constant bias;
  // a drifting bias moves every pose's mean alike, long or short), the turns by a variance factor
  // (timing errors grow with the turn); re-estimated and the fit repeated until they settle.
  // A part beyond its noise model then no longer drags the parts that hold theirs (the poses'
  // gravity directions), and the covariance is the completed model's. The gate judges the parts'
  // chi2 against the data's white noise alone.
  void solve_joint() {
    Weights w;
    for (int round = 0; round < kVarianceRounds; ++round) {
      ceres::Problem problem;
      build_joint(problem, w);
      solve_joint_once(problem);
      const Weights next = next_weights();
      const bool settled = w.settled(next, va_.mean() / mean_count_, vg_.mean() / mean_count_);
      out_.variance_rounds = round + 1;
      if (settled || round + 1 == kVarianceRounds) {
        out_.variance_settled = settled;
        step_over_sigma(problem);
        store_coefficients(covariance_of_blocks(problem));
        white_parts(w);
        return;
      }
      w = next;
    }
  }

  struct Weights {
    double accel = 0.0, gyro = 0.0;  // bias wander variances added to each pose mean's
    double turns = 1.0;              // variance factor of the turns
    bool settled(const Weights& n, double accel_white, double gyro_white) const {
      return std::abs(n.accel - accel) < 0.02 * (accel + accel_white) &&
             std::abs(n.gyro - gyro) < 0.02 * (gyro + gyro_white) &&
             std::abs(n.turns / turns - 1.0) < 0.01;
    }
  };

  // tau^2 >= 0 with sum e^2 / (s^2 + tau^2) = dof (0 when the white noise explains them).
  static double additive_variance(const std::vector<double>& e2, const std::vector<double>& s2,
                                  double dof) {
    auto excess = [&](double tau2) {
      double sum = 0.0;
      for (std::size_t i = 0; i < e2.size(); ++i) sum += e2[i] / (s2[i] + tau2);
      return sum - dof;
    };
    if (!(dof > 0.0) || excess(0.0) <= 0.0) return 0.0;
    double lo = 0.0, hi = 0.0;
    for (double x : e2) hi += x;
    for (int k = 0; k < 100; ++k) {
      const double mid = 0.5 * (lo + hi);
      (excess(mid) > 0.0 ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
  }

  // The next round's weights from this solution's residuals.
  Weights next_weights() {
    Weights n;
    std::vector<double> ea, sa, eg, sg;
    for (std::size_t p = 0; p < pd_.size(); ++p) {
      const auto& d = pd_[p];
      double ra[3], rg[3];
      AccelPoseCost{d.accel, Eigen::Vector3d::Ones(), g_}(a_, u_[p].data(), ra);
      GyroPoseCost{d.gyro, Eigen::Matrix3d::Identity(), omega_v_}(gb_, gl_, u_[p].data(), rg);
      const Eigen::Matrix3d cov = gyro_pose_covariance(p, 0.0);
      for (int i = 0; i < 3; ++i) {
        ea.push_back(ra[i] * ra[i]);
        sa.push_back(va_(i) / d.n);
        eg.push_back(rg[i] * rg[i]);
        sg.push_back(cov(i, i));
      }
    }
    n.accel = additive_variance(ea, sa, out_.accel_fit.dof);
    n.gyro = additive_variance(eg, sg, out_.gyro_rest_fit.dof);
    n.turns = std::max(1.0, out_.turn_fit.chi2_per_dof());
    return n;
  }

  // The parts' chi2 against the white noise alone (the gate's), at the solution; the weights
  // found (bias wander, the turns' factor) recorded with them.
  void white_parts(const Weights& w) {
    ceres::Problem white;
    build_joint(white, Weights{});
    out_.turns.clear();
    fit_parts(white);
    out_.chi2 = out_.accel_fit.chi2 + out_.gyro_rest_fit.chi2 + out_.turn_fit.chi2;
    out_.chi2_per_dof = out_.chi2 / out_.dof;
    out_.accel_fit.wander = std::sqrt(w.accel);
    out_.gyro_rest_fit.wander = std::sqrt(w.gyro);
    // A typical pose mean's sigma over its white noise's; the turns' factor's root.
    out_.accel_fit.sigma_scale = std::sqrt(1.0 + w.accel * mean_count_ / va_.mean());
    out_.gyro_rest_fit.sigma_scale = std::sqrt(1.0 + w.gyro * mean_count_ / vg_.mean());
    out_.turn_fit.sigma_scale = std::sqrt(w.turns);
  }

  static ceres::LossFunction* weight(double factor) {
    return factor > 1.0 ? new ceres::ScaledLoss(nullptr, 1.0 / factor, ceres::TAKE_OWNERSHIP)
                        : nullptr;
  }

  // A pose mean's rate covariance: white noise, the Earth rate's unknown part, a bias wander.
  Eigen::Matrix3d gyro_pose_covariance(std::size_t p, double wander) const {
    Eigen::Matrix3d cov = (vg_ / pd_[p].n).asDiagonal();
    cov += o_.site ? Eigen::Matrix3d(omega_h_ * omega_h_ / 2.0 *
                                     (Eigen::Matrix3d::Identity() - u_[p] * u_[p].transpose()))
                   : Eigen::Matrix3d(Omega_ * Omega_ / 3.0 * Eigen::Matrix3d::Identity());
    return cov + wander * Eigen::Matrix3d::Identity();
  }

  void build_joint(ceres::Problem& problem, const Weights& w) {
    accel_ids_.clear();
    gyro_ids_.clear();
    for (std::size_t p = 0; p < pd_.size(); ++p) {
      const auto& d = pd_[p];
      const Eigen::Vector3d sigma2 = va_ / d.n + Eigen::Vector3d::Constant(w.accel);
      accel_ids_.push_back(problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<AccelPoseCost, 3, kAccel, 3>(
              new AccelPoseCost{d.accel, sigma2.cwiseSqrt().cwiseInverse(), g_}),
          nullptr, a_, u_[p].data()));
      const Eigen::Matrix3d L = gyro_pose_covariance(p, w.gyro).llt().matrixL();
      gyro_ids_.push_back(problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<GyroPoseCost, 3, kGyroBias, kGyroLin, 3>(
              new GyroPoseCost{d.gyro, L.inverse(), omega_v_}),
          nullptr, gb_, gl_, u_[p].data()));
    }
    add_turns(problem, w.turns);
    for (auto& v : u_) problem.SetManifold(v.data(), new ceres::SphereManifold<3>());
  }

  void solve_joint_once(ceres::Problem& problem) {
    out_.joint_stage = run(problem, o_.max_iterations, "joint");
    if (!out_.joint_stage.converged)
      throw TableFreeError(Kind::SolveFailed,
                           "table-free calibration: the joint solution did not converge in " +
                               std::to_string(o_.max_iterations) +
                               " iterations (inconsistent data: poses that are not at rest, a "
                               "wrong gravity, or gyro columns, unit or sample rate that do not "
                               "turn the poses into each other)");
    out_.iterations =
        out_.accel_stage.iterations + out_.gyro_stage.iterations + out_.joint_stage.iterations;
    out_.termination = out_.joint_stage.message;
    out_.dof = out_.joint_stage.residuals - out_.joint_stage.parameters;
    if (out_.dof <= 0)
      throw TableFreeError(Kind::TooFewPoses,
                           "table-free calibration: no degrees of freedom left with " +
                               std::to_string(pd_.size()) + " poses");
    out_.turns.clear();
    fit_parts(problem);
    // The chi2 against the noise model (the parts' unweighted sums), not the weighted cost.
    out_.chi2 = out_.accel_fit.chi2 + out_.gyro_rest_fit.chi2 + out_.turn_fit.chi2;
    out_.chi2_per_dof = out_.chi2 / out_.dof;
  }

  // The whitened, weighted Jacobian of the fit and its residuals at the solution; its rows in
  // the order of `blocks` (all blocks in the order they were added when empty).
  static void jacobian_of(ceres::Problem& problem, Eigen::MatrixXd& J, Eigen::VectorXd* r,
                          const std::vector<ceres::ResidualBlockId>& blocks = {}) {
    ceres::Problem::EvaluateOptions eo;
    eo.residual_blocks = blocks;
    ceres::CRSMatrix crs;
    std::vector<double> res;
    problem.Evaluate(eo, nullptr, r ? &res : nullptr, nullptr, &crs);
    J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
    for (int i = 0; i < crs.num_rows; ++i)
      for (int k = crs.rows[static_cast<std::size_t>(i)];
           k < crs.rows[static_cast<std::size_t>(i) + 1]; ++k)
        J(i, crs.cols[static_cast<std::size_t>(k)]) = crs.values[static_cast<std::size_t>(k)];
    if (r) *r = Eigen::Map<Eigen::VectorXd>(res.data(), static_cast<Eigen::Index>(res.size()));
  }

  // "Converged" from the estimate: the Gauss-Newton step still left at the solution, each
  // coefficient's against its sigma (the same weighted normal equations give both). Beyond
  // kConvergedStep of a sigma somewhere the estimate is still moving: not converged.
  void step_over_sigma(ceres::Problem& problem) {
    Eigen::MatrixXd J;
    Eigen::VectorXd r;
    jacobian_of(problem, J, &r);
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(J);
    const Eigen::VectorXd step = cod.solve(-r);
    const Eigen::MatrixXd cov =
        Eigen::MatrixXd(J.transpose() * J).completeOrthogonalDecomposition().pseudoInverse();
    double worst = 0.0;
    for (const double* block : {static_cast<const double*>(a_), static_cast<const double*>(gb_),
                                static_cast<const double*>(gl_)}) {
      const int offset = column_of(problem, block);
      const int size = problem.ParameterBlockSize(block);
      for (int i = offset; i < offset + size; ++i)
        if (cov(i, i) > 0.0) worst = std::max(worst, std::abs(step(i)) / std::sqrt(cov(i, i)));
    }
    out_.step_over_sigma = worst;
    out_.converged = std::isfinite(worst) && worst < TableFreeResult::kConvergedStep;
  }

  // The first column of a parameter block in the Jacobian of Problem::Evaluate (the problem's
  // own block order, tangent sizes).
  static int column_of(ceres::Problem& problem, const double* block) {
    std::vector<double*> blocks;
    problem.GetParameterBlocks(&blocks);
    int col = 0;
    for (double* b : blocks) {
      if (b == block) return col;
      col += problem.ParameterBlockTangentSize(b);
    }
    throw TableFreeError(Kind::SolveFailed,
                         "table-free calibration: a coefficient block is not in the fit");
  }

  // The residuals of some blocks at the solution.
  static std::vector<double> residuals_of(ceres::Problem& problem,
                                          const std::vector<ceres::ResidualBlockId>& ids) {
    ceres::Problem::EvaluateOptions eo;
    eo.residual_blocks = ids;
    eo.apply_loss_function = false;
    double cost = 0.0;
    std::vector<double> r;
    problem.Evaluate(eo, &cost, &r, nullptr, nullptr);
    return r;
  }

  static TableFreeFitPart fit_part(const std::vector<double>& r, double leverage) {
    TableFreeFitPart f;
    for (double x : r) f.chi2 += x * x;
    f.residuals = static_cast<int>(r.size());
    f.dof = static_cast<double>(f.residuals) - leverage;
    if (f.dof > 0.0) f.sigma_scale = std::max(1.0, std::sqrt(f.chi2 / f.dof));
    return f;
  }

  // The leverage of each part (the sum of the hat matrix's diagonal over its residuals): the
  // parameters it determines, the directions shared with the other parts counted by share.
  // The rows part by part: the problem holds each pose's accelerometer and gyro blocks in turn.
  std::array<double, 3> leverages(ceres::Problem& problem) const {
    std::vector<ceres::ResidualBlockId> blocks = accel_ids_;
    blocks.insert(blocks.end(), gyro_ids_.begin(), gyro_ids_.end());
    blocks.insert(blocks.end(), turn_ids_.begin(), turn_ids_.end());
    Eigen::MatrixXd J;
    jacobian_of(problem, J, nullptr, blocks);
    const Eigen::MatrixXd Q = Eigen::HouseholderQR<Eigen::MatrixXd>(J).householderQ() *
                              Eigen::MatrixXd::Identity(J.rows(), J.cols());
    const Eigen::VectorXd h = Q.rowwise().squaredNorm();  // hat matrix diagonal
    const auto na = static_cast<Eigen::Index>(3 * accel_ids_.size());
    const auto ng = static_cast<Eigen::Index>(3 * gyro_ids_.size());
    return {h.head(na).sum(), h.segment(na, ng).sum(), h.tail(h.size() - na - ng).sum()};
  }

  // The chi2 in parts and the turns one by one (rate, angle, duration: the fit gate's bound).
  void fit_parts(ceres::Problem& problem) {
    const std::array<double, 3> lev = leverages(problem);
    out_.accel_fit = fit_part(residuals_of(problem, accel_ids_), lev[0]);
    out_.gyro_rest_fit = fit_part(residuals_of(problem, gyro_ids_), lev[1]);
    const std::vector<double> rt = residuals_of(problem, turn_ids_);
    out_.turn_fit = fit_part(rt, lev[2]);
    for (std::size_t p = 0; p < turns_.size(); ++p) {
      const Turn& t = turns_[p];
      TableFreeTurn o;
      o.from = pd_[p].pose->index;
      o.duration = r_[t.k1].t - r_[t.k0].t;
      for (std::size_t k = t.k0 + 1; k <= t.k1; ++k) {
        const double w = r_[k].gyro.norm();
        o.angle += w * (r_[k].t - r_[k - 1].t);
        o.peak_rate = std::max(o.peak_rate, w);
      }
      o.interval = o.duration / static_cast<double>(std::max<std::size_t>(1, t.k1 - t.k0));
      o.noise_sigma = 1.0 / t.inv_sigma;
      o.chi2 = rt[2 * p] * rt[2 * p] + rt[2 * p + 1] * rt[2 * p + 1];
      out_.turns.push_back(o);
    }
  }

  Eigen::Matrix<double, 21, 21, Eigen::RowMajor> covariance_of_blocks(ceres::Problem& problem) {
    ceres::Covariance::Options co;
    co.algorithm_type = ceres::DENSE_SVD;
    co.num_threads = 1;
    ceres::Covariance covariance(co);
    const std::vector<const double*> blocks = {a_, gb_, gl_};
    std::vector<std::pair<const double*, const double*>> pairs;
    for (std::size_t i = 0; i < blocks.size(); ++i)
      for (std::size_t j = i; j < blocks.size(); ++j) pairs.emplace_back(blocks[i], blocks[j]);
    if (!covariance.Compute(pairs, &problem))
      throw TableFreeError(Kind::SolveFailed,
                           "table-free calibration: the solution's covariance is singular (the "
                           "poses do not turn the unit about enough different axes)");
    Eigen::Matrix<double, 21, 21, Eigen::RowMajor> C_blocks;
    covariance.GetCovarianceMatrix(blocks, C_blocks.data());
    // The parts' variance factors are the fit's weights: the covariance is already scaled per
    // part (triad and stage).
    return C_blocks;
  }

  void store_coefficients(const Eigen::Matrix<double, 21, 21, Eigen::RowMajor>& C_blocks) {
    double values[21];
    std::copy(a_, a_ + 9, values);
    std::copy(gb_, gb_ + 3, values + 9);
    std::copy(gl_, gl_ + 9, values + 12);
    std::vector<int> order;
    for (const auto& s : kSlots) {
      TableFreeCoefficient c;
      c.name = s.name;
      c.fixed_by_convention = s.index < 0;
      if (s.index >= 0) {
        c.value = values[s.index];
        c.sigma = std::sqrt(C_blocks(s.index, s.index));
        order.push_back(s.index);
        out_.covariance_names.push_back(c.name);
      }
      out_.coefficients.push_back(c);
    }
    const auto m = static_cast<Eigen::Index>(order.size());
    out_.covariance.resize(m, m);
    for (Eigen::Index i = 0; i < m; ++i)
      for (Eigen::Index j = 0; j < m; ++j)
        out_.covariance(i, j) =
            C_blocks(order[static_cast<std::size_t>(i)], order[static_cast<std::size_t>(j)]);
    for (auto& [info, ptr] : out_.model.coefficient_refs())
      for (const auto& c : out_.coefficients)
        if (c.name == info.name) *ptr = c.value;
  }

  // Residuals per pose, with the model's own formula.
  void pose_fits() {
    const TriadErrors& A = out_.model.accel;
    const TriadErrors& G = out_.model.gyro;
    const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
    for (std::size_t p = 0; p < pd_.size(); ++p) {
      TableFreePoseFit f;
      f.index = pd_[p].pose->index;
      f.t_start = r_[pd_[p].first].t;
      f.t_end = r_[pd_[p].last].t;
      f.count = pd_[p].last - pd_[p].first + 1;
      f.first = pd_[p].first;
      f.last = pd_[p].last;
      f.direction = u_[p];
      f.gravity_error = A.invert_step(pd_[p].accel, zero, zero).norm() - g_;
      f.accel_rms = std::sqrt((pd_[p].accel - A.apply(g_ * u_[p], zero)).squaredNorm() / 3.0);
      f.gyro_rms = std::sqrt((pd_[p].gyro - G.apply(omega_v_ * u_[p], zero)).squaredNorm() / 3.0);
      if (p > 0) {
        double C[3][3];
        integrate_turn(r_, turns_[p - 1].k0, turns_[p - 1].k1, gb_, gl_, C);
        Eigen::Matrix3d Cm;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) Cm(i, j) = C[i][j];
        const Eigen::Vector3d pred = Cm.transpose() * u_[p - 1];
        f.turn_error = std::atan2(pred.cross(u_[p]).norm(), pred.dot(u_[p]));
        f.turn_sigma = 1.0 / turns_[p - 1].inv_sigma;
      }
      out_.poses.push_back(f);
    }
  }

  const std::vector<ImuReading>& r_;
  const TableFreeOptions& o_;
  TableFreeResult& out_;
  std::vector<PoseData> pd_;
  double g_ = 0.0, Omega_ = 0.0, omega_v_ = 0.0, omega_h_ = 0.0;
  Eigen::Vector3d va_, vg_;
  double rate_psd_ = 0.0;
  double mean_count_ = 1.0;  // readings per pose mean, on average
  double a_[kAccel] = {0.0};
  double gb_[kGyroBias] = {0.0};
  double gl_[kGyroLin] = {0.0};
  std::vector<Eigen::Vector3d> u_;
  std::vector<Turn> turns_;
  std::vector<ceres::ResidualBlockId> accel_ids_, gyro_ids_, turn_ids_;
};

}  // namespace

const TableFreeCoefficient& TableFreeResult::at(const std::string& name) const {
  for (const auto& c : coefficients)
    if (c.name == name) return c;
  throw std::invalid_argument("table-free result has no coefficient '" + name + "'");
}

TableFreeResult calibrate_table_free(const std::vector<ImuReading>& r,
                                     const std::vector<Pose>& poses, const TableFreeOptions& o) {
  TableFreeResult out;
  TableFreeSolver(r, o, out).solve(poses);
  return out;
}

TableFreeResult calibrate_table_free_counts(const std::vector<ImuReading>& counts,
                                            const RawScaling& nominal,
                                            const TableFreeOptions& options,
                                            const PoseDetectorOptions& detector) {
  std::vector<Pose> poses;
  std::vector<ImuReading> si;
  try {
    poses = detect_poses(counts, detector).poses;
    si = si_from_counts(counts, nominal);
  } catch (const PoseDetectorError& e) {
    throw TableFreeError(TableFreeError::Kind::BadInput, e.what());
  } catch (const std::invalid_argument& e) {
    throw TableFreeError(TableFreeError::Kind::BadInput, e.what());
  }
  TableFreeResult out = calibrate_table_free(si, poses, options);
  out.has_raw = true;
  auto view = [&](const TriadErrors& e, const std::string& triad, const Eigen::Vector3d& s0,
                  const Eigen::Vector3d& o0) {
    RawTriadView v;
    const char* axis[3] = {"x", "y", "z"};
    const Eigen::Matrix3d L = e.linear();
    for (int i = 0; i < 3; ++i) {
      const auto& k = out.at(triad + ".scale." + axis[i]);
      const auto& b = out.at(triad + ".bias." + axis[i]);
      v.sensitivity(i) = s0(i) * (1.0 + k.value);
      v.sensitivity_sigma(i) = std::abs(s0(i)) * k.sigma;
      v.offset(i) = o0(i) + s0(i) * b.value;
      v.offset_sigma(i) = std::abs(s0(i)) * b.sigma;
      v.row_norm(i) = std::abs(s0(i)) * L.row(i).norm();
    }
    return v;
  };
  out.accel_raw = view(out.model.accel, "accel", nominal.accel_sensitivity, nominal.accel_offset);
  out.gyro_raw = view(out.model.gyro, "gyro", nominal.gyro_sensitivity, nominal.gyro_offset);
  return out;
}

}  // namespace sinscal
