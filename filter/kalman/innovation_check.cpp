#include "filter/kalman/innovation_check.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace sinscal {

namespace {

const char* const kKinds[4] = {"velocity (turns)", "velocity (dwells)", "position", "attitude"};
const char* const kAxes[3] = {"north", "east", "down"};

// A statistic that is not a finite number (a diverged filter's NaN innovations) fails the
// upper test (p 0) and never the lower one (p 1); Boost throws on it.
double chi2_upper(double x, double dof) {
  if (!std::isfinite(x)) return 0.0;
  return boost::math::cdf(boost::math::complement(boost::math::chi_squared(dof), x));
}

double chi2_lower(double x, double dof) {
  if (!std::isfinite(x)) return 1.0;
  return boost::math::cdf(boost::math::chi_squared(dof), x);
}

ChannelCheck channel_check(const std::string& name, const AutocorrelationSums& s) {
  ChannelCheck c;
  c.channel = name;
  c.updates = s.count();
  const double n = static_cast<double>(c.updates);
  c.nis = s.sum_squares();
  c.nis_per_dof = c.nis / n;
  c.nis_p = chi2_upper(c.nis, n);
  c.mean = s.sum() / n;
  const int h = static_cast<int>(std::min<long>(s.lags(), c.updates / 5));
  if (h >= 1 && c.updates > h + 1 && s.varies()) {
    c.lags = h;
    c.ljung_box_q = s.ljung_box_q(h);
    c.ljung_box_p = chi2_upper(c.ljung_box_q, h);
    for (int k = 1; k <= h; ++k)
      if (std::abs(s.autocorrelation(k)) > std::abs(c.largest_autocorrelation)) {
        c.largest_lag = k;
        c.largest_autocorrelation = s.autocorrelation(k);
      }
  }
  return c;
}

}  // namespace

void InnovationRecord::add(InnovationKind kind, int axis, double normalized) {
  if (axis < 0 || axis > 2) throw std::invalid_argument("innovation record: axis out of range");
  const int index = 3 * static_cast<int>(kind) + axis;
  auto& c = channels_[static_cast<std::size_t>(index)];
  if (!c) c.emplace(kInnovationLags);
  c->push(normalized);
}

std::string InnovationRecord::channel_name(int channel) {
  return std::string(kKinds[channel / 3]) + " " + kAxes[channel % 3];
}

InnovationCheck innovation_check(const InnovationRecord& record, double alpha) {
  InnovationCheck out;
  out.alpha = alpha;
  for (int c = 0; c < InnovationRecord::kChannels; ++c) {
    const auto& s = record.channel(c);
    if (!s || s->count() == 0) continue;
    out.channels.push_back(channel_check(InnovationRecord::channel_name(c), *s));
    ChannelCheck& k = out.channels.back();
    k.sigma_bound = c / 3 != static_cast<int>(InnovationKind::VelocityDwells);
    out.tests += 1 + (k.lags > 0 && !k.sigma_bound ? 1 : 0);
  }
  if (out.tests == 0) {
    out.verdict = "not tested (no update)";
    return out;
  }
  out.threshold = alpha / out.tests;
  char b[240];
  for (auto& c : out.channels) {
    c.nis_holds = !(c.nis_p < out.threshold);
    c.sigma_bound =
        c.sigma_bound || chi2_lower(c.nis, static_cast<double>(c.updates)) < out.threshold;
    c.white = c.lags == 0 || c.sigma_bound || !(c.ljung_box_p < out.threshold);
    if (!c.nis_holds) {
      std::snprintf(b, sizeof b, "%s NIS per dof %.3g on %ld updates (p %.2g)", c.channel.c_str(),
                    c.nis_per_dof, c.updates, c.nis_p);
      out.failures.emplace_back(b);
    }
    if (!c.white) {
      std::snprintf(b, sizeof b,
                    "%s innovations correlated at lag %d (r %.2f; Ljung-Box Q %.4g on %d lags, "
                    "p %.2g)",
                    c.channel.c_str(), c.largest_lag, c.largest_autocorrelation, c.ljung_box_q,
                    c.lags, c.ljung_box_p);
      out.failures.emplace_back(b);
    }
  }
  out.consistent = out.failures.empty();
  if (out.consistent) return out;
  out.verdict = "not consistent: ";
  for (std::size_t i = 0; i < out.failures.size(); ++i)
    out.verdict += (i ? "; " : "") + out.failures[i];
  return out;
}

}  // namespace sinscal
