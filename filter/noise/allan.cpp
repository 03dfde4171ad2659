#include "filter/noise/allan.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/special_functions/digamma.hpp>
#include <boost/math/special_functions/trigamma.hpp>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "models/units.hpp"

namespace sinscal {
namespace {

constexpr std::array<AllanTerm, 5> kAllTerms = {AllanTerm::Quantization, AllanTerm::White,
                                                AllanTerm::BiasInstability, AllanTerm::RandomWalk,
                                                AllanTerm::RateRamp};

constexpr int kLogPasses = 6;  // Gauss-Newton passes of the log fit (converged in 3-4)
constexpr int kTerms = 5;      // quantization, white, bias instability, random walk, rate ramp
const double kFlicker = 2.0 * std::log(2.0) / units::pi;  // AVAR of the flicker floor per B^2

double basis(int term, double tau) {
  switch (term) {
    case 0:
      return 3.0 / (tau * tau);
    case 1:
      return 1.0 / tau;
    case 2:
      return kFlicker;
    case 3:
      return tau / 3.0;
    default:
      return tau * tau / 2.0;
  }
}

/// Equivalent degrees of freedom of the overlapping Allan variance, N phase points, cluster m
/// (NIST SP 1065, simple approximations by noise type).
double edf(AllanTerm type, double N, double m) {
  double e = 1.0;
  switch (type) {
    case AllanTerm::Quantization:  // white phase
      e = (N + 1.0) * (N - 2.0 * m) / (2.0 * (N - m));
      break;
    case AllanTerm::White:  // white frequency
      e = (3.0 * (N - 1.0) / (2.0 * m) - 2.0 * (N - 2.0) / N) * 4.0 * m * m / (4.0 * m * m + 5.0);
      break;
    case AllanTerm::BiasInstability:  // flicker frequency
      e = m == 1.0 ? 2.0 * (N - 2.0) * (N - 2.0) / (2.3 * N - 4.9)
                   : 5.0 * N * N / (4.0 * m * (N + 3.0 * m));
      break;
    case AllanTerm::RandomWalk:  // random-walk frequency
    case AllanTerm::RateRamp:    // no tabulated edf: the random walk's (the steepest noise)
      e = (N - 2.0) / m * ((N - 1.0) * (N - 1.0) - 3.0 * m * (N - 1.0) + 4.0 * m * m) /
          ((N - 3.0) * (N - 3.0));
      break;
  }
  return std::max(1.0, e);
}

// Correlation of the log Allan variances of neighbouring octaves (overlapping estimator, by the
// noise type that dominates there), measured on 300 simulated records of 2^16 samples each:
// 0.53 (white), 0.69 (flicker), 0.88 (random walk); quantization taken as white, rate ramp as
// random walk. Two lags apart they fall about as the square (0.2, 0.32, 0.65).
double octave_correlation(AllanTerm type) {
  switch (type) {
    case AllanTerm::Quantization:
    case AllanTerm::White:
      return 0.53;
    case AllanTerm::BiasInstability:
      return 0.69;
    default:
      return 0.88;
  }
}

// The inverse Cholesky factor of the estimates' correlation: a Markov chain over the cluster
// times (ascending), corr(i, i+1) = sqrt(rho_i rho_i+1)^(log2(m_i+1 / m_i)), corr(i, j) the
// product along the chain (always a valid correlation). Whitens the weighted least squares.
Eigen::MatrixXd whitening(const std::vector<AllanPoint>& pts) {
  const auto n = static_cast<Eigen::Index>(pts.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Identity(n, n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = i + 1; j < n; ++j) {
      const AllanPoint& a = pts[static_cast<std::size_t>(j - 1)];
      const AllanPoint& b = pts[static_cast<std::size_t>(j)];
      const double rho = std::sqrt(octave_correlation(a.dominant) * octave_correlation(b.dominant));
      const double step = std::abs(std::log2(static_cast<double>(b.m) / static_cast<double>(a.m)));
      C(i, j) = C(j, i) = C(i, j - 1) * std::pow(rho, step);
    }
  const Eigen::LLT<Eigen::MatrixXd> llt(C);
  if (llt.info() != Eigen::Success) return Eigen::MatrixXd::Identity(n, n);
  return llt.matrixL().solve(Eigen::MatrixXd::Identity(n, n));
}

void set_bounds(AllanPoint& p, double avar, double confidence) {
  const boost::math::chi_squared chi2(p.edf);
  const double lo = boost::math::quantile(chi2, 0.5 * (1.0 - confidence));
  const double hi = boost::math::quantile(chi2, 0.5 * (1.0 + confidence));
  p.adev_low = std::sqrt(avar * p.edf / hi);
  p.adev_high = std::sqrt(avar * p.edf / lo);
}

}  // namespace

double AllanFit::term_variance(AllanTerm term, double tau) const {
  switch (term) {
    case AllanTerm::Quantization:
      return quantization * quantization * basis(0, tau);
    case AllanTerm::White:
      return white * white * basis(1, tau);
    case AllanTerm::BiasInstability:
      return bias_instability * bias_instability * basis(2, tau);
    case AllanTerm::RandomWalk:
      return random_walk * random_walk * basis(3, tau);
    case AllanTerm::RateRamp:
      return rate_ramp * rate_ramp * basis(4, tau);
  }
  return 0.0;
}

double AllanFit::adev(double tau) const {
  double v = 0.0;
  for (AllanTerm t : kAllTerms) v += term_variance(t, tau);
  return std::sqrt(v);
}

namespace {

// Each estimate is AVAR chi2(edf) / edf. Its logarithm has the mean log AVAR + psi(edf / 2) -
// log(edf / 2) and the variance psi'(edf / 2) (2 / edf and -1 / edf for many degrees of freedom,
// where the fit is the Gaussian one of the variances; at edf 2, the last octave of a random
// walk, 1.64 instead of 1 and a mean 0.58 below log AVAR: the chi-square's skew). Pass 0 fits
// the variances with weights from the data (a start); the passes after it fit the logarithms
// by Gauss-Newton, each linearised at the previous model m:
//   log(avar_i) - mean_i - log(m_i) ~ (A x - m)_i / m_i,  weight 1 / (m_i^2 psi'(edf_i / 2)).
void pass_weights(const std::vector<AllanPoint>& pts, const Eigen::VectorXd& avar,
                  const Eigen::VectorXd& model, bool gaussian, Eigen::VectorXd& sw,
                  Eigen::VectorXd& target) {
  for (Eigen::Index i = 0; i < avar.size(); ++i) {
    const double edf = pts[static_cast<std::size_t>(i)].edf;
    // A point without variance (an exact sequence) carries no weight.
    const double v = model(i) > 0.0 ? model(i) : avar(i);
    if (gaussian) {  // the Gaussian fit of the variances
      sw(i) = v > 0.0 ? std::sqrt(edf / 2.0) / v : 0.0;
      target(i) = avar(i);
    } else if (!(v > 0.0) || !(avar(i) > 0.0)) {  // no logarithm
      sw(i) = 0.0;
      target(i) = 0.0;
    } else {
      const double log_mean = boost::math::digamma(edf / 2.0) - std::log(edf / 2.0);
      sw(i) = 1.0 / (v * std::sqrt(boost::math::trigamma(edf / 2.0)));
      target(i) = v * (1.0 + std::log(avar(i) / v) - log_mean);
    }
  }
}

}  // namespace

AllanFit fit_allan(const std::vector<AllanPoint>& pts, bool fit_quantization, bool fit_rate_ramp,
                   bool log_fit) {
  const auto n = static_cast<Eigen::Index>(pts.size());
  if (n < 2) throw AllanError("Allan fit: fewer than two cluster times");
  Eigen::VectorXd avar(n);
  for (Eigen::Index i = 0; i < n; ++i)
    avar(i) = pts[static_cast<std::size_t>(i)].adev * pts[static_cast<std::size_t>(i)].adev;
  if (!(avar.maxCoeff() > 0.0)) throw AllanError("Allan fit: the record has no variance");
  AllanFit best;
  const Eigen::MatrixXd W = whitening(pts);
  Eigen::VectorXd model = avar;  // pass 0 from the data, the later passes from the model
  const int passes = log_fit ? kLogPasses + 1 : 2;
  for (int pass = 0; pass < passes; ++pass) {
    Eigen::VectorXd sw(n);      // sqrt of the weights
    Eigen::VectorXd target(n);  // in variance units: the data (pass 0) or the linearised log
    pass_weights(pts, avar, model, pass == 0 || !log_fit, sw, target);
    double best_cost = std::numeric_limits<double>::infinity();
    AllanFit pass_best;
    for (int subset = 1; subset < (1 << kTerms); ++subset) {
      if (!fit_quantization && (subset & 1)) continue;
      if (!fit_rate_ramp && (subset & 16)) continue;
      std::vector<int> terms;
      for (int t = 0; t < kTerms; ++t)
        if (subset & (1 << t)) terms.push_back(t);
      const auto k = static_cast<Eigen::Index>(terms.size());
      if (k > n) continue;
      Eigen::MatrixXd A(n, k);
      for (Eigen::Index i = 0; i < n; ++i)
        for (Eigen::Index j = 0; j < k; ++j)
          A(i, j) = sw(i) *
                    basis(terms[static_cast<std::size_t>(j)], pts[static_cast<std::size_t>(i)].tau);
      A = W * A;
      const Eigen::VectorXd scale = A.colwise().norm().transpose();
      const Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
      const Eigen::VectorXd b = W * sw.cwiseProduct(target);
      const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(As);
      if (qr.rank() < k) continue;
      const Eigen::VectorXd x = qr.solve(b).cwiseQuotient(scale);
      if ((x.array() <= 0.0).any()) continue;
      const double cost = (A * x - b).squaredNorm();
      if (cost >= best_cost) continue;
      best_cost = cost;
      // Covariance of the variances x: (A^T A)^-1 in the scaled columns.
      const Eigen::MatrixXd Rinv =
          qr.matrixR().topLeftCorner(k, k).triangularView<Eigen::Upper>().solve(
              Eigen::MatrixXd::Identity(k, k));
      const Eigen::MatrixXd cov_s = Rinv * Rinv.transpose();  // permuted order
      Eigen::VectorXd var_x(k);
      const auto& perm = qr.colsPermutation().indices();
      for (Eigen::Index j = 0; j < k; ++j) var_x(perm(j)) = cov_s(j, j);
      var_x = var_x.cwiseQuotient(scale.cwiseAbs2());
      AllanFit f;
      double* value[kTerms] = {&f.quantization, &f.white, &f.bias_instability, &f.random_walk,
                               &f.rate_ramp};
      double* sigma[kTerms] = {&f.quantization_sigma, &f.white_sigma, &f.bias_instability_sigma,
                               &f.random_walk_sigma, &f.rate_ramp_sigma};
      for (Eigen::Index j = 0; j < k; ++j) {
        const int t = terms[static_cast<std::size_t>(j)];
        *value[t] = std::sqrt(x(j));
        *sigma[t] = std::sqrt(var_x(j)) / (2.0 * *value[t]);  // of sqrt(x)
      }
      f.chi2 = cost;
      pass_best = f;
    }
    if (!std::isfinite(best_cost)) throw AllanError("Allan fit: no non-negative solution");
    best = pass_best;
    best.valid = true;
    for (Eigen::Index i = 0; i < n; ++i)
      model(i) = best.adev(pts[static_cast<std::size_t>(i)].tau) *
                 best.adev(pts[static_cast<std::size_t>(i)].tau);
  }
  // The floor of the fitted curve (the raw points' minimum would be biased low by the scatter
  // of the few-degree-of-freedom estimates at long cluster times).
  const AllanPoint* at = &pts.front();
  for (const auto& p : pts)
    if (best.adev(p.tau) < best.adev(at->tau)) at = &p;
  best.floor_bias_instability = best.adev(at->tau) / 0.664;
  best.floor_bias_instability_sigma = best.floor_bias_instability / std::sqrt(2.0 * at->edf);
  return best;
}

namespace {

// Cluster sizes m (in samples) up to max_fraction of the record: octaves, or log-spaced.
std::vector<std::size_t> cluster_sizes(std::size_t n, const AllanOptions& o) {
  const auto m_max = static_cast<std::size_t>(o.max_fraction * static_cast<double>(n));
  std::vector<std::size_t> ms;
  if (o.points_per_decade == 0) {
    for (std::size_t m = 1; m <= m_max; m *= 2) ms.push_back(m);
  } else {
    for (int k = 0;; ++k) {
      const auto m = static_cast<std::size_t>(
          std::llround(std::pow(10.0, static_cast<double>(k) / o.points_per_decade)));
      if (m > m_max) break;
      if (ms.empty() || m != ms.back()) ms.push_back(m);
    }
  }
  if (ms.size() < 2) throw AllanError("Allan deviation: the record is too short");
  return ms;
}

// The term of `fit` with the largest Allan variance at tau.
AllanTerm dominant_term(const AllanFit& fit, double tau) {
  double top = -1.0;
  AllanTerm dominant = AllanTerm::White;
  for (AllanTerm t : kAllTerms) {
    const double v = fit.term_variance(t, tau);
    if (v > top) {
      top = v;
      dominant = t;
    }
  }
  return dominant;
}

// Fit with white-noise degrees of freedom, then with those of each point's dominant term. A
// record the model does not describe (a drift, an exact sequence) keeps white-noise edf.
AllanFit fit_with_dominant_edf(std::vector<AllanPoint>& pts, double N, const AllanOptions& o) {
  try {
    AllanFit fit = fit_allan(pts, o.fit_quantization, o.fit_rate_ramp, o.log_fit);
    for (int pass = 0; pass < 2; ++pass) {
      for (auto& p : pts) {
        p.dominant = dominant_term(fit, p.tau);
        p.edf = edf(p.dominant, N, static_cast<double>(p.m));
      }
      fit = fit_allan(pts, o.fit_quantization, o.fit_rate_ramp, o.log_fit);
    }
    return fit;
  } catch (const AllanError&) {
    for (auto& p : pts) {
      p.dominant = AllanTerm::White;
      p.edf = edf(p.dominant, N, static_cast<double>(p.m));
    }
    return AllanFit{};
  }
}

void check_options(const AllanOptions& o) {
  if (!(o.max_fraction > 0.0) || o.max_fraction > 0.5 || !(o.confidence > 0.0) ||
      !(o.confidence < 1.0) || o.points_per_decade < 0)
    throw AllanError("Allan deviation: options out of range");
}

void check_length(std::size_t n) {
  if (n < kAllanMinSamples)
    throw AllanError("Allan deviation: " + std::to_string(n) + " samples are too few (" +
                     std::to_string(kAllanMinSamples) + " at least)");
}

// The points of the Allan variances `est` (N phase points), fitted, with their bounds. The
// degrees of freedom are those of the fully overlapping estimator (a stride of at most m / R
// loses a fraction of order 1 / R of them: docs/methods/allan.md).
std::vector<AllanPoint> points_of(const std::vector<AllanAccumulator::Estimate>& est, double tau0,
                                  double N, const AllanOptions& o, AllanFit* fit_out) {
  if (est.size() < 2) throw AllanError("Allan deviation: the record is too short");
  std::vector<AllanPoint> pts;
  for (const auto& e : est) {
    AllanPoint p;
    p.m = e.m;
    p.stride = e.stride;
    p.tau = static_cast<double>(e.m) * tau0;
    p.adev = std::sqrt(e.avar);
    p.edf = edf(AllanTerm::White, N, static_cast<double>(e.m));
    pts.push_back(p);
  }
  const AllanFit fit = fit_with_dominant_edf(pts, N, o);
  for (std::size_t i = 0; i < pts.size(); ++i) set_bounds(pts[i], est[i].avar, o.confidence);
  if (fit_out) *fit_out = fit;
  return pts;
}

// Cluster sizes of an accumulator: octaves or log-spaced up to 2^40 samples; from 2R on, each
// rounded to a multiple of its stride 2^floor(log2(m / R)).
std::vector<std::pair<std::size_t, std::size_t>> stream_sizes(int points_per_decade) {
  constexpr std::size_t R = AllanAccumulator::kExactClusters / 2;
  constexpr double top = 1099511627776.0;                // 2^40
  std::vector<std::pair<std::size_t, std::size_t>> out;  // (m, stride)
  for (int k = 0;; ++k) {
    const double mf = points_per_decade == 0
                          ? std::ldexp(1.0, k)
                          : std::round(std::pow(10.0, static_cast<double>(k) / points_per_decade));
    if (mf > top) break;
    auto m = static_cast<std::size_t>(mf);
    std::size_t stride = 1;
    while (m >= 2 * R * stride) stride *= 2;
    m = static_cast<std::size_t>(
            std::llround(static_cast<double>(m) / static_cast<double>(stride))) *
        stride;
    if (out.empty() || m != out.back().first) out.emplace_back(m, stride);
  }
  return out;
}

}  // namespace

std::vector<AllanPoint> allan_deviation(const std::vector<double>& rates, double tau0,
                                        const AllanOptions& o, AllanFit* fit_out) {
  if (!(tau0 > 0.0)) throw AllanError("Allan deviation: the sample interval must be positive");
  check_length(rates.size());
  check_options(o);
  const std::size_t n = rates.size();
  const std::size_t N = n + 1;  // points of the integrated signal
  double mean = 0.0;
  for (double y : rates) mean += y;
  mean /= static_cast<double>(n);
  // Integrated signal (the mean removed: the Allan variance does not see it, and the sums stay
  // small against their second differences).
  std::vector<double> theta(N);
  theta[0] = 0.0;
  for (std::size_t k = 0; k < n; ++k) theta[k + 1] = theta[k] + (rates[k] - mean) * tau0;
  std::vector<AllanAccumulator::Estimate> est;
  for (std::size_t m : cluster_sizes(n, o)) {
    double sum = 0.0;
    for (std::size_t k = 0; k + 2 * m < N; ++k) {
      const double d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
      sum += d * d;
    }
    const double tau = static_cast<double>(m) * tau0;
    est.push_back({m, 1, N - 2 * m, sum / (2.0 * tau * tau * static_cast<double>(N - 2 * m))});
  }
  return points_of(est, tau0, static_cast<double>(N), o, fit_out);
}

AllanAccumulator::AllanAccumulator(int points_per_decade) {
  for (const auto& [m, stride] : stream_sizes(points_per_decade)) {
    if (groups_.empty() || groups_.back().stride != stride) {
      groups_.emplace_back();
      groups_.back().stride = stride;
      groups_.back().ring.push_back(0.0);  // theta_0
      groups_.back().pushed = 1;
    }
    Level l;
    l.m = m;
    l.r = m / stride;
    groups_.back().levels.push_back(l);
  }
  for (auto& g : groups_) {
    std::size_t cap = 1;
    while (cap < 2 * g.levels.back().r + 1) cap *= 2;
    g.mask = cap - 1;
  }
}

void AllanAccumulator::push(Group& g) {
  const std::size_t q = g.pushed++;  // theta_{q stride}
  if (g.ring.size() <= g.mask)
    g.ring.push_back(theta_);
  else
    g.ring[q & g.mask] = theta_;
  const double* ring = g.ring.data();
  for (Level& l : g.levels) {
    if (q < 2 * l.r) break;
    const double d = theta_ - 2.0 * ring[(q - l.r) & g.mask] + ring[(q - 2 * l.r) & g.mask];
    l.sum += d * d;
    ++l.terms;
  }
}

void AllanAccumulator::add(double rate) {
  if (n_ == 0) offset_ = rate;
  theta_ += rate - offset_;
  ++n_;
  for (Group& g : groups_) {
    if ((n_ & (g.stride - 1)) != 0) break;  // strides ascend as powers of two
    push(g);
  }
}

std::vector<AllanAccumulator::Estimate> AllanAccumulator::estimates(double max_fraction) const {
  const auto m_max = static_cast<std::size_t>(max_fraction * static_cast<double>(n_));
  std::vector<Estimate> out;
  for (const Group& g : groups_)
    for (const Level& l : g.levels) {
      if (l.m > m_max || l.terms == 0) continue;
      const double m = static_cast<double>(l.m);
      out.push_back({l.m, g.stride, l.terms, l.sum / (2.0 * m * m * static_cast<double>(l.terms))});
    }
  return out;
}

std::size_t AllanAccumulator::memory_bytes() const {
  std::size_t b = sizeof(*this);
  for (const Group& g : groups_)
    b += sizeof(Group) + g.ring.capacity() * sizeof(double) + g.levels.capacity() * sizeof(Level);
  return b;
}

std::vector<AllanPoint> allan_deviation(const AllanAccumulator& acc, double tau0,
                                        const AllanOptions& o, AllanFit* fit_out) {
  if (!(tau0 > 0.0)) throw AllanError("Allan deviation: the sample interval must be positive");
  check_length(acc.samples());
  check_options(o);
  return points_of(acc.estimates(o.max_fraction), tau0, static_cast<double>(acc.samples() + 1), o,
                   fit_out);
}

AllanStream::AllanStream(const AllanOptions& o) : options_(o) {
  check_options(o);
  for (auto& c : channels_) c = AllanAccumulator(o.points_per_decade);
}

void AllanStream::add_rates(const Eigen::Vector3d& omega_ib_b, const Eigen::Vector3d& f_b) {
  for (int i = 0; i < 3; ++i) {
    channels_[static_cast<std::size_t>(i)].add(omega_ib_b(i));
    channels_[static_cast<std::size_t>(i) + 3].add(f_b(i));
  }
}

void AllanStream::add(const ImuSample& s) {
  if (samples() == 0) {
    tau0_ = s.dt;
    if (!(tau0_ > 0.0)) throw AllanError("Allan analysis: sample interval must be positive");
  }
  if (std::abs(s.dt - tau0_) > 0.01 * tau0_)
    throw AllanError("Allan analysis: the sample interval varies (sample " +
                     std::to_string(samples() + 1) + ": " + std::to_string(s.dt) + " s against " +
                     std::to_string(tau0_) + " s)");
  add_rates(s.dtheta_b / s.dt, s.dv_b / s.dt);
}

std::size_t AllanStream::memory_bytes() const {
  std::size_t b = sizeof(*this);
  for (const auto& c : channels_) b += c.memory_bytes() - sizeof(c);
  return b;
}

AllanAnalysis AllanStream::analysis(double tau0) const {
  if (samples() == 0) throw AllanError("Allan analysis: no samples");
  AllanAnalysis out;
  out.samples = samples();
  out.tau0 = tau0;
  for (std::size_t i = 0; i < 3; ++i) {
    out.gyro[i] = allan_deviation(channels_[i], tau0, options_, &out.gyro_fit[i]);
    out.accel[i] = allan_deviation(channels_[i + 3], tau0, options_, &out.accel_fit[i]);
  }
  for (const auto& p : out.gyro[0]) out.max_stride = std::max(out.max_stride, p.stride);
  return out;
}

AllanAnalysis analyse_allan(const std::vector<ImuSample>& samples, const AllanOptions& o) {
  if (samples.empty()) throw AllanError("Allan analysis: no samples");
  AllanStream stream(o);
  for (const ImuSample& s : samples) stream.add(s);
  return stream.analysis(stream.first_interval());
}

namespace {

// One key of the fragment: the mean of the axes, each axis in a comment; with `sigma`, the
// 1-sigma of each axis's fit in a comment line below. Skipped when `optional` and not fitted.
struct FragmentWriter {
  std::ostringstream& s;
  const std::array<AllanFit, 3>& fits;
  void line(const std::string& key, double AllanFit::*value, double AllanFit::*sigma,
            double si_per_unit, const char* unit, bool optional = false) const {
    if (optional && fits[0].*value == 0.0 && fits[1].*value == 0.0 && fits[2].*value == 0.0) return;
    double mean = 0.0;
    for (const auto& f : fits) mean += f.*value / si_per_unit / 3.0;
    s << key << " = " << mean << " " << unit << "  # x " << fits[0].*value / si_per_unit << ", y "
      << fits[1].*value / si_per_unit << ", z " << fits[2].*value / si_per_unit << "\n";
    if (sigma == nullptr) return;
    const std::string name = key[0] == '#' ? key.substr(2) : key;
    s << "#   1-sigma of " << name << ": x " << fits[0].*sigma / si_per_unit << ", y "
      << fits[1].*sigma / si_per_unit << ", z " << fits[2].*sigma / si_per_unit << " " << unit
      << "\n";
  }
};

}  // namespace

std::string AllanAnalysis::profile_fragment() const {
  std::ostringstream s;
  s << std::setprecision(4);
  s << "# Allan analysis (IEEE Std 952): mean of the three axes, each axis in the comment;\n"
    << "# the 1-sigma of each fitted term from the estimates' degrees of freedom and the\n"
    << "# correlation of neighbouring octaves.\n"
    << "# bias_instability: the curve's minimum / 0.664 (IEEE's flicker floor: ADEV =\n"
    << "# sqrt(2 ln 2 / pi) B = 0.664 B). As the profile's Gauss-Markov sigma it is an\n"
    << "# approximation: a Gauss-Markov bias of sigma q and correlation time T peaks at an\n"
    << "# Allan deviation of 0.617 q at tau = 1.89 T.\n"
    << "# sample interval " << tau0 << " s, record about " << static_cast<double>(samples) * tau0
    << " s\n[gyro]\n";
  const double sqrt12 = std::sqrt(12.0);
  const FragmentWriter g{s, gyro_fit}, a{s, accel_fit};
  using F = AllanFit;
  g.line("arw", &F::white, &F::white_sigma, units::deg_per_sqrt_h, "deg/sqrt(h)");
  g.line("bias_instability", &F::floor_bias_instability, nullptr, units::deg_per_h, "deg/h");
  g.line("# fitted flicker term", &F::bias_instability, &F::bias_instability_sigma,
         units::deg_per_h, "deg/h");
  g.line("rate_random_walk", &F::random_walk, &F::random_walk_sigma, units::deg_per_h_per_sqrt_h,
         "deg/h/sqrt(h)");
  g.line("# rate_ramp", &F::rate_ramp, &F::rate_ramp_sigma, units::deg_per_h / units::hour,
         "deg/h/h", true);
  g.line("quantum", &F::quantization, &F::quantization_sigma, units::arcsec / sqrt12, "arcsec",
         true);
  s << "\n[accel]\n";
  a.line("vrw", &F::white, &F::white_sigma, units::ug_per_sqrt_hz, "ug/sqrt(Hz)");
  a.line("bias_instability", &F::floor_bias_instability, nullptr, units::ug, "ug");
  a.line("# fitted flicker term", &F::bias_instability, &F::bias_instability_sigma, units::ug,
         "ug");
  a.line("random_walk", &F::random_walk, &F::random_walk_sigma, units::ug_per_sqrt_h, "ug/sqrt(h)");
  a.line("# rate_ramp", &F::rate_ramp, &F::rate_ramp_sigma, units::ug / units::hour, "ug/h", true);
  a.line("quantum", &F::quantization, &F::quantization_sigma, 1.0 / sqrt12, "m/s", true);
  return s.str();
}

}  // namespace sinscal
