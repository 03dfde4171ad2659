#include "filter/diagnosis/diagnosis_core.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <cstdio>

#include "filter/noise/autocorrelation.hpp"

namespace sinscal {

double log10_chi2_tail(double x, int dof) {
  if (dof <= 0) return 0.0;
  if (!(x > 0.0)) return 0.0;
  const double p = boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), x));
  if (p > 1e-280) return std::log10(p);
  // Q(s, y) = Gamma(s, y) / Gamma(s) ~ y^(s-1) e^-y / Gamma(s) (1 + (s-1)/y + ...), y = x/2.
  const double s = 0.5 * dof, y = 0.5 * x;
  const double ln = (s - 1.0) * std::log(y) - y - std::lgamma(s) + std::log1p((s - 1.0) / y);
  return ln / std::log(10.0);
}

double log10_f_tail(double f, int dof1, int dof2) {
  if (dof1 <= 0 || dof2 <= 0 || !(f > 0.0)) return 0.0;
  const double p = boost::math::cdf(boost::math::complement(boost::math::fisher_f(dof1, dof2), f));
  if (p > 1e-280) return std::log10(p);
  return log10_chi2_tail(f * dof1, dof1);
}

void chi2_verdict(TestVerdict& v, const std::string& test, double statistic) {
  v.test = test;
  v.statistic = statistic;
  v.dof2 = 0;
  v.p_value =
      v.dof > 0
          ? boost::math::cdf(boost::math::complement(boost::math::chi_squared(v.dof), statistic))
          : 1.0;
  v.log10_p = log10_chi2_tail(statistic, v.dof);
}

void f_verdict(TestVerdict& v, double likelihood_ratio, double scale, int dof2) {
  v.test = "F";
  v.statistic = (likelihood_ratio / v.dof) / scale;
  v.dof2 = dof2;
  v.p_value = v.dof > 0 && dof2 > 0 ? boost::math::cdf(boost::math::complement(
                                          boost::math::fisher_f(v.dof, dof2), v.statistic))
                                    : 1.0;
  v.log10_p = log10_f_tail(v.statistic, v.dof, dof2);
}

TestVerdict ljung_box(const std::vector<double>& series, int lags) {
  TestVerdict v;
  v.test = "ljung-box";
  const auto n = static_cast<int>(series.size());
  const int h = lags > 0 ? lags : std::min(10, n / 5);
  if (h < 1 || n <= h + 1) return v;
  AutocorrelationSums sums(h);  // the filter's streaming sums (filter/noise/autocorrelation.hpp)
  for (double x : series) sums.push(x);
  if (!sums.varies()) return v;  // constant: not tested
  v.dof = h;
  chi2_verdict(v, "ljung-box", sums.ljung_box_q(h));
  return v;
}

std::string findings_cap_stop(int cap, const std::string& where, const std::string& family) {
  std::string out = "the findings cap (" + std::to_string(cap) + ") was reached";
  if (!family.empty())
    out += "; still significant" + (where.empty() ? "" : " " + where) + ": " + family;
  return out;
}

std::string refused_stop(int round, const std::string& family, double p, const std::string& reason,
                         const std::string& then) {
  char b[600];
  std::snprintf(b, sizeof b,
                "round %d: %s was the most significant candidate (p %.2g), but %s: not named, %s",
                round, family.c_str(), p, reason.c_str(), then.c_str());
  return b;
}

}  // namespace sinscal
