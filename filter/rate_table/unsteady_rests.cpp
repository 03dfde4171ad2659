#include "filter/rate_table/unsteady_rests.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <cstdio>
#include <set>

#include "models/units.hpp"

namespace sinscal {

namespace {

const char* const kOutput[6] = {"gyro x",          "gyro y",          "gyro z",
                                "accelerometer x", "accelerometer y", "accelerometer z"};

double output_of(const RateReading& r, int c) { return c < 3 ? r.omega(c) : r.f(c - 3); }
double var_of(const SegmentMean& m, int c) { return c < 3 ? m.var_omega(c) : m.var_f(c - 3); }
double tau_of(const SegmentMean& m, int c) { return c < 3 ? m.tau_omega(c) : m.tau_f(c - 3); }

// The normal deviate whose two-sided tail is `p`.
double two_sided(double p) {
  return boost::math::quantile(
      boost::math::complement(boost::math::normal_distribution<double>(), 0.5 * p));
}

// The log's rest noise of output `c` without rest `k`: the other rests' readings-weighted
// variance and autocorrelation time (false without another rest).
struct Noise {
  double var = 0.0, tau = 1.0;
};
bool rest_noise(const std::vector<RateSegment>& segments, const std::vector<SegmentMean>& means,
                std::size_t k, int c, Noise& out) {
  double n = 0.0, var = 0.0, tau = 0.0;
  for (std::size_t j = 0; j < means.size(); ++j) {
    if (j == k || segments[j].kind != RateSegment::Kind::Static) continue;
    const auto count = static_cast<double>(means[j].count);
    n += count;
    var += count * var_of(means[j], c);
    tau += count * tau_of(means[j], c);
  }
  if (!(n > 0.0) || !(var > 0.0)) return false;
  out = {var / n, std::max(1.0, tau / n)};
  return true;
}

// The best split of one output of a rest into two levels, each part at least `h` readings: its
// chi2 gain over one level (in `noise`), where and by how much.
struct Split {
  double gain = 0.0, change = 0.0;
  std::size_t at = 0;
  std::size_t splits = 0;
};
Split best_split(const std::vector<RateReading>& r, const SegmentMean& m, int c,
                 const Noise& noise) {
  Split best;
  const std::size_t n = m.last - m.first;
  const auto h = static_cast<std::size_t>(std::max(3.0, std::ceil(2.0 * noise.tau)));
  if (n < 2 * h) return best;
  std::vector<double> prefix(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) prefix[i + 1] = prefix[i] + output_of(r[m.first + i], c);
  best.splits = n - 2 * h + 1;
  for (std::size_t k = h; k + h <= n; ++k) {
    const double n1 = static_cast<double>(k), n2 = static_cast<double>(n - k);
    const double d = (prefix[n] - prefix[k]) / n2 - prefix[k] / n1;
    const double gain = n1 * n2 / (n1 + n2) * d * d / (noise.var * noise.tau);
    if (gain <= best.gain) continue;
    best.gain = gain;
    best.change = d;
    best.at = m.first + k;
  }
  return best;
}

std::string describe(const UnsteadyRest& u, const RateSegment& s, double other_sd) {
  const bool gyro = u.output < 3;
  const double per = gyro ? units::deg_per_s : 1e-3 * units::g0;
  const char* unit = gyro ? "deg/s" : "mg";
  char text[400];
  std::snprintf(text, sizeof text,
                "%s, readings %zu-%zu: %s level change %+.3g %s at reading %zu, %.1f sigma in the "
                "log's rest noise (%.3g %s per reading, from the other rests; quantile %.1f "
                "sigma), its scatter %.1f times theirs",
                segment_name(s, u.segment).c_str(), u.first, u.last, kOutput[u.output],
                u.change / per, unit, u.at, u.sigma, other_sd / per, unit, u.quantile,
                u.scatter_ratio);
  return text;
}

}  // namespace

std::vector<UnsteadyRest> unsteady_rests(const std::vector<RateReading>& readings,
                                         const std::vector<RateSegment>& segments,
                                         const std::vector<SegmentMean>& means, double alpha) {
  std::vector<UnsteadyRest> out;
  const auto rests =
      static_cast<double>(std::count_if(segments.begin(), segments.end(), [](const RateSegment& s) {
        return s.kind == RateSegment::Kind::Static;
      }));
  for (std::size_t k = 0; k < segments.size() && k < means.size(); ++k) {
    if (segments[k].kind != RateSegment::Kind::Static) continue;
    UnsteadyRest worst;
    double worst_excess = 0.0, worst_sd = 0.0;
    for (int c = 0; c < 6; ++c) {
      Noise noise;
      if (!rest_noise(segments, means, k, c, noise)) continue;
      const Split s = best_split(readings, means[k], c, noise);
      if (s.splits == 0) continue;
      const double z = two_sided(alpha / (static_cast<double>(s.splits) * 6.0 * rests));
      const double sigma = std::sqrt(s.gain);
      if (!(sigma > z) || sigma / z <= worst_excess) continue;
      worst_excess = sigma / z;
      worst_sd = std::sqrt(noise.var);
      worst = UnsteadyRest{};
      worst.segment = k;
      worst.output = c;
      worst.first = means[k].first;
      worst.last = means[k].last;
      worst.at = s.at;
      worst.change = s.change;
      worst.sigma = sigma;
      worst.quantile = z;
      worst.scatter_ratio = std::sqrt(var_of(means[k], c) / noise.var);
    }
    if (!(worst_excess > 0.0)) continue;
    worst.statement = describe(worst, segments[k], worst_sd);
    out.push_back(worst);
  }
  return out;
}

namespace {

// The fit without the segments in `drop`.
RateTableResult fit_without(const std::set<std::size_t>& drop,
                            const std::vector<RateSegment>& segments,
                            const std::vector<SegmentMean>& means, const Site& site, double gravity,
                            const RateTableOptions& options) {
  std::vector<RateSegment> s;
  std::vector<SegmentMean> m;
  for (std::size_t k = 0; k < segments.size(); ++k) {
    if (drop.count(k) != 0) continue;
    s.push_back(segments[k]);
    m.push_back(means[k]);
  }
  return rate_table_calibrate(s, m, site, gravity, options);
}

// The full fit's coefficients the reduced one lacks, named.
std::string lost(const RateTableResult& full, const RateTableResult& reduced) {
  std::string out;
  for (const auto& c : full.coefficients)
    if (std::none_of(reduced.coefficients.begin(), reduced.coefficients.end(),
                     [&](const RateCoefficient& d) { return d.name == c.name; }))
      out += (out.empty() ? "" : ", ") + c.name;
  return out;
}

// Rest `k`'s variances and autocorrelation times set to the log's rest noise (the other rests'),
// output by output where there is one.
void in_rest_noise(const std::vector<RateSegment>& segments, const std::vector<SegmentMean>& means,
                   std::size_t k, SegmentMean& m) {
  for (int c = 0; c < 6; ++c) {
    Noise noise;
    if (!rest_noise(segments, means, k, c, noise)) continue;
    (c < 3 ? m.var_omega(c) : m.var_f(c - 3)) = noise.var;
    (c < 3 ? m.tau_omega(c) : m.tau_f(c - 3)) = noise.tau;
  }
}

std::string triad_of(const std::string& name) { return name.substr(0, name.find('.') + 1); }

// Whether both fits have the same coefficients of `triad` ("gyro." or "accel."): only then is the
// shift of its coefficients the rest's data, not a model the others cannot determine.
bool same_model(const RateTableResult& a, const RateTableResult& b, const std::string& triad) {
  std::set<std::string> in_a, in_b;
  for (const auto& c : a.coefficients)
    if (c.name.rfind(triad, 0) == 0) in_a.insert(c.name);
  for (const auto& c : b.coefficients)
    if (c.name.rfind(triad, 0) == 0) in_b.insert(c.name);
  return in_a == in_b;
}

// The rest's means against the fit of the others: the shift of the coefficients both fits have
// when it is left out, chi2 in the shift's covariance (P_others - P_full: nested fits, the
// deleted-residual test of its rows), scaled to the others' sigmas; its dof the covariance's rank.
void against_others(UnsteadyRest& u, const RateTableResult& full, const RateTableResult& others,
                    double alpha) {
  const std::string triad = u.output < 3 ? "gyro." : "accel.";
  std::vector<std::pair<Eigen::Index, Eigen::Index>> common;  // (full, others) positions
  for (std::size_t i = 0; i < full.coefficients.size(); ++i)
    for (std::size_t j = 0; j < others.coefficients.size(); ++j)
      if (full.coefficients[i].name == others.coefficients[j].name &&
          triad_of(full.coefficients[i].name) == triad && same_model(full, others, triad))
        common.emplace_back(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
  const auto n = static_cast<Eigen::Index>(common.size());
  Eigen::VectorXd shift(n);
  Eigen::MatrixXd cov(n, n);
  for (Eigen::Index a = 0; a < n; ++a) {
    const auto [fa, oa] = common[static_cast<std::size_t>(a)];
    const double scale = others.coefficients[static_cast<std::size_t>(oa)].sigma;
    shift(a) = (full.coefficients[static_cast<std::size_t>(fa)].value -
                others.coefficients[static_cast<std::size_t>(oa)].value) /
               scale;
    for (Eigen::Index b = 0; b < n; ++b) {
      const auto [fb, ob] = common[static_cast<std::size_t>(b)];
      cov(a, b) = (others.covariance(oa, ob) - full.covariance(fa, fb)) /
                  (scale * others.coefficients[static_cast<std::size_t>(ob)].sigma);
    }
  }
  double chi2 = 0.0;
  int dof = 0;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(n > 0 ? cov
                                                                 : Eigen::MatrixXd::Zero(1, 1));
  for (Eigen::Index k = 0; k < n; ++k) {
    if (!(eig.eigenvalues()(k) > 1e-9)) continue;
    const double p = eig.eigenvectors().col(k).dot(shift);
    chi2 += p * p / eig.eigenvalues()(k);
    ++dof;
  }
  u.others_chi2 = chi2;
  u.others_dof = dof;
  u.others_quantile = dof > 0 ? boost::math::quantile(boost::math::complement(
                                    boost::math::chi_squared_distribution<double>(dof), alpha))
                              : 0.0;
  char text[200];
  std::snprintf(text, sizeof text,
                "; its %s means (in the log's rest noise) against the fit of the other segments: "
                "chi2 %.1f on %d dof (quantile %.1f)",
                u.output < 3 ? "gyro" : "accelerometer", chi2, dof, u.others_quantile);
  u.statement += dof > 0 ? std::string(text)
                         : "; without it the other segments do not determine all of its triad's "
                           "coefficients: nothing checks its means";
}

// The rest `u`'s means in the noise a rest of this log has (its own scatter and autocorrelation
// time grow with the level change and would hide it) against the fit of the other segments
// (against_others). A refit the check alone needs that fails (RateTableError: e.g. a scale beyond
// its bound without the rest) leaves the rest unchecked, said so, never the run's refusal.
void judge_against_others(UnsteadyRest& u, const std::vector<RateSegment>& segments,
                          const std::vector<SegmentMean>& means, const Site& site, double gravity,
                          const RateTableOptions& options, double alpha) {
  try {
    std::vector<SegmentMean> judged = means;
    in_rest_noise(segments, means, u.segment, judged[u.segment]);
    const RateTableResult with = rate_table_calibrate(segments, judged, site, gravity, options);
    const RateTableResult others =
        fit_without({u.segment}, segments, means, site, gravity, options);
    against_others(u, with, others, alpha);
  } catch (const RateTableError& e) {
    u.others_chi2 = 0.0;
    u.others_quantile = 0.0;
    u.others_dof = 0;
    u.statement +=
        std::string("; its means not checked against the other segments (") + e.what() + ")";
  }
}

}  // namespace

RateTableResult rate_table_calibrate_rests(const std::vector<RateReading>& readings,
                                           const std::vector<RateSegment>& segments,
                                           const std::vector<SegmentMean>& means, const Site& site,
                                           double gravity, const RateTableOptions& options,
                                           bool keep, double alpha) {
  RateTableResult full = rate_table_calibrate(segments, means, site, gravity, options);
  std::vector<UnsteadyRest> found = unsteady_rests(readings, segments, means, alpha);
  if (found.empty()) return full;
  std::set<std::size_t> drop;
  for (auto& u : found) {
    judge_against_others(u, segments, means, site, gravity, options,
                         alpha / static_cast<double>(found.size()));
    const bool off = u.others_chi2 > u.others_quantile;
    u.excluded = off && !keep;
    if (u.excluded) drop.insert(u.segment);
    u.statement += u.excluded ? ": not a rest, left out of the fit (--keep-unsteady-rests keeps it)"
                   : off      ? ": not a rest, kept (--keep-unsteady-rests)"
                              : ": kept";
  }
  if (drop.empty()) {
    full.unsteady = found;
    return full;
  }
  RateTableResult reduced = fit_without(drop, segments, means, site, gravity, options);
  const std::string missing = lost(full, reduced);
  if (!missing.empty()) {
    std::string why;
    for (const auto& u : found)
      if (u.excluded) why += (why.empty() ? "" : "; ") + u.statement;
    throw RateTableError(why + "; without it the other segments do not determine " + missing +
                         ": refused (--keep-unsteady-rests fits it as a rest)");
  }
  reduced.unsteady = found;
  return reduced;
}

std::vector<RateSegment> fitted_segments(const std::vector<RateSegment>& segments,
                                         const RateTableResult& r) {
  std::vector<RateSegment> out;
  for (std::size_t k = 0; k < segments.size(); ++k)
    if (std::none_of(r.unsteady.begin(), r.unsteady.end(),
                     [k](const UnsteadyRest& u) { return u.excluded && u.segment == k; }))
      out.push_back(segments[k]);
  return out;
}

}  // namespace sinscal
