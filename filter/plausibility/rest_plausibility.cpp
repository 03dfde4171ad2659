#include "filter/plausibility/rest_plausibility.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <filesystem>
#include <functional>

#include "models/earth.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

// Generic bounds (no sensor profile): the widest of common consumer MEMS data sheets for the
// errors, a gyro's zero-rate offset up to 25 deg/s per axis (MPU-6050: 20, L3GD20 at 2000 deg/s:
// 25), an accelerometer's zero-g offset up to 150 mg per axis and its sensitivity 3 % off
// (MPU-6050: 80 mg on z, 3 %). Noise densities from below a navigation-grade unit's (FOG 0.001
// deg/sqrt(h), 10 ug/sqrt(Hz)) to a hand's tremor on a consumer part: gyro 1e-4 to 20
// deg/sqrt(h), accelerometer 0.5 to 5000 ug/sqrt(Hz).
constexpr double kGenericGyroBias = 25.0 * units::deg_per_s;
constexpr double kGenericAccelBias = 0.150 * units::g0;
constexpr double kGenericAccelScale = 0.03;
constexpr double kGenericGyroNoiseLo = 1e-4 * units::deg_per_sqrt_h;
constexpr double kGenericGyroNoiseHi = 20.0 * units::deg_per_sqrt_h;
constexpr double kGenericAccelNoiseLo = 0.5 * units::ug_per_sqrt_hz;
constexpr double kGenericAccelNoiseHi = 5000.0 * units::ug_per_sqrt_hz;
// A consumer MEMS unit's bias drift over a hand-held session without a profile: the data sheets'
// offset temperature drift (about 1 mg/K, 0.05 deg/s/K) over 2 K of warm-up or a hand's heat.
constexpr double kGenericAccelWander = 2.0 * units::mg;
constexpr double kGenericGyroWander = 0.1 * units::deg_per_s;
// A profile's noise: a unit half as noisy as its data sheet's typical density is not credible;
// ten times noisier is a hand's tremor or a vibrating bench, not yet a wrong unit.
constexpr double kProfileNoiseBelow = 2.0;
constexpr double kProfileNoiseAbove = 10.0;
// Noise sigmas of a rest's mean added to the bounds.
constexpr double kMeanSigmas = 5.0;
// Swapped triads: the gyros' rest means turn by more than this between rests, their sizes within
// this ratio, while the accelerometers' turn by less than this.
constexpr double kTurnedRests = 30.0 * units::deg;
constexpr double kSteadySize = 1.5;
constexpr double kSteadyDirection = 10.0 * units::deg;

std::string number(double v, int precision = 4) { return plausibility_number(v, precision); }

bool density_ok(double d, double lo, double hi) { return d >= lo && d <= hi; }

// The unit factor (measured over true) that brings a triad's rest rate or specific force and its
// noise into their bounds, named; empty when none does.
std::string rescuing_factor(bool gyro, double dt, const std::function<bool(double)>& passes) {
  // The smallest correction that does.
  std::vector<UnitFactor> factors = unit_factors(gyro, dt);
  std::stable_sort(factors.begin(), factors.end(), [](const UnitFactor& a, const UnitFactor& b) {
    return std::abs(std::log(a.value)) < std::abs(std::log(b.value));
  });
  for (const auto& f : factors)
    if (passes(f.value)) return f.cause;
  return "";
}

struct RestContext {
  double g, Omega;
  const RestLimits& l;
  std::string swapped;  // not empty: the rests show the triads swapped (why)
};

// Largest angle between the first rest's mean and another's; their magnitudes' max / min.
void spread(const std::vector<Eigen::Vector3d>& v, double& angle, double& ratio) {
  angle = 0.0;
  double lo = v.front().norm(), hi = lo;
  for (const auto& x : v) {
    angle = std::max(angle, std::atan2(v.front().cross(x).norm(), v.front().dot(x)));
    lo = std::min(lo, x.norm());
    hi = std::max(hi, x.norm());
  }
  ratio = lo > 0.0 ? hi / lo : 0.0;
}

// At rest the accelerometers' mean turns with the pose and keeps its size (gravity), the gyros'
// stays put (the biases). The other way round, whatever the units, the triads are swapped.
std::string swapped_triads(const std::vector<RestStatistics>& rests) {
  if (rests.size() < 3) return "";
  std::vector<Eigen::Vector3d> f, w;
  for (const auto& r : rests) {
    f.push_back(r.f_b);
    w.push_back(r.omega_ib_b);
  }
  double fa = 0.0, fr = 0.0, wa = 0.0, wr = 0.0;
  spread(f, fa, fr);
  spread(w, wa, wr);
  if (!(wa > kTurnedRests && wr < kSteadySize && fa < kSteadyDirection)) return "";
  return "the gyro and accelerometer columns (or files) swapped: the gyros' mean turns by up to " +
         number(wa / units::deg, 3) +
         " deg from rest to rest at a steady size, as gravity does, "
         "while the accelerometers' stays within " +
         number(fa / units::deg, 2) + " deg";
}

double rate_bound(const RestContext& c, const RestStatistics& r) {
  return c.l.gyro_bias + c.Omega + kMeanSigmas * r.gyro_density.norm() / std::sqrt(r.seconds);
}

double force_bound(const RestContext& c, const RestStatistics& r) {
  return c.l.specific_force + kMeanSigmas * r.accel_density.norm() / std::sqrt(r.seconds);
}

// Whether the rest's gyro means and noise, divided by `k`, would pass.
bool gyro_passes(const RestContext& c, const RestStatistics& r, double k) {
  return r.omega_ib_b.norm() / k <= rate_bound(c, r) &&
         density_ok(r.gyro_density.maxCoeff() / k, c.l.gyro_noise_lo, c.l.gyro_noise_hi);
}

// A unit is named for the accelerometers when it brings |f| this close to g (relative): the
// bounds are wider than the factors' spacing (a 16 g scale for a 2 g one is 8, not g0 = 9.8).
constexpr double kNamedUnit = 0.15;

bool accel_passes(const RestContext& c, const RestStatistics& r, double k) {
  return std::abs(std::log(r.f_b.norm() / k / c.g)) <= kNamedUnit &&
         density_ok(r.accel_density.maxCoeff() / k, c.l.accel_noise_lo, c.l.accel_noise_hi);
}

// The likely cause of a triad that fails: the two triads swapped, accelerometer data as the
// gyros', a unit, or the bounds.
std::string rest_cause(const RestContext& c, const RestStatistics& r, bool gyro) {
  if (!c.swapped.empty()) return c.swapped;
  const bool gyros_read_gravity = std::abs(r.omega_ib_b.norm() - c.g) <= force_bound(c, r);
  const bool accels_read_a_rate = r.f_b.norm() <= rate_bound(c, r);
  if (gyros_read_gravity && accels_read_a_rate)
    return "the gyro and accelerometer columns (or files) swapped";
  if (gyro && gyros_read_gravity)
    return "the gyros read gravity: accelerometer data given as the gyros' (the same file, or the "
           "accelerometer columns named twice)";
  std::string unit = rescuing_factor(
      gyro, r.dt, [&](double k) { return gyro ? gyro_passes(c, r, k) : accel_passes(c, r, k); });
  if (!unit.empty()) return unit;
  return "a wrong unit, scale or column, or a sensor that is not of the kind of the bounds (" +
         c.l.source + ")";
}

std::string noise_line(const RestStatistics& r) {
  return r.where + ": gyro " + number(r.gyro_density.maxCoeff() / units::deg_per_sqrt_h, 3) +
         " deg/sqrt(h), accelerometer " +
         number(r.accel_density.maxCoeff() / units::ug_per_sqrt_hz, 3) +
         " ug/sqrt(Hz) (largest axis)";
}

// The quietest rest's noise against the band: a sensor's white noise is a floor that a tremor
// only adds to, so the quietest rest measures it.
PlausibilityCheck check_noise(const RestContext& c, const std::vector<RestStatistics>& rests,
                              const std::string& input) {
  const auto quietest = [&](bool gyro) -> const RestStatistics& {
    return *std::min_element(rests.begin(), rests.end(), [&](const auto& a, const auto& b) {
      return gyro ? a.gyro_density.maxCoeff() < b.gyro_density.maxCoeff()
                  : a.accel_density.maxCoeff() < b.accel_density.maxCoeff();
    });
  };
  const RestStatistics &rg = quietest(true), &ra = quietest(false);
  const double dg = rg.gyro_density.maxCoeff(), da = ra.accel_density.maxCoeff();
  const bool gyro_ok = density_ok(dg, c.l.gyro_noise_lo, c.l.gyro_noise_hi);
  const bool accel_ok = density_ok(da, c.l.accel_noise_lo, c.l.accel_noise_hi);
  std::string detail =
      input + ": noise densities at the sample interval " + number(rg.dt) +
      " s: the quietest rest, " + noise_line(rg) +
      (&rg == &ra ? "" : "; quietest accelerometer " + noise_line(ra)) + "; the band (" +
      c.l.source + "): gyro " + number(c.l.gyro_noise_lo / units::deg_per_sqrt_h, 3) + " to " +
      number(c.l.gyro_noise_hi / units::deg_per_sqrt_h, 3) + " deg/sqrt(h), accelerometer " +
      number(c.l.accel_noise_lo / units::ug_per_sqrt_hz, 3) + " to " +
      number(c.l.accel_noise_hi / units::ug_per_sqrt_hz, 3) + " ug/sqrt(Hz)";
  if (!gyro_ok || !accel_ok) {
    const bool gyro = !gyro_ok;
    const double d = gyro ? dg : da;
    const std::string unit = rescuing_factor(gyro, rg.dt, [&](double k) {
      return gyro ? density_ok(d / k, c.l.gyro_noise_lo, c.l.gyro_noise_hi)
                  : density_ok(d / k, c.l.accel_noise_lo, c.l.accel_noise_hi);
    });
    detail += ": the " + std::string(gyro ? "gyros'" : "accelerometers'") +
              " outside it; the densities scale with the square root of the sample interval, so "
              "a wrong rate (without a time column) puts them there, or a wrong unit" +
              (unit.empty() ? "" : " (" + unit + ")");
  }
  return {"noise", gyro_ok && accel_ok, detail};
}

}  // namespace

RestLimits RestLimits::from_profile(const SensorProfile* p) {
  RestLimits l;
  if (!p) {
    l.source = "generic MEMS bounds";
    l.gyro_bias = std::sqrt(3.0) * kGenericGyroBias;
    l.specific_force = std::sqrt(3.0) * kGenericAccelBias + kGenericAccelScale * units::g0;
    l.gyro_noise_lo = kGenericGyroNoiseLo;
    l.gyro_noise_hi = kGenericGyroNoiseHi;
    l.accel_noise_lo = kGenericAccelNoiseLo;
    l.accel_noise_hi = kGenericAccelNoiseHi;
    l.accel_wander.instability = kGenericAccelWander;
    l.gyro_wander.instability = kGenericGyroWander;
    return l;
  }
  // The table's gate's bounds (a rest is a dwell of unknown attitude).
  const PlausibilityLimits t = PlausibilityLimits::from_profile(p);
  l.source = "sensor profile '" + p->name + "'";
  l.gyro_bias = t.check_rate ? t.rate : std::sqrt(3.0) * kGenericGyroBias;
  l.specific_force = t.specific_force;
  const double gw = p->noise.gyro.white, aw = p->noise.accel.white;
  l.gyro_noise_lo = gw > 0.0 ? gw / kProfileNoiseBelow : kGenericGyroNoiseLo;
  l.gyro_noise_hi = gw > 0.0 ? gw * kProfileNoiseAbove : kGenericGyroNoiseHi;
  l.accel_noise_lo = aw > 0.0 ? aw / kProfileNoiseBelow : kGenericAccelNoiseLo;
  l.accel_noise_hi = aw > 0.0 ? aw * kProfileNoiseAbove : kGenericAccelNoiseHi;
  // The profile's bias wander; a profile that states none (white noise only) gets the generic
  // thermal drift, said in the source.
  const auto wander = [](const TriadNoise& n, double generic) {
    if (!(n.bias_instability > 0.0) && !(n.random_walk > 0.0)) return Wander{generic, 0.0, 0.0};
    return Wander{n.bias_instability, n.bias_instability > 0.0 ? n.correlation_time : 0.0,
                  n.random_walk};
  };
  l.accel_wander = wander(p->noise.accel, kGenericAccelWander);
  l.gyro_wander = wander(p->noise.gyro, kGenericGyroWander);
  const auto stated = [](const TriadNoise& n) {
    return n.bias_instability > 0.0 || n.random_walk > 0.0;
  };
  if (!stated(p->noise.accel) || !stated(p->noise.gyro))
    l.wander_source = l.source + " (no bias wander stated for " +
                      (stated(p->noise.accel)  ? "the gyros"
                       : stated(p->noise.gyro) ? "the accelerometers"
                                               : "either triad") +
                      ": a consumer MEMS unit's thermal drift)";
  return l;
}

RestStatistics rest_statistics(const std::vector<ImuReading>& r, std::size_t first,
                               std::size_t last, const std::string& where) {
  RestStatistics s;
  s.where = where;
  if (last >= r.size() || last < first + 2)
    throw std::invalid_argument(where + ": a rest needs at least three readings");
  const std::size_t n = last - first + 1;
  Eigen::Vector3d da = Eigen::Vector3d::Zero(), dg = Eigen::Vector3d::Zero();
  for (std::size_t k = first; k <= last; ++k) {
    s.f_b += r[k].accel;
    s.omega_ib_b += r[k].gyro;
    if (k == first) continue;
    da += (r[k].accel - r[k - 1].accel).cwiseAbs2();
    dg += (r[k].gyro - r[k - 1].gyro).cwiseAbs2();
  }
  s.count = n;
  s.f_b /= static_cast<double>(n);
  s.omega_ib_b /= static_cast<double>(n);
  s.seconds = r[last].t - r[first].t;
  s.dt = s.seconds / static_cast<double>(n - 1);
  // var(y_k - y_k-1) = 2 var(y) for white noise; density = sigma sqrt(dt).
  const double pairs = 2.0 * static_cast<double>(n - 1);
  s.accel_density = (da / pairs * s.dt).cwiseSqrt();
  s.gyro_density = (dg / pairs * s.dt).cwiseSqrt();
  return s;
}

PlausibilityReport check_rests(const std::vector<RestStatistics>& rests, double g,
                               const RestLimits& l, const std::string& input) {
  const RestContext c{g, Earth::wgs84().rate(), l, swapped_triads(rests)};
  PlausibilityFindings magnitude{{}, "rests"}, rate{{}, "rests"};
  for (const auto& r : rests) {
    const std::string where = input + ": " + r.where;
    const double f = r.f_b.norm(), w = r.omega_ib_b.norm();
    if (!(std::abs(f - g) <= force_bound(c, r)))
      magnitude.lines.push_back(where + ": |f| = " + number(f) +
                                " m/s^2 at rest where gravity is " + number(g) + " (bound +-" +
                                number(force_bound(c, r), 3) + ", " + l.source +
                                "): " + rest_cause(c, r, false));
    if (!(w <= rate_bound(c, r)))
      rate.lines.push_back(
          where + ": |omega| = " + number(w / units::deg_per_s) + " deg/s at rest (bound " +
          number(rate_bound(c, r) / units::deg_per_s, 3) + " deg/s: the gyro biases of the " +
          l.source + " plus the Earth rate): " + rest_cause(c, r, true));
  }
  PlausibilityReport report;
  report.checks.push_back(magnitude.check("gravity magnitude"));
  report.checks.push_back(rate.check("rate at rest"));
  if (!rests.empty()) report.checks.push_back(check_noise(c, rests, input));
  return report;
}

PlausibilityCheck check_same_signal(const std::vector<ImuReading>& r, const RestLimits& l,
                                    const std::string& input) {
  PlausibilityCheck c{"same signal", true, ""};
  const auto n = static_cast<double>(r.size());
  if (r.size() < 3) return c;
  Eigen::Vector3d ma = Eigen::Vector3d::Zero(), mg = Eigen::Vector3d::Zero();
  for (const auto& x : r) {
    ma += x.accel;
    mg += x.gyro;
  }
  ma /= n;
  mg /= n;
  Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();
  Eigen::Vector3d va = Eigen::Vector3d::Zero(), vg = Eigen::Vector3d::Zero();
  for (const auto& x : r) {
    const Eigen::Vector3d a = x.accel - ma, w = x.gyro - mg;
    cross += w * a.transpose();
    va += a.cwiseAbs2();
    vg += w.cwiseAbs2();
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      if (!(va(j) > 0.0 && vg(i) > 0.0)) continue;
      const double rho = cross(i, j) / std::sqrt(va(j) * vg(i));
      if (std::abs(rho) < l.same_signal || !c.passed) continue;
      c.passed = false;
      c.detail = input + ": gyro " + std::string(1, char('x' + i)) + " and accelerometer " +
                 std::string(1, char('x' + j)) + " are one signal (correlation " + number(rho, 6) +
                 "): the same file given for both triads, or the accelerometer columns named as "
                 "the gyros'";
    }
  return c;
}

PlausibilityCheck check_same_files(const LogFormat& log) {
  PlausibilityCheck c{"same signal", true, ""};
  if (!log.split()) return c;
  std::error_code ec;
  const bool same = std::filesystem::equivalent(log.accel_file, log.gyro_file, ec);
  if (same && !ec) {
    c.passed = false;
    c.detail = log.gyro_file +
               ": given as both accel_file and gyro_file: the same file for both "
               "triads (the gyros' file is another)";
  }
  return c;
}

namespace {

double chi2_quantile(double dof, double false_alarm) {
  return boost::math::quantile(boost::math::chi_squared(std::max(dof, 1.0)), 1.0 - false_alarm);
}

// What a turn's residual variance per component is expected to be over the noise the fit gives
// it: the noise, a timing error of one sample interval at its peak rate, an unmodelled share of
// its angle.
double turn_excess(const TableFreeTurn& t) {
  if (!(t.noise_sigma > 0.0)) return 1.0;
  const double timing = t.peak_rate * t.interval;
  const double dynamics = HandheldFitBounds::kTurnDynamics * t.angle;
  return 1.0 + (timing * timing + dynamics * dynamics) / (t.noise_sigma * t.noise_sigma);
}

}  // namespace

namespace {

// Mean-square deviation of the bias from its session mean over `span` s, and the number of its
// independent values: a Gauss-Markov process of variance B^2 and correlation time tau keeps
// B^2 (1 - g(span/tau)), g(x) = 2/x - 2 (1 - e^-x)/x^2 the variance of its time average, with
// about 1 + span/tau independent values; a random walk K keeps K^2 span/6, one value.
std::pair<double, double> wander_variance(const RestLimits::Wander& w, double span) {
  double var = w.random_walk * w.random_walk * span / 6.0;
  double values = 1.0;
  if (w.instability > 0.0 && w.correlation_time > 0.0 && span > 0.0) {
    const double x = span / w.correlation_time;
    const double g = x < 1e-6 ? 1.0 - x / 3.0 : 2.0 / x - 2.0 * (1.0 - std::exp(-x)) / (x * x);
    var += w.instability * w.instability * (1.0 - g);
    values = 1.0 + x;
  } else {
    var += w.instability * w.instability;  // one value over the session
  }
  return {var, values};
}

// A static part: its white-noise quantile plus the wander's expected chi2 (each residual's
// wander variance over its noise variance n_p / N_i^2, the fit's share removed by dof/residuals)
// at the quantile of its independent values.
HandheldFitBounds::Part static_part(const TableFreeFitPart& f, const TableFreeResult& r,
                                    const Eigen::Vector3d& noise, const RestLimits::Wander& w) {
  HandheldFitBounds::Part p{f.chi2, f.dof, 0.0, 0.0, 0.0};
  const double span = r.poses.empty() ? 0.0 : r.poses.back().t_end - r.poses.front().t_start;
  const auto [var, values] = wander_variance(w, span);
  p.wander = std::sqrt(var);
  double per_var = 0.0;  // sum over the residuals of n_p / N_i^2
  for (const auto& pose : r.poses)
    for (int i = 0; i < 3; ++i)
      if (noise(i) > 0.0) per_var += static_cast<double>(pose.count) / (noise(i) * noise(i));
  const double share = f.residuals > 0 ? f.dof / f.residuals : 0.0;
  const double wander_chi2 = var * per_var * share;
  const double n_values =
      std::min(values, static_cast<double>(std::max<std::size_t>(1, r.poses.size())));
  p.expected = f.dof + wander_chi2;
  p.bound = chi2_quantile(f.dof, HandheldFitBounds::kFalseAlarm) +
            wander_chi2 * chi2_quantile(n_values, HandheldFitBounds::kFalseAlarm) / n_values;
  return p;
}

}  // namespace

HandheldFitBounds handheld_fit_bounds(const TableFreeResult& r, const RestLimits& l) {
  HandheldFitBounds b;
  b.wander_source = l.wander_source.empty() ? l.source : l.wander_source;
  b.accel = static_part(r.accel_fit, r, r.accel_noise, l.accel_wander);
  b.gyro = static_part(r.gyro_rest_fit, r, r.gyro_noise, l.gyro_wander);
  b.turns = {r.turn_fit.chi2, r.turn_fit.dof, 0.0, 0.0, 0.0};
  double sum = 0.0;
  for (const auto& t : r.turns) sum += turn_excess(t);
  b.turn_excess = r.turns.empty() ? 1.0 : sum / static_cast<double>(r.turns.size());
  b.turns.expected = b.turn_excess * r.turn_fit.dof;
  b.turns.bound = b.turn_excess * chi2_quantile(b.turns.dof, HandheldFitBounds::kFalseAlarm);
  return b;
}

PlausibilityCheck check_handheld_fit(const TableFreeResult& r, const RestLimits& l,
                                     const std::string& input) {
  const HandheldFitBounds b = handheld_fit_bounds(r, l);
  PlausibilityCheck c{"fit", true, ""};
  auto part = [&](const char* what, const HandheldFitBounds::Part& p) {
    if (p.chi2 <= p.bound) return;
    c.passed = false;
    c.detail +=
        std::string(c.detail.empty() ? input + ": the table-free fit's residuals: " : "; ") + what +
        " chi2 " + number(p.chi2) + " (dof " + number(p.dof) + ", chi2/dof " +
        number(p.chi2 / std::max(p.dof, 1.0)) + ") beyond its bound " + number(p.bound) + " (" +
        number(p.chi2 / std::max(p.bound, 1e-300), 3) + " times)";
  };
  part("accelerometer poses", b.accel);
  part("gyro poses", b.gyro);
  part("turns", b.turns);
  if (!c.passed)
    c.detail += " (the noise model: the data's noise, the bias wander of the " + b.wander_source +
                ", the turns' timing; docs/methods/table-free.md): not the data's model; the "
                "data are not what the session says (a wrong file, column or unit)";
  if (!r.converged) {
    c.passed = false;
    c.detail += std::string(c.detail.empty() ? input + ": " : "; ") +
                "the estimate has not converged (its last step is " + number(r.step_over_sigma, 3) +
                " of a sigma)";
  }
  return c;
}

PlausibilityCheck check_fit(double chi2_per_dof, const RestLimits& l, const std::string& input,
                            const std::string& what) {
  PlausibilityCheck c{"fit", true, ""};
  if (chi2_per_dof <= l.max_fit_chi2_per_dof) return c;
  c.passed = false;
  c.detail = input + ": " + what + ": chi2/dof " + number(chi2_per_dof) + ", " +
             number(chi2_per_dof, 2) + " times its noise model (bound " +
             number(l.max_fit_chi2_per_dof) +
             "): not converged to the data's model; the data are not what the session says (a "
             "wrong file, column or unit)";
  return c;
}

PlausibilityCheck check_reading_intervals(const LogFormat& log,
                                          const std::vector<ImuReading>& readings,
                                          const std::string& input) {
  std::vector<double> dt;
  dt.reserve(readings.size());
  for (std::size_t i = 1; i < readings.size(); ++i) dt.push_back(readings[i].t - readings[i - 1].t);
  // The table methods' remedy (the rate table's means) is not this record's.
  return check_interval_spread(
      interval_spread(dt), integrating_limits(PlausibilityLimits{}, log), input,
      "the table-free fit integrates its turns: use a log with a clean time column");
}

PlausibilityReport check_handheld(const LogFormat& log, const std::vector<ImuReading>& readings,
                                  const std::vector<Pose>& poses, double g, const RestLimits& l,
                                  const std::string& input) {
  std::vector<RestStatistics> rests;
  for (const Pose& p : poses)
    if (p.last >= p.first + 2 && p.last < readings.size())
      rests.push_back(rest_statistics(readings, p.first, p.last,
                                      "pose " + std::to_string(p.index) +
                                          " (t = " + number(p.t_start, 6) + " to " +
                                          number(p.t_end, 6) + " s)"));
  PlausibilityReport report = check_rests(rests, g, l, input);
  report.checks.push_back(check_same_files(log));
  if (report.checks.back().passed) report.checks.back() = check_same_signal(readings, l, input);
  report.checks.push_back(check_reading_intervals(log, readings, input));
  return report;
}

PlausibilityReport check_six_face(const LogFormat& log, const std::vector<PartStatistics>& parts,
                                  const FerrarisDeclaration& declared, double g,
                                  const RestLimits& l, const std::string& input) {
  std::vector<RestStatistics> rests;
  std::vector<ImuReading> turns;
  for (const auto& p : parts) {
    const bool face =
        std::find(declared.faces.begin(), declared.faces.end(), p.label) != declared.faces.end();
    if (!face) {
      turns.insert(turns.end(), p.readings.begin(), p.readings.end());
      continue;
    }
    if (p.count < 3 || !(p.duration > 0.0)) continue;
    RestStatistics r;
    r.where = "face '" + p.label + "'";
    r.f_b = p.mean_f;
    r.omega_ib_b = p.mean_rate;
    r.count = p.count;
    r.seconds = p.duration;
    r.dt = p.duration / static_cast<double>(p.count);
    r.accel_density = (p.var_f * r.dt).cwiseSqrt();
    r.gyro_density = (p.var_rate * r.dt).cwiseSqrt();
    rests.push_back(r);
  }
  PlausibilityReport report = check_rests(rests, g, l, input);
  report.checks.push_back(check_same_files(log));
  if (report.checks.back().passed) report.checks.back() = check_same_signal(turns, l, input);
  return report;
}

std::string record_statement(const LogFormat& log, std::size_t samples, double seconds) {
  const auto has_t = [](const std::vector<std::string>& cols) {
    return std::find(cols.begin(), cols.end(), "t") != cols.end();
  };
  const bool timed =
      log.native || log.kind == LogFormat::Kind::NovAtel ||
      (log.split() ? has_t(log.accel_columns) || has_t(log.gyro_columns) : has_t(log.columns));
  return "the record: " + std::to_string(samples) + " samples over " + number(seconds, 6) +
         " s at the declared " + number(log.rate_hz, 6) + " Hz" +
         (timed ? " (times from the log's time column)"
                : " (no time column: each sample is 1 / rate, so the length and every noise "
                  "density below follow from the declared rate)");
}

std::string rest_noise_cause(const LogFormat& log, double t0, double t1, double gyro_white,
                             double accel_white) {
  std::vector<ImuSample> samples;
  LogReader reader(log);
  reader.skip_bad_samples([](const BadSampleError&) {});
  for (ImuSample s; reader.next(s) && s.t <= t1;)
    if (s.t >= t0) samples.push_back(s);
  if (samples.size() < 3 || gyro_white <= 0.0 || accel_white <= 0.0) return "";
  const std::vector<ImuReading> readings = readings_from_samples(samples);
  const RestStatistics st = rest_statistics(readings, 0, readings.size() - 1, "");
  const Eigen::Vector3d g = st.gyro_density / gyro_white, a = st.accel_density / accel_white;
  if (std::max(g.maxCoeff(), a.maxCoeff()) <= kNoiseExcess) return "";
  std::string axes;
  for (int i = 0; i < 3; ++i) {
    const std::string axis(1, static_cast<char>('x' + i));
    if (g(i) > kNoiseExcess)
      axes += ", gyro " + axis + " " + number(st.gyro_density(i) / units::deg_per_sqrt_h, 3) +
              " deg/sqrt(h) (" + number(g(i), 3) + "x)";
    if (a(i) > kNoiseExcess)
      axes += ", accel " + axis + " " + number(st.accel_density(i) / units::ug_per_sqrt_hz, 4) +
              " ug/sqrt(Hz) (" + number(a(i), 3) + "x)";
  }
  return "at rest (t = " + number(t0, 4) + " to " + number(t1, 4) +
         " s) the outputs' noise density is beyond " + number(kNoiseExcess, 2) +
         " times the sensor profile's (" + number(gyro_white / units::deg_per_sqrt_h, 3) +
         " deg/sqrt(h), " + number(accel_white / units::ug_per_sqrt_hz, 4) +
         " ug/sqrt(Hz)): " + axes.substr(2) +
         ": the filter's noise model is not the data's (outputs jumping between levels, a "
         "profile for another unit or output rate, a filtered or decimated log)";
}

}  // namespace sinscal
