#include "filter/noise/allan.hpp"

#include <Eigen/QR>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

#include "models/units.hpp"

namespace sinscal {
namespace {

constexpr int kTerms = 4;  // quantization, white, bias instability, random walk
const double kFlicker = 2.0 * std::log(2.0) / units::pi;  // AVAR of the flicker floor per B^2

double basis(int term, double tau) {
  switch (term) {
    case 0:
      return 3.0 / (tau * tau);
    case 1:
      return 1.0 / tau;
    case 2:
      return kFlicker;
    default:
      return tau / 3.0;
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
      e = (N - 2.0) / m * ((N - 1.0) * (N - 1.0) - 3.0 * m * (N - 1.0) + 4.0 * m * m) /
          ((N - 3.0) * (N - 3.0));
      break;
  }
  return std::max(1.0, e);
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
  }
  return 0.0;
}

double AllanFit::adev(double tau) const {
  double v = 0.0;
  for (AllanTerm t : {AllanTerm::Quantization, AllanTerm::White, AllanTerm::BiasInstability,
                      AllanTerm::RandomWalk})
    v += term_variance(t, tau);
  return std::sqrt(v);
}

AllanFit fit_allan(const std::vector<AllanPoint>& pts, bool fit_quantization) {
  const auto n = static_cast<Eigen::Index>(pts.size());
  if (n < 2) throw AllanError("Allan fit: fewer than two cluster times");
  Eigen::VectorXd avar(n);
  for (Eigen::Index i = 0; i < n; ++i)
    avar(i) = pts[static_cast<std::size_t>(i)].adev * pts[static_cast<std::size_t>(i)].adev;
  if (!(avar.maxCoeff() > 0.0)) throw AllanError("Allan fit: the record has no variance");
  AllanFit best;
  Eigen::VectorXd model = avar;  // weights of pass 1 from the data, pass 2 from the model
  for (int pass = 0; pass < 2; ++pass) {
    Eigen::VectorXd sw(n);  // sqrt of the weights edf / (2 v^2)
    for (Eigen::Index i = 0; i < n; ++i) {
      // A point without variance (an exact sequence) carries no weight.
      const double v = model(i) > 0.0 ? model(i) : avar(i);
      sw(i) = v > 0.0 ? std::sqrt(pts[static_cast<std::size_t>(i)].edf / 2.0) / v : 0.0;
    }
    double best_cost = std::numeric_limits<double>::infinity();
    AllanFit pass_best;
    for (int subset = 1; subset < (1 << kTerms); ++subset) {
      if (!fit_quantization && (subset & 1)) continue;
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
      const Eigen::VectorXd scale = A.colwise().norm().transpose();
      const Eigen::MatrixXd As = A * scale.cwiseInverse().asDiagonal();
      const Eigen::VectorXd b = sw.cwiseProduct(avar);
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
      double* value[kTerms] = {&f.quantization, &f.white, &f.bias_instability, &f.random_walk};
      double* sigma[kTerms] = {&f.quantization_sigma, &f.white_sigma, &f.bias_instability_sigma,
                               &f.random_walk_sigma};
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
  double floor = std::numeric_limits<double>::infinity();
  for (const auto& p : pts) floor = std::min(floor, best.adev(p.tau));
  best.floor_bias_instability = floor / 0.664;
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
  for (AllanTerm t : {AllanTerm::Quantization, AllanTerm::White, AllanTerm::BiasInstability,
                      AllanTerm::RandomWalk}) {
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
AllanFit fit_with_dominant_edf(std::vector<AllanPoint>& pts, double N, bool fit_quantization) {
  try {
    AllanFit fit = fit_allan(pts, fit_quantization);
    for (int pass = 0; pass < 2; ++pass) {
      for (auto& p : pts) {
        p.dominant = dominant_term(fit, p.tau);
        p.edf = edf(p.dominant, N, static_cast<double>(p.m));
      }
      fit = fit_allan(pts, fit_quantization);
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

}  // namespace

std::vector<AllanPoint> allan_deviation(const std::vector<double>& rates, double tau0,
                                        const AllanOptions& o, AllanFit* fit_out) {
  if (!(tau0 > 0.0)) throw AllanError("Allan deviation: the sample interval must be positive");
  if (rates.size() < kAllanMinSamples)
    throw AllanError("Allan deviation: " + std::to_string(rates.size()) + " samples are too few (" +
                     std::to_string(kAllanMinSamples) + " at least)");
  if (!(o.max_fraction > 0.0) || o.max_fraction > 0.5 || !(o.confidence > 0.0) ||
      !(o.confidence < 1.0) || o.points_per_decade < 0)
    throw AllanError("Allan deviation: options out of range");
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

  std::vector<AllanPoint> pts;
  std::vector<double> avar;
  for (std::size_t m : cluster_sizes(n, o)) {
    double sum = 0.0;
    for (std::size_t k = 0; k + 2 * m < N; ++k) {
      const double d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
      sum += d * d;
    }
    AllanPoint p;
    p.m = m;
    p.tau = static_cast<double>(m) * tau0;
    const double v = sum / (2.0 * p.tau * p.tau * static_cast<double>(N - 2 * m));
    avar.push_back(v);
    p.adev = std::sqrt(v);
    p.dominant = AllanTerm::White;
    p.edf = edf(p.dominant, static_cast<double>(N), static_cast<double>(m));
    pts.push_back(p);
  }
  const AllanFit fit = fit_with_dominant_edf(pts, static_cast<double>(N), o.fit_quantization);
  for (std::size_t i = 0; i < pts.size(); ++i) set_bounds(pts[i], avar[i], o.confidence);
  if (fit_out) *fit_out = fit;
  return pts;
}

AllanAnalysis analyse_allan(const std::vector<ImuSample>& samples, const AllanOptions& o) {
  if (samples.empty()) throw AllanError("Allan analysis: no samples");
  AllanAnalysis out;
  out.samples = samples.size();
  out.tau0 = samples.front().dt;
  if (!(out.tau0 > 0.0)) throw AllanError("Allan analysis: sample interval must be positive");
  std::array<std::vector<double>, 6> ch;
  for (auto& c : ch) c.reserve(samples.size());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const ImuSample& s = samples[k];
    if (std::abs(s.dt - out.tau0) > 0.01 * out.tau0)
      throw AllanError("Allan analysis: the sample interval varies (sample " +
                       std::to_string(k + 1) + ": " + std::to_string(s.dt) + " s against " +
                       std::to_string(out.tau0) + " s)");
    for (int i = 0; i < 3; ++i) {
      ch[i].push_back(s.dtheta_b(i) / s.dt);
      ch[i + 3].push_back(s.dv_b(i) / s.dt);
    }
  }
  for (int i = 0; i < 3; ++i) {
    out.gyro[i] = allan_deviation(ch[i], out.tau0, o, &out.gyro_fit[i]);
    out.accel[i] = allan_deviation(ch[i + 3], out.tau0, o, &out.accel_fit[i]);
  }
  return out;
}

std::string AllanAnalysis::profile_fragment() const {
  std::ostringstream s;
  s << std::setprecision(4);
  auto line = [&](const char* key, const std::array<AllanFit, 3>& fits, double AllanFit::*member,
                  double si_per_unit, const char* unit) {
    if (std::string(key) == "quantum" && fits[0].*member == 0.0 && fits[1].*member == 0.0 &&
        fits[2].*member == 0.0)
      return;
    double mean = 0.0;
    for (const auto& f : fits) mean += f.*member / si_per_unit / 3.0;
    s << key << " = " << mean << " " << unit << "  # x " << fits[0].*member / si_per_unit << ", y "
      << fits[1].*member / si_per_unit << ", z " << fits[2].*member / si_per_unit << "\n";
  };
  s << "# Allan analysis (IEEE Std 952): mean of the three axes, each axis in the comment.\n"
    << "# bias_instability: the curve's minimum / 0.664 (flicker floor). As the profile's\n"
    << "# Gauss-Markov sigma it is an approximation: a Gauss-Markov bias of sigma q and\n"
    << "# correlation time T peaks at an Allan deviation of 0.617 q at tau = 1.89 T.\n"
    << "# sample interval " << tau0 << " s, record about " << static_cast<double>(samples) * tau0
    << " s\n[gyro]\n";
  const double sqrt12 = std::sqrt(12.0);
  line("arw", gyro_fit, &AllanFit::white, units::deg_per_sqrt_h, "deg/sqrt(h)");
  line("bias_instability", gyro_fit, &AllanFit::floor_bias_instability, units::deg_per_h, "deg/h");
  line("# fitted flicker term", gyro_fit, &AllanFit::bias_instability, units::deg_per_h, "deg/h");
  line("rate_random_walk", gyro_fit, &AllanFit::random_walk, units::deg_per_h_per_sqrt_h,
       "deg/h/sqrt(h)");
  line("quantum", gyro_fit, &AllanFit::quantization, units::arcsec / sqrt12, "arcsec");
  s << "\n[accel]\n";
  line("vrw", accel_fit, &AllanFit::white, units::ug_per_sqrt_hz, "ug/sqrt(Hz)");
  line("bias_instability", accel_fit, &AllanFit::floor_bias_instability, units::ug, "ug");
  line("# fitted flicker term", accel_fit, &AllanFit::bias_instability, units::ug, "ug");
  line("random_walk", accel_fit, &AllanFit::random_walk, units::ug_per_sqrt_h, "ug/sqrt(h)");
  line("quantum", accel_fit, &AllanFit::quantization, 1.0 / sqrt12, "m/s");
  return s.str();
}

}  // namespace sinscal
