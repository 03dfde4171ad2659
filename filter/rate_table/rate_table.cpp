#include "filter/rate_table/rate_table.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <utility>

#include "filter/noise/autocorrelation.hpp"
#include "models/attitude.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

const char* const kAxis[3] = {"x", "y", "z"};

RateSegment static_segment(const std::string& label, const Eigen::Matrix3d& C, double dwell) {
  RateSegment s;
  s.label = label;
  s.C_b_n_known = C;
  s.duration = dwell;
  return s;
}

// A rotation plan's step: where it leaves the known attitude, and (rate-table segments) the
// segment it is.
void walk_step(const Plan& plan, const Table& table, const RotationStep& st, std::size_t i,
               Eigen::Matrix3d& known, std::vector<RateSegment>& out) {
  Eigen::Vector3d axis_b = st.axis_b;
  if (st.kind == RotationStep::Axis::Inner) axis_b = st.sign * table.inner_axis_b();
  if (st.kind == RotationStep::Axis::Outer)
    axis_b = known.transpose() * (st.sign * table.geometry().outer_axis_n);
  if (st.constant_rate) {
    RateSegment s;
    s.kind = RateSegment::Kind::Rate;
    s.label = "rate " + std::to_string(i + 1) + " (" + st.axis_name + ")";
    s.C_b_n_known = known;
    s.axis_b = axis_b.normalized();
    s.rate = st.rate;
    s.angle = st.angle - st.rate * st.rate / plan.move_accel;
    s.duration = s.angle / st.rate;
    out.push_back(s);
  }
  known = known * rotation(axis_b, st.angle);
  if (st.pause > 0.0)
    out.push_back(static_segment("after " + std::to_string(i + 1) + " (" + st.axis_name + ")",
                                 known, st.pause));
}

// The centred moving average of the rates over `w` readings (w odd).
std::vector<Eigen::Vector3d> smoothed_rates(const std::vector<RateReading>& r, std::size_t w) {
  std::vector<Eigen::Vector3d> out(r.size(), Eigen::Vector3d::Zero());
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  const std::size_t h = w / 2;
  std::size_t lo = 0, hi = 0;  // window [lo, hi)
  for (std::size_t k = 0; k < r.size(); ++k) {
    const std::size_t want_lo = k >= h ? k - h : 0, want_hi = std::min(r.size(), k + h + 1);
    for (; hi < want_hi; ++hi) sum += r[hi].omega;
    for (; lo < want_lo; ++lo) sum -= r[lo].omega;
    out[k] = sum / static_cast<double>(hi - lo);
  }
  return out;
}

bool matches(const Eigen::Vector3d& w, const RateSegment& s, const RateTableOptions& o) {
  if (s.kind == RateSegment::Kind::Static) return w.norm() < o.static_threshold;
  return (w - s.rate * s.axis_b).norm() < o.static_threshold + o.rate_tolerance * s.rate;
}

// `x` less its least-squares fit by a constant and a sinusoid of `step` rad per sample: what
// turns with the body in a rate segment (the Earth rate and gravity across the axis) is a known
// input, not noise, and would otherwise show as a long autocorrelation.
std::vector<double> without_turning_part(std::vector<double> x, double step) {
  if (!(step > 0.0)) return x;
  Eigen::MatrixXd A(static_cast<Eigen::Index>(x.size()), 3);
  for (Eigen::Index k = 0; k < A.rows(); ++k) {
    const double phase = step * static_cast<double>(k);
    A.row(k) << 1.0, std::cos(phase), std::sin(phase);
  }
  const Eigen::Map<const Eigen::VectorXd> y(x.data(), static_cast<Eigen::Index>(x.size()));
  const Eigen::Vector3d c = (A.transpose() * A).ldlt().solve(A.transpose() * y);
  const Eigen::VectorXd residual = y - A * c;
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = residual(static_cast<Eigen::Index>(k));
  return x;
}

// The segment's readings [a, b) trimmed by `trim` and 5 % at both ends: means, variances and
// autocorrelation times (of the readings less what turns with the body at `step` rad per reading).
SegmentMean mean_of(const std::vector<RateReading>& r, std::size_t a, std::size_t b,
                    std::size_t trim, double step) {
  const std::size_t cut = std::max(trim, (b - a) / 20);
  SegmentMean m;
  m.first = a + cut;
  m.last = b > m.first + cut + 2 ? b - cut : m.first + 2;
  m.last = std::min(m.last, b);
  m.count = m.last - m.first;
  for (std::size_t k = m.first; k < m.last; ++k) {
    m.omega += r[k].omega;
    m.f += r[k].f;
  }
  const double n = static_cast<double>(m.count);
  m.omega /= n;
  m.f /= n;
  for (std::size_t k = m.first; k < m.last; ++k) {
    m.var_omega += (r[k].omega - m.omega).cwiseAbs2();
    m.var_f += (r[k].f - m.f).cwiseAbs2();
  }
  m.var_omega /= std::max(1.0, n - 1.0);
  m.var_f /= std::max(1.0, n - 1.0);
  std::vector<double> x(m.count);
  for (int c = 0; c < 6; ++c) {
    for (std::size_t k = m.first; k < m.last; ++k)
      x[k - m.first] = c < 3 ? r[k].omega(c) : r[k].f(c - 3);
    (c < 3 ? m.tau_omega(c) : m.tau_f(c - 3)) = autocorrelation_time(without_turning_part(x, step));
  }
  return m;
}

// ---- the least squares --------------------------------------------------------------------

// The known inputs of a segment's mean: the gyros' (Earth rate included) and the accelerometers'
// (static only), and the covariance of the means (noise, table attitude, the Earth rate's part
// across a rate segment's axis that its unknown start angle leaves).
struct MeanRow {
  bool has_f = false;
  double t = 0.0;  // s: the segment's middle reading at the nominal rate
  Eigen::Vector3d x_w, x_f, y_w, y_f, f_for_gyro;
  Eigen::Matrix3d cov_w, cov_f;
};

// Components below 1e-9 of `size` (the vector's before projection) set to zero: the rounding of a
// rotated axis is not an input (it would make a coefficient look determined).
Eigen::Vector3d cleaned(Eigen::Vector3d v, double size) {
  const double floor = 1e-9 * size;
  for (int i = 0; i < 3; ++i)
    if (std::abs(v(i)) < floor) v(i) = 0.0;
  return v;
}

MeanRow row_of(const RateSegment& s, const SegmentMean& m, const Eigen::Vector3d& w_ie_n,
               const Eigen::Vector3d& f_n, const RateTableOptions& o) {
  MeanRow r;
  const Eigen::Matrix3d C_n_b = s.C_b_n_known.transpose();
  const double n = static_cast<double>(m.count);
  r.y_w = m.omega;
  r.y_f = m.f;
  r.t = 0.5 * static_cast<double>(m.first + m.last - 1) / o.nominal_rate_hz;
  // The mean's variance: var tau / n, the readings' variance about their own mean corrected by
  // (n - 1) / (n - tau) for what the mean took out of it (n / tau: the effective sample count).
  // A floor far below any sensor's noise (noise-free simulations).
  const auto of_mean = [n](const Eigen::Vector3d& var, const Eigen::Vector3d& tau) {
    Eigen::Vector3d v;
    for (int i = 0; i < 3; ++i)
      v(i) = var(i) * tau(i) * (n - 1.0) / (n * std::max(1.0, n - tau(i)));
    return v;
  };
  r.cov_w = (of_mean(m.var_omega, m.tau_omega) + Eigen::Vector3d::Constant(1e-20)).asDiagonal();
  r.cov_f = (of_mean(m.var_f, m.tau_f) + Eigen::Vector3d::Constant(1e-16)).asDiagonal();
  if (s.kind == RateSegment::Kind::Static) {
    r.has_f = true;
    r.x_w = C_n_b * w_ie_n;
    r.x_f = C_n_b * f_n;
    r.x_f = cleaned(r.x_f, f_n.norm());
    r.f_for_gyro = r.x_f;
    const Eigen::Vector3d u = r.x_f.normalized();
    r.cov_f += o.table_sigma * o.table_sigma * r.x_f.squaredNorm() *
               (Eigen::Matrix3d::Identity() - u * u.transpose());
    return r;
  }
  const Eigen::Matrix3d P = s.axis_b * s.axis_b.transpose();
  const Eigen::Matrix3d Q = Eigen::Matrix3d::Identity() - P;
  r.x_w = s.rate * s.axis_b + P * C_n_b * w_ie_n;
  r.f_for_gyro = cleaned(P * C_n_b * f_n, f_n.norm());
  // The readings used span an angle of about theta (their count at the nominal reading rate):
  // not whole revolutions, its start unknown. The across part's mean over it, with the fraction
  // of a revolution at random: variance (|omega_across| / theta)^2 per axis across.
  const double theta =
      std::max(s.rate * static_cast<double>(m.count) / o.nominal_rate_hz, 0.5 * M_PI);
  const double across = (Q * C_n_b * w_ie_n).norm() / theta;
  r.cov_w += across * across * Q;
  return r;
}

// One unknown: its name, its scale (SI per unit of the column) and its column (6 rows: gyro,
// accel) at a segment's inputs.
struct Param {
  std::string name;
  bool in_catalog = true;
  std::function<Eigen::Matrix<double, 6, 1>(const MeanRow&)> column;
};

// The gyros' scale asymmetries and (with `cross`) their cross-axis asymmetries: the even part of
// the response to each turn axis's rate.
using AddParam =
    std::function<void(const std::string&, int, std::function<double(const MeanRow&)>, bool)>;

void add_gyro_asymmetries(bool cross, const AddParam& add) {
  for (int i = 0; i < 3; ++i)
    add(
        std::string("gyro.scale_asym.") + kAxis[i], i,
        [i](const MeanRow& r) { return std::abs(r.x_w(i)); }, true);
  if (!cross) return;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j)
        add(
            std::string("gyro.cross_asym.") + kAxis[i] + kAxis[j], i,
            [j](const MeanRow& r) { return std::abs(r.x_w(j)); }, false);
}

std::vector<Param> candidate_params(bool gyro_rates, const RateTableOptions& opt) {
  const bool cross = opt.cross_asymmetry, drift = opt.gyro_drift;
  using V6 = Eigen::Matrix<double, 6, 1>;
  std::vector<Param> p;
  auto add = [&](const std::string& name, int row, std::function<double(const MeanRow&)> v,
                 bool cat = true) {
    p.push_back({name, cat, [row, v = std::move(v)](const MeanRow& r) {
                   V6 c = V6::Zero();
                   c(row) = v(r);
                   return c;
                 }});
  };
  for (int t = 0; t < 2; ++t) {
    const std::string tr = t == 0 ? "gyro." : "accel.";
    const int o = 3 * t;
    auto x = [t](const MeanRow& r) -> const Eigen::Vector3d& { return t == 0 ? r.x_w : r.x_f; };
    for (int i = 0; i < 3; ++i)
      add(tr + "bias." + kAxis[i], o + i, [](const MeanRow&) { return 1.0; });
    for (int i = 0; t == 0 && drift && i < 3; ++i)
      add(tr + "bias_drift." + kAxis[i], o + i, [](const MeanRow& r) { return r.t; });
    if (t == 0 && !gyro_rates) continue;
    for (int i = 0; i < 3; ++i)
      add(tr + "scale." + kAxis[i], o + i, [x, i](const MeanRow& r) { return x(r)(i); });
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (i != j)
          add(tr + "misalignment." + kAxis[i] + kAxis[j], o + i,
              [x, j](const MeanRow& r) { return x(r)(j); });
  }
  // The asymmetries before the g-sensitivity when the cross-axis ones are modelled: with gravity
  // along one body axis, a g-sensitivity and the offsets while turning are one column space.
  if (gyro_rates && cross) add_gyro_asymmetries(true, add);
  for (int i = 0; i < 3; ++i)
    add(std::string("accel.k2.") + kAxis[i], 3 + i,
        [i](const MeanRow& r) { return r.x_f(i) * r.x_f(i); });
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      add(std::string("gyro.g_sensitivity.") + kAxis[i] + kAxis[j], i,
          [j](const MeanRow& r) { return r.f_for_gyro(j); });
  if (gyro_rates) {
    if (!cross) add_gyro_asymmetries(false, add);
    for (int i = 0; i < 3; ++i)
      add(
          std::string("gyro.k2.") + kAxis[i], i,
          [i](const MeanRow& r) { return r.x_w(i) * r.x_w(i); }, false);
  }
  for (int i = 0; i < 3; ++i)
    add(std::string("accel.scale_asym.") + kAxis[i], 3 + i,
        [i](const MeanRow& r) { return std::abs(r.x_f(i)); });
  for (int i = 0; i < 3; ++i)
    add(
        std::string("accel.k3.") + kAxis[i], 3 + i,
        [i](const MeanRow& r) { return std::pow(r.x_f(i), 3); }, false);
  return p;
}

// The whitened system: rows of every mean (gyro rows of every segment, accel rows of the static
// ones), y - x against the candidate columns.
struct System {
  Eigen::MatrixXd A;  // whitened, all candidates
  Eigen::VectorXd b;  // whitened
};

System whitened(const std::vector<MeanRow>& rows, const std::vector<Param>& params,
                bool accel = true) {
  std::size_t n = 0;
  for (const auto& r : rows) n += r.has_f && accel ? 6 : 3;
  System s{
      Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(params.size())),
      Eigen::VectorXd::Zero(static_cast<Eigen::Index>(n))};
  Eigen::Index at = 0;
  for (const auto& r : rows) {
    for (int t = 0; t < (r.has_f && accel ? 2 : 1); ++t) {
      const Eigen::Matrix3d cov = t == 0 ? r.cov_w : r.cov_f;
      const Eigen::Matrix3d L_inv = cov.llt().matrixL().solve(Eigen::Matrix3d::Identity());
      Eigen::Matrix3Xd cols(3, params.size());
      for (std::size_t k = 0; k < params.size(); ++k)
        cols.col(static_cast<Eigen::Index>(k)) =
            params[k].column(r).segment<3>(static_cast<Eigen::Index>(3) * t);
      s.A.middleRows(at, 3) = L_inv * cols;
      s.b.segment<3>(at) = L_inv * (t == 0 ? r.y_w - r.x_w : r.y_f - r.x_f);
      at += 3;
    }
  }
  return s;
}

// Each triad's chi2 and dof: the residuals of its rows (whitened() order: per mean, 3 gyro rows
// then 3 accelerometer rows) less the coefficients of its own.
std::vector<RateTableResult::TriadFit> triad_fits(const std::vector<MeanRow>& rows,
                                                  const Eigen::VectorXd& residual,
                                                  const std::vector<Param>& params,
                                                  const std::vector<std::size_t>& keep,
                                                  bool accel) {
  RateTableResult::TriadFit gyro{"gyro", 0.0, 0}, acc{"accel", 0.0, 0};
  Eigen::Index at = 0;
  for (const auto& r : rows) {
    gyro.chi2 += residual.segment<3>(at).squaredNorm();
    gyro.dof += 3;
    at += 3;
    if (!(r.has_f && accel)) continue;
    acc.chi2 += residual.segment<3>(at).squaredNorm();
    acc.dof += 3;
    at += 3;
  }
  for (const std::size_t k : keep) --(params[k].name.rfind("accel.", 0) == 0 ? acc : gyro).dof;
  std::vector<RateTableResult::TriadFit> out{gyro};
  if (accel) out.push_back(acc);
  return out;
}

// The whitened residuals (whitened() order) per segment: gyro rows, then accelerometer rows where
// the segment has them (NaN otherwise).
std::vector<Eigen::Matrix<double, 6, 1>> per_segment(const std::vector<MeanRow>& rows,
                                                     const Eigen::VectorXd& residual, bool accel) {
  std::vector<Eigen::Matrix<double, 6, 1>> out;
  Eigen::Index at = 0;
  for (const auto& r : rows) {
    Eigen::Matrix<double, 6, 1> z;
    z.setConstant(std::numeric_limits<double>::quiet_NaN());
    z.head<3>() = residual.segment<3>(at);
    at += 3;
    if (r.has_f && accel) {
      z.tail<3>() = residual.segment<3>(at);
      at += 3;
    }
    out.push_back(z);
  }
  return out;
}

// The candidates taken in order while each adds to the rank (columns scaled to unit norm).
std::vector<std::size_t> determined(const Eigen::MatrixXd& A) {
  std::vector<std::size_t> keep;
  Eigen::MatrixXd M(A.rows(), 0);
  for (Eigen::Index k = 0; k < A.cols(); ++k) {
    const double norm = A.col(k).norm();
    if (!(norm > 0.0)) continue;
    Eigen::MatrixXd T(A.rows(), M.cols() + 1);
    T << M, A.col(k) / norm;
    if (T.cols() > T.rows()) continue;
    const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(T).singularValues();
    if (sv(sv.size() - 1) < 1e-6 * sv(0)) continue;
    M = T;
    keep.push_back(static_cast<std::size_t>(k));
  }
  return keep;
}

// A triad's base terms (bias, scale, misalignment) must all be determined, or its other terms
// would absorb the missing ones: else only what needs none of them stays (the gyros' bias, its
// drift and the g-sensitivity; nothing of the accelerometers').
void drop_incomplete(const std::vector<Param>& params, std::vector<std::size_t>& keep) {
  for (const char* prefix : {"gyro.", "accel."}) {
    const std::string tr = prefix;
    int base = 0;
    for (std::size_t k : keep) {
      const std::string& n = params[k].name;
      base += n.rfind(tr + "bias.", 0) == 0 || n.rfind(tr + "scale.", 0) == 0 ||
              n.rfind(tr + "misalignment.", 0) == 0;
    }
    if (base == 12) continue;
    keep.erase(std::remove_if(keep.begin(), keep.end(),
                              [&](std::size_t k) {
                                const std::string& n = params[k].name;
                                return n.rfind(tr, 0) == 0 &&
                                       !(tr == "gyro." && (n.rfind("gyro.bias.", 0) == 0 ||
                                                           n.rfind("gyro.bias_drift.", 0) == 0 ||
                                                           n.rfind("gyro.g_sens", 0) == 0));
                              }),
               keep.end());
  }
}

}  // namespace

std::vector<RateSegment> rate_segments(const Plan& plan, const Site& site) {
  (void)site;
  std::vector<RateSegment> out;
  if (plan.type == Plan::Type::Orientations) {
    for (const auto& o : plan.orientations)
      out.push_back(static_segment(o.label, C_b_n_from_euler(plan.convention, o.angles), o.dwell));
  } else {
    const Table table(plan.table);
    Eigen::Matrix3d known = C_b_n_from_euler(plan.convention, plan.start);
    // No start rest ([start] dwell = 0): the log begins in the first rate-table segment.
    if (plan.start_dwell > 0.0) out.push_back(static_segment("start", known, plan.start_dwell));
    for (std::size_t i = 0; i < plan.steps.size(); ++i)
      walk_step(plan, table, plan.steps[i], i, known, out);
  }
  if (out.empty()) throw RateTableError(plan.path + ": no static dwell or rate-table segment");
  for (std::size_t i = 0; i < out.size(); ++i) out[i].number = i + 1;
  return out;
}

std::vector<RateReading> read_rate_readings(
    const LogFormat& log, const std::function<void(const BadSampleError&)>& on_skip) {
  LogReader reader(log);
  if (on_skip) reader.skip_bad_samples(on_skip);
  std::vector<RateReading> out;
  ImuSample s;
  while (reader.next(s)) {
    if (!(s.dt > 0.0)) throw LogError(log.file, reader.line(), "a reading without an interval");
    out.push_back({s.dtheta_b / s.dt, s.dv_b / s.dt});
  }
  if (out.empty()) throw LogError(log.file, reader.line(), "no readings");
  return out;
}

void floor_by_pooled(std::vector<SegmentMean>& means) {
  Eigen::Vector3d sum_w = Eigen::Vector3d::Zero(), sum_f = Eigen::Vector3d::Zero();
  double count = 0.0;
  for (const auto& m : means) {
    const auto n = static_cast<double>(m.count);
    sum_w += n * m.tau_omega;
    sum_f += n * m.tau_f;
    count += n;
  }
  if (!(count > 0.0)) return;
  for (auto& m : means) {
    m.tau_omega = m.tau_omega.cwiseMax(sum_w / count);
    m.tau_f = m.tau_f.cwiseMax(sum_f / count);
  }
}

std::string segment_name(const RateSegment& s, std::size_t index) {
  return "segment " + std::to_string(s.number > 0 ? s.number : index + 1) + " (" + s.label + ")";
}

std::string largest_residual(const RateTableResult& r, const std::vector<RateSegment>& segments,
                             const std::string& triad) {
  double worst = 0.0;
  std::string named;
  const int from = triad == "accel" ? 3 : 0, to = triad == "gyro" ? 3 : 6;
  for (std::size_t k = 0; k < r.residual_sigma.size() && k < segments.size(); ++k)
    for (int i = from; i < to; ++i) {
      const double z = r.residual_sigma[k](i);
      if (!(std::abs(z) > worst)) continue;
      worst = std::abs(z);
      char text[64];
      std::snprintf(text, sizeof text, "%s %s %+.1f sigma", i < 3 ? "gyro" : "accelerometer",
                    kAxis[i % 3], z);
      named = segment_name(segments[k], k) + ": " + text;
    }
  return named;
}

std::vector<SegmentMean> find_segments(const std::vector<RateReading>& readings,
                                       const std::vector<RateSegment>& segments,
                                       const RateTableOptions& o) {
  const std::size_t w = 2 * static_cast<std::size_t>(o.smoothing * o.nominal_rate_hz / 2) + 1;
  const auto smooth = smoothed_rates(readings, w);
  std::vector<SegmentMean> out;
  std::size_t p = 0, start = 0;
  bool open = false;
  for (std::size_t k = 0; k <= readings.size() && p < segments.size(); ++k) {
    const bool m = k < readings.size() && matches(smooth[k], segments[p], o);
    if (m && !open) {
      open = true;
      start = k;
    }
    if (m || !open) continue;
    open = false;
    const double want = segments[p].duration * o.nominal_rate_hz * o.min_fraction;
    if (static_cast<double>(k - start) < std::max(want, 3.0 * static_cast<double>(w))) continue;
    const double step =
        segments[p].kind == RateSegment::Kind::Rate ? segments[p].rate / o.nominal_rate_hz : 0.0;
    out.push_back(mean_of(readings, start, k, w, step));
    ++p;
    if (k < readings.size()) --k;  // this reading may begin the next segment
  }
  if (p < segments.size())
    throw RateTableError(
        "segment " + std::to_string(p + 1) + " (" + segments[p].label +
        ") not found in the log after reading " +
        std::to_string(out.empty() ? 0 : out.back().last) + ": no run of readings at its " +
        (segments[p].kind == RateSegment::Kind::Static
             ? std::string("rest")
             : "rate of " + std::to_string(segments[p].rate / units::deg) + " deg/s") +
        " long enough (the plan's order, rates and durations, or the log's gyro unit or axes)");
  floor_by_pooled(out);
  return out;
}

RateTableResult rate_table_calibrate(const std::vector<RateSegment>& segments,
                                     const std::vector<SegmentMean>& means, const Site& site,
                                     double gravity, const RateTableOptions& options) {
  if (means.size() != segments.size())
    throw RateTableError("rate table: the segments and their means differ in number");
  const Earth& earth = Earth::wgs84();
  Eigen::Vector3d g_n = earth.gravity_n(site.lat_rad, site.h_m);
  if (gravity > 0.0) g_n = g_n.normalized() * gravity;
  RateTableResult res;
  res.means = means;
  // The rank test on the commanded inputs alone: gravity straight down, no Earth rate (their
  // small parts, a few deg/h or a normal gravity's tilt at height, determine nothing).
  std::vector<MeanRow> rows, commanded;
  const Eigen::Vector3d down(0.0, 0.0, g_n.norm());
  for (std::size_t i = 0; i < segments.size(); ++i) {
    rows.push_back(row_of(segments[i], means[i], earth.omega_ie_n(site.lat_rad), -g_n, options));
    commanded.push_back(row_of(segments[i], means[i], Eigen::Vector3d::Zero(), -down, options));
    ++(segments[i].kind == RateSegment::Kind::Static ? res.static_segments : res.rate_segments);
  }
  const auto params = candidate_params(res.rate_segments > 0, options);
  auto keep = determined(whitened(commanded, params).A);
  drop_incomplete(params, keep);
  // A triad without coefficients has no rows (the accelerometers; the gyros keep their biases).
  const bool accel = std::any_of(keep.begin(), keep.end(), [&](std::size_t k) {
    return params[k].name.rfind("accel.", 0) == 0;
  });
  const System sys = whitened(rows, params, accel);
  if (keep.empty()) throw RateTableError("rate table: the segments determine no coefficient");
  Eigen::MatrixXd A(sys.A.rows(), static_cast<Eigen::Index>(keep.size()));
  for (std::size_t k = 0; k < keep.size(); ++k)
    A.col(static_cast<Eigen::Index>(k)) = sys.A.col(static_cast<Eigen::Index>(keep[k]));
  const Eigen::MatrixXd N = A.transpose() * A;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(N);
  const Eigen::VectorXd x = ldlt.solve(A.transpose() * sys.b);
  const Eigen::MatrixXd P = ldlt.solve(Eigen::MatrixXd::Identity(N.rows(), N.cols()));
  res.chi2 = (A * x - sys.b).squaredNorm();
  res.dof = static_cast<int>(A.rows() - A.cols());
  res.triad_fits = triad_fits(rows, A * x - sys.b, params, keep, accel);
  res.residual_sigma = per_segment(rows, sys.b - A * x, accel);  // data less the fit
  res.covariance = P;
  std::vector<bool> used(params.size(), false);
  for (std::size_t k = 0; k < keep.size(); ++k) {
    const auto e = static_cast<Eigen::Index>(k);
    used[keep[k]] = true;
    res.coefficients.push_back({params[keep[k]].name, x(e), std::sqrt(std::max(0.0, P(e, e))),
                                params[keep[k]].in_catalog});
  }
  for (std::size_t k = 0; k < params.size(); ++k)
    if (!used[k]) res.undetermined.push_back(params[k].name);
  for (const auto& c : res.coefficients)  // no sensor is off by a fifth: the plan is not the data
    if (c.name.find(".scale.") != std::string::npos && std::abs(c.value) > 0.2)
      throw RateTableError("rate table: " + c.name + " comes out at " +
                           std::to_string(c.value * 100.0) +
                           " %: the plan's attitudes, axes or rates are not what the data show "
                           "(a face or a turn's direction swapped, a wrong axis, unit or order)");
  return res;
}

}  // namespace sinscal
