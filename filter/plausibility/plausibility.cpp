#include "filter/plausibility/plausibility.hpp"

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/normal.hpp>
#include <cmath>
#include <sstream>

#include "filter/closed_form/closed_form.hpp"
#include "filter/installation/installation.hpp"
#include "filter/kalman/kalman_calibrator.hpp"
#include "filter/kalman/pass_linearization.hpp"
#include "filter/rate_table/rate_table.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "rig/session.hpp"

namespace sinscal {

namespace {

// Fraction of each end of a dwell left out of its mean (the table settling, timing slack).
constexpr double kDwellEdgeFraction = 0.1;
// Floors of the bounds: a table may sit a few degrees off level or off the plan's heading, and
// the IMU on its platform up to 2 deg off (docs/conventions.md).
constexpr double kMinDirection = 5.0 * units::deg;
// What the calibration admits (a base 3 sigma off level, the largest mounting) must pass it.
static_assert(kAdmittedMounting + 3.0 * kBaseLevelPriorSigma <= kMinDirection * (1.0 + 1e-12),
              "the gate's gravity-direction floor refuses installations the calibration admits");
constexpr double kMinSpecificForce = 1e-3 * units::g0;
constexpr double kMinRateFraction = 0.05;  // of the Earth rate
// A ratio of measured to expected magnitude this close to a unit factor names the unit.
constexpr double kFactorTolerance = 0.05;

double largest(const SensorProfile& p, const std::string& family) {
  const auto it = p.ranges.find(family);
  if (it == p.ranges.end()) return 0.0;
  return std::max(std::abs(it->second.lo), std::abs(it->second.hi));
}

// The likely cause of a magnitude `ratio` times what it should be: a unit mistaken for another.
std::string unit_cause(double ratio, double dt, bool gyro) {
  for (const auto& f : unit_factors(gyro, dt))
    if (std::abs(std::log(ratio / f.value)) < kFactorTolerance) return f.cause;
  if (ratio < 1e-3) return "no signal (a constant or zero channel?)";
  if (gyro && ratio > 20.0)
    return "the unit turns during the plan's dwell: the plan's timing (or the session's "
           "time_offset) does not match the log";
  return "a wrong unit or scale, or a sensor profile that does not match the unit";
}

std::string number(double v, int precision = 4) { return plausibility_number(v, precision); }

// Saturation: the first sample at the profile's range names its line.
class SaturationWatch {
 public:
  SaturationWatch(const PlausibilityLimits& l, const std::string& input) : l_(l), input_(input) {}
  void see(const ImuSample& s, std::size_t line) {
    if (!(s.dt > 0.0)) return;
    const double f = (s.dv_b / s.dt).cwiseAbs().maxCoeff();
    const double w = (s.dtheta_b / s.dt).cwiseAbs().maxCoeff();
    const bool accel = l_.accel_range > 0.0 && f >= (1.0 - 1e-6) * l_.accel_range;
    const bool gyro = l_.gyro_range > 0.0 && w >= (1.0 - 1e-6) * l_.gyro_range;
    if (!accel && !gyro) return;
    if (count_++ > 0) return;
    std::ostringstream m;
    m << input_ << ":" << line << ": the " << (accel ? "accelerometers" : "gyros")
      << " are saturated (|" << (accel ? "f" : "omega")
      << "| = " << number(accel ? f : w / units::deg_per_s) << (accel ? " m/s^2" : " deg/s")
      << " at the sensor profile's range "
      << number(accel ? l_.accel_range : l_.gyro_range / units::deg_per_s)
      << (accel ? " m/s^2" : " deg/s") << ")";
    first_ = m.str();
  }
  PlausibilityCheck check() const {
    PlausibilityCheck c{"saturation", count_ == 0, ""};
    if (count_ > 0)
      c.detail = first_ + "; " + std::to_string(count_) +
                 " samples at the range: clipped data cannot be calibrated";
    return c;
  }

 private:
  const PlausibilityLimits& l_;
  std::string input_;
  std::size_t count_ = 0;
  std::string first_;
};

// The sample intervals as a histogram of interval / first interval in bins of 0.1 % (constant
// memory over any log; the reader refuses intervals outside 0.5 to 1.5 nominal, bridged skips
// aside, so the range of 0 to 4 first intervals holds them).
class IntervalWatch {
 public:
  void see(const ImuSample& s, std::size_t count) {
    if (count < 2 || !(s.dt > 0.0)) return;  // the first sample's interval is the nominal one
    if (dt0_ == 0.0) dt0_ = s.dt;
    const double r = s.dt / dt0_ * kBinsPerInterval;
    const auto b = static_cast<std::size_t>(std::min(r, static_cast<double>(kBins - 1)));
    ++bins_[b];
    sums_[b] += r;
    ++n_;
  }
  IntervalSpread spread() const {
    IntervalSpread out;
    out.intervals = n_;
    if (n_ == 0) return out;
    out.low = quantile(0.01);
    out.median = quantile(0.5);
    out.high = quantile(0.99);
    out.resolution = grid_step();
    return out;
  }

 private:
  static constexpr std::size_t kBins = 4000;
  static constexpr double kBinsPerInterval = 1000.0;
  double quantile(double p) const {
    const double target = p * static_cast<double>(n_);
    std::size_t sum = 0, b = 0;
    for (; b + 1 < kBins; ++b) {
      sum += bins_[b];
      if (static_cast<double>(sum) >= target) break;
    }
    return (static_cast<double>(b) + 0.5) / kBinsPerInterval * dt0_;
  }
  // The intervals' grid: the occupied bins (each at least 0.1 % of the intervals) fall into runs
  // of neighbours; separate runs (an empty bin between them) are values of a quantized clock, and
  // the smallest distance between runs' centres is its resolution. One run: no grid.
  double grid_step() const {
    std::vector<double> centres;  // each run's mean interval, in bins
    double sum = 0.0;
    std::size_t count = 0;
    for (std::size_t b = 0; b <= kBins; ++b) {
      const bool occupied = b < kBins && bins_[b] * 1000 >= n_;
      if (occupied) {
        sum += sums_[b];
        count += bins_[b];
      } else if (count > 0) {
        centres.push_back(sum / static_cast<double>(count));
        sum = 0.0;
        count = 0;
      }
    }
    double step = 0.0;
    for (std::size_t i = 1; i < centres.size(); ++i) {
      const double d = centres[i] - centres[i - 1];
      if (step == 0.0 || d < step) step = d;
    }
    // A clock's grid holds every value as a whole number of steps (within a tenth of a step; a
    // run holds one value of a grid, so its mean is that value): two irregular values, 98.4 and
    // 101.6 ms say, are not a grid of 3.2 ms.
    for (const double c : centres)
      if (std::abs(c - step * std::round(c / step)) > 0.1 * step) return 0.0;
    return step / kBinsPerInterval * dt0_;
  }
  double dt0_ = 0.0;
  std::vector<std::size_t> bins_ = std::vector<std::size_t>(kBins, 0);
  std::vector<double> sums_ = std::vector<double>(kBins, 0.0);  // of interval / first, in bins
  std::size_t n_ = 0;
};

// Adds a sample's temperatures to a dwell's sums (the first sample also starts its rate).
void add_temperature(DwellMean& m, const ImuSample& s, double& t_first, double& T_first) {
  if (!s.has_temperature) return;
  if (!m.has_temperature) {
    t_first = s.t;
    T_first = s.gyro_temperature_c;
  } else if (s.t > t_first) {
    m.gyro_temperature_rate = (s.gyro_temperature_c - T_first) / (s.t - t_first);
  }
  m.has_temperature = true;
  m.accel_temperature_c += s.accel_temperature_c;
  m.gyro_temperature_c += s.gyro_temperature_c;
}

// One pass over the log: dwell means, saturation and the sample intervals.
std::vector<DwellMean> read_means(LogReader& reader, const PlanTimeline& timeline,
                                  double time_offset, bool dwell_checks, SaturationWatch& sat,
                                  IntervalWatch& intervals, double& dt) {
  std::vector<DwellMean> means;
  for (const auto& d : timeline.dwells) {
    DwellMean m;  // sums start at zero (the members' initializers)
    m.dwell = d;
    means.push_back(m);
  }
  ImuSample s;
  std::size_t next = 0;
  double t_first = 0.0, T_first = 0.0;  // the current dwell's first temperature
  // A log the reader refuses part of the way is the estimators' to report (with their results up
  // to there): the gate judges what it could read.
  auto next_sample = [&]() {
    try {
      return reader.next(s);
    } catch (const LogError&) {
      return false;
    }
  };
  while (next_sample()) {
    sat.see(s, reader.line());
    intervals.see(s, reader.count());
    if (dt == 0.0) dt = s.dt;
    if (!dwell_checks) continue;
    const double t = s.t - time_offset;
    while (next < means.size()) {
      const PlanDwell& d = means[next].dwell;
      const double edge = kDwellEdgeFraction * (d.t_end - d.t_start);
      if (t - s.dt >= d.t_start + edge && t <= d.t_end - edge) {
        means[next].omega_ib_b += s.dtheta_b;
        means[next].f_b += s.dv_b;
        means[next].seconds += s.dt;
        ++means[next].samples;
        add_temperature(means[next], s, t_first, T_first);
        break;
      }
      if (t <= d.t_end - edge) break;  // before this dwell's middle
      ++next;
    }
  }
  for (auto& m : means)
    if (m.seconds > 0.0) {
      m.f_b /= m.seconds;
      m.omega_ib_b /= m.seconds;
      m.accel_temperature_c /= static_cast<double>(m.samples);
      m.gyro_temperature_c /= static_cast<double>(m.samples);
    }
  return means;
}

using Findings = PlausibilityFindings;  // each failing dwell's description

std::string dwell_name(const PlanDwell& d) {
  return "dwell " + std::to_string(d.index) + (d.label.empty() ? "" : " (" + d.label + ")");
}

}  // namespace

std::vector<UnitFactor> unit_factors(bool gyro, double dt) {
  std::vector<UnitFactor> factors;
  if (gyro)
    factors = {{units::deg, "values in rad declared as deg"},
               {1.0 / units::deg, "values in deg declared as rad"},
               {3600.0, "values per hour declared per second"},
               {1.0 / 3600.0, "values per second declared per hour"}};
  else
    factors = {{1000.0, "values in mm/s (or mm/s^2) declared as m/s"},
               {1e-3, "values in m/s declared as mm/s"},
               {1.0 / units::g0, "values in g declared as m/s^2 (or m/s)"},
               {units::g0, "values in m/s^2 declared as g"}};
  if (dt > 0.0) {
    factors.push_back({1.0 / dt, "rates declared as increments (or the wrong rate)"});
    factors.push_back({dt, "increments declared as rates (or the wrong rate)"});
  }
  return factors;
}

PlausibilityLimits PlausibilityLimits::from_profile(const SensorProfile* p) {
  PlausibilityLimits l;
  if (!p) return l;
  const double g = units::g0, Omega = Earth::wgs84().rate();
  const double ab = largest(*p, "accel.bias"), ak = largest(*p, "accel.scale"),
               am = largest(*p, "accel.misalignment"), k2 = largest(*p, "accel.k2");
  const double gb = largest(*p, "gyro.bias"), gk = largest(*p, "gyro.scale"),
               gm = largest(*p, "gyro.misalignment"), gs = largest(*p, "gyro.g_sensitivity");
  l.specific_force = std::max(
      kMinSpecificForce,
      3.0 * (std::sqrt(3.0) * (ab + p->noise.accel.bias_instability) + (ak + am) * g + k2 * g * g));
  l.check_rate = p->ranges.count("gyro.bias") > 0;
  l.rate = std::max(
      kMinRateFraction * Omega,
      3.0 * (std::sqrt(3.0) * (gb + p->noise.gyro.bias_instability + gs * g) + (gk + gm) * Omega));
  l.direction = std::max(kMinDirection, 3.0 * (am + ak + ab / g));
  l.reference_temperature_c = p->reference_temperature_c;
  for (int d = 1; d <= 3; ++d) {
    const auto of = [&](const std::string& family) {
      return largest(*p, family + "_temp" + std::to_string(d));
    };
    const auto k = static_cast<std::size_t>(d - 1);
    l.specific_force_thermal[k] = 3.0 * (std::sqrt(3.0) * of("accel.bias") +
                                         (of("accel.scale") + of("accel.misalignment")) * g);
    l.rate_thermal[k] = 3.0 * (std::sqrt(3.0) * of("gyro.bias") +
                               (of("gyro.scale") + of("gyro.misalignment")) * Omega);
  }
  l.rate_per_temperature_rate = 3.0 * std::sqrt(3.0) * largest(*p, "gyro.bias_temp_rate");
  l.accel_range = p->accel_range;
  l.gyro_range = p->gyro_range;
  l.accel_white = p->noise.accel.white;
  l.gyro_white = p->noise.gyro.white;
  return l;
}

double PlausibilityLimits::thermal_part(const std::array<double, 3>& per_degree, double dT) {
  double out = 0.0;
  for (std::size_t k = 0; k < per_degree.size(); ++k)
    out += per_degree[k] * std::pow(std::abs(dT), static_cast<double>(k + 1));
  return out;
}

std::string plausibility_number(double v, int precision) {
  std::ostringstream s;
  s.precision(precision);
  s << v;
  return s.str();
}

PlausibilityCheck PlausibilityFindings::check(const std::string& name) const {
  PlausibilityCheck c{name, lines.empty(), ""};
  for (std::size_t i = 0; i < lines.size() && i < 3; ++i)
    c.detail += (i > 0 ? "; " : "") + lines[i];
  if (lines.size() > 3) c.detail += "; and " + std::to_string(lines.size() - 3) + " more " + items;
  return c;
}

bool PlausibilityReport::passed() const {
  return std::all_of(checks.begin(), checks.end(),
                     [](const PlausibilityCheck& c) { return c.passed; });
}

std::string PlausibilityReport::failures() const {
  std::string out;
  for (const auto& c : checks)
    if (!c.passed) out += (out.empty() ? "" : "\n") + c.name + ": " + c.detail;
  return out;
}

PlausibilityReport check_plausibility(LogReader& reader, const std::string& input,
                                      const PlanTimeline& timeline, const Site& site,
                                      double time_offset, const PlausibilityLimits& l,
                                      bool dwell_checks) {
  SaturationWatch sat(l, input);
  IntervalWatch intervals;
  double dt = 0.0;
  const std::vector<DwellMean> means =
      read_means(reader, timeline, time_offset, dwell_checks, sat, intervals, dt);
  PlausibilityReport report;
  report.checks.push_back(sat.check());
  if (l.max_interval_spread > 0.0)
    report.checks.push_back(check_interval_spread(intervals.spread(), l, input));
  if (!dwell_checks) return report;
  const Eigen::Vector3d f_n = -Earth::wgs84().gravity_n(site.lat_rad, site.h_m);
  const double g = f_n.norm(), Omega = Earth::wgs84().rate();
  Findings magnitude, rate, direction;
  for (const auto& m : means) {
    const std::string where = input + ": " + dwell_name(m.dwell);
    if (m.samples == 0) continue;  // the log ends early: the estimators name the mismatch
    const double f = m.f_b.norm();
    const double dTa = m.has_temperature ? m.accel_temperature_c - l.reference_temperature_c : 0;
    const double dTg = m.has_temperature ? m.gyro_temperature_c - l.reference_temperature_c : 0;
    const double f_tol = l.specific_force + 5.0 * l.accel_white / std::sqrt(m.seconds) +
                         PlausibilityLimits::thermal_part(l.specific_force_thermal, dTa);
    if (std::abs(f - g) > f_tol)
      magnitude.add(where + ": |f| = " + number(f) + " m/s^2 at rest where gravity is " +
                    number(g) + " (" + number(f / g) + " times): " + unit_cause(f / g, dt, false));
    const double w = m.omega_ib_b.norm();
    const double w_tol = l.rate + 5.0 * l.gyro_white / std::sqrt(m.seconds) +
                         PlausibilityLimits::thermal_part(l.rate_thermal, dTg) +
                         l.rate_per_temperature_rate * std::abs(m.gyro_temperature_rate);
    if (l.check_rate && std::abs(w - Omega) > w_tol)
      rate.add(where + ": |omega| = " + number(w / units::deg_per_h) +
               " deg/h at rest where the Earth rate is " + number(Omega / units::deg_per_h) +
               " deg/h (bound " + number(w_tol / units::deg_per_h, 3) + " from the profile" +
               (m.has_temperature ? " at " + number(m.gyro_temperature_c, 3) + " C" : "") +
               "): " + unit_cause(w / Omega, dt, true));
    const Eigen::Vector3d expected = m.dwell.C_b_n_known.transpose() * f_n;
    const double angle = std::atan2(expected.cross(m.f_b).norm(), expected.dot(m.f_b));
    if (f > 0.0 && angle > l.direction)
      direction.add(where + ": gravity measured " + number(angle / units::deg, 3) +
                    " deg from where the plan's attitude puts it (bound " +
                    number(l.direction / units::deg, 2) +
                    " deg): a wrong axis map or sign, or the wrong plan");
  }
  report.checks.push_back(magnitude.check("gravity magnitude"));
  if (l.check_rate) report.checks.push_back(rate.check("Earth rate"));
  report.checks.push_back(direction.check("gravity direction"));
  return report;
}

IntervalSpread interval_spread(const std::vector<double>& intervals) {
  IntervalWatch watch;
  ImuSample s;
  std::size_t count = 1;
  for (const double dt : intervals) {
    if (!(dt > 0.0)) continue;
    s.dt = dt;
    watch.see(s, ++count);
  }
  return watch.spread();
}

PlausibilityLimits integrating_limits(PlausibilityLimits l, const LogFormat& log) {
  l.max_interval_spread = PlausibilityLimits::kIntegratingIntervalSpread;
  const bool timed = log.kind == LogFormat::Kind::NovAtel ||
                     std::count(log.columns.begin(), log.columns.end(), "t") > 0;
  l.assumed_rate_hz = timed ? 0.0 : log.rate_hz;
  return l;
}

PlausibilityCheck check_interval_spread(const IntervalSpread& s, const PlausibilityLimits& l,
                                        const std::string& input, const std::string& remedy) {
  PlausibilityCheck c{"sample intervals", true, ""};
  if (l.assumed_rate_hz > 0.0) {
    c.detail = input + ": no time column: the times are assumed from the session's rate of " +
               number(l.assumed_rate_hz) + " Hz (its sample intervals cannot be checked)";
    return c;
  }
  if (s.intervals == 0) return c;
  const double ms = 1e-3;
  c.detail = input + ": sample intervals " + number(s.low / ms, 3) + "-" + number(s.high / ms, 3) +
             " ms (median " + number(s.median / ms, 3) + " ms, spread " +
             number(100.0 * s.spread(), 2) + " %";
  if (s.resolution > 0.0)
    c.detail += "; timestamps in steps of " + number(s.resolution / ms, 3) + " ms, jitter beyond " +
                "them " + number(100.0 * s.jitter(), 2) + " %";
  c.passed = !(s.jitter() > l.max_interval_spread);
  if (c.passed) {
    c.detail += ")";
    return c;
  }
  c.detail += ", tolerated " + number(100.0 * l.max_interval_spread, 2) +
              " %): the integrating methods need a steady rate; " + remedy;
  return c;
}

PlausibilityReport check_plausibility(const Session& session, const PlausibilityLimits& limits,
                                      bool dwell_checks) {
  LogReader reader(session.log);
  return check_plausibility(reader, session.log.file, PlanTimeline::of(session.plan, session.site),
                            session.site, session.time_offset, limits, dwell_checks);
}

void enforce(const PlausibilityReport& report, bool force) {
  if (!report.passed() && !force)
    throw PlausibilityError("the data fail the plausibility gate (--force runs anyway):\n" +
                            report.failures());
}

PlausibilityCheck check_stage1_fit(const std::vector<EquivalentInputs>& stage1,
                                   const PlausibilityLimits& l, const std::string& input) {
  Findings bad;
  for (const auto& e : stage1)
    if (!(e.chi2_per_dof <= l.max_stage1_chi2_per_dof))
      bad.add(input + ": " + dwell_name(e.dwell) + ": stage-1 chi2 per dof " +
              number(e.chi2_per_dof) + " (expected about 1, bound " +
              number(l.max_stage1_chi2_per_dof) +
              "): the navigation errors do not follow the model (the data or the plan are not "
              "what the session says, or the noise densities are wrong)");
  return bad.check("stage-1 fit");
}

namespace {
// The accelerometers' part of the linear range: the velocity a dwell's inputs build up.
PlausibilityCheck speed_range(const ClosedFormReport& r, const std::string& input) {
  PlausibilityCheck c{"closed-form linear range", true, ""};
  if (!(r.largest_speed > r.linear_speed)) return c;
  c.passed = false;
  c.detail = input + ": dwell " + r.largest_speed_dwell +
             ": the accelerometers' equivalent inputs drive the navigator's velocity to " +
             number(r.largest_speed, 3) + " m/s within the dwell, beyond stage 1's linear range " +
             "of " + number(r.linear_speed, 3) +
             " m/s (there its neglected v^2/R reaches the accelerometer inputs' sigma)" +
             (r.removed_accel ? ", after the accelerometers' bias, scale and misalignment were "
                                "removed: an accelerometer error the closed form does not model"
                              : ": the accelerometer errors (bias, scale, misalignment) were not "
                                "removed (not all determined, or the gyros beyond their range)") +
             "; the Kalman filter (--method kf) does not linearize over a dwell";
  return c;
}
}  // namespace

namespace {
// The share beyond which a run's last pass is refused: its estimate may be off by a sigma of the
// linearization's own (the automatic passes stop at kLinearizationShare, a tenth).
constexpr double kLinearizationRefusal = 1.0;

// What to run instead: a streamed log is read once (several passes need the file); automatic
// passes that ran out need a larger fixed count; else either.
std::string kf_linearization_remedy(int passes, bool streamed) {
  if (streamed) return "several passes need the log as a file, not --stream (then --passes 0)";
  if (passes == 0)
    return "the automatic passes stopped at " + std::to_string(kMaxAutomaticPasses) +
           ": run more (--passes N, N > " + std::to_string(kMaxAutomaticPasses) +
           "), each about the previous estimate";
  return "run the automatic passes (--passes 0) or more passes (--passes N), each about the "
         "previous estimate";
}
}  // namespace

PlausibilityCheck check_kf_linearization(const PassLinearization& last, int passes, int passes_run,
                                         const std::string& input, bool streamed) {
  PlausibilityCheck c{"kf linear range", true, ""};
  if (!(last.share > kLinearizationRefusal)) return c;
  c.passed = false;
  c.detail = input + ": the filter's pass " + std::to_string(passes_run) + " (" +
             (passes == 0 ? "automatic passes, at most " + std::to_string(kMaxAutomaticPasses)
                          : "--passes " + std::to_string(passes)) +
             ") ran far from the coefficients it linearized about: its neglected second-order " +
             "term reaches " + last.text() + ", beyond " + number(kLinearizationRefusal, 2) +
             " sigma: the sensor's errors are too large for one linearization (consumer MEMS); " +
             kf_linearization_remedy(passes, streamed);
  return c;
}

PlausibilityCheck check_linear_range(const ClosedFormReport& r, const std::string& input) {
  PlausibilityCheck c{"closed-form linear range", true, ""};
  if (!(r.largest_turn > r.linear_turn)) return speed_range(r, input);
  const bool removed = r.linearizations > 1;
  const Eigen::Vector3d b = (removed ? r.removed_gyro_bias : r.first_gyro_bias) / units::deg_per_s;
  c.passed = false;
  c.detail = input + ": dwell " + r.largest_turn_dwell + ": the gyros turn the attitude by " +
             number(r.largest_turn / units::deg, 3) + " deg within the dwell, beyond stage 1's " +
             "linear range of " + number(r.linear_turn / units::deg, 3) +
             " deg (there its neglected g phi^2/2 reaches the accelerometer inputs' sigma); the " +
             "gyro biases are " + number(b.x(), 3) + ", " + number(b.y(), 3) + ", " +
             number(b.z(), 3) + " deg/s" +
             (removed ? ", removed in " + std::to_string(r.linearizations - 1) +
                            " relinearization(s): what still turns the attitude is a gyro error "
                            "the closed form does not model (g-sensitivity, bias instability)"
                      : ": the gyro biases turn the attitude") +
             "; the Kalman filter (--method kf) models them";
  return c;
}

// The chi2 per dof a fit of `dof` degrees of freedom exceeds with the probability of a normal
// variable beyond `z` sigma.
double chi2_per_dof_bound(int dof, double z) {
  const double tail =
      boost::math::cdf(boost::math::complement(boost::math::normal_distribution<double>(), z));
  return boost::math::quantile(
             boost::math::complement(boost::math::chi_squared_distribution<double>(dof), tail)) /
         dof;
}

PlausibilityCheck check_stage2_fit(const ClosedFormReport& r, const PlausibilityLimits& l,
                                   const std::string& input) {
  PlausibilityCheck c{"stage-2 fit", true, ""};
  const Stage2Result& s2 = r.stage2;
  if (s2.dof <= 0) return c;
  const double bound = chi2_per_dof_bound(s2.dof, l.stage2_fit_z);
  if (s2.chi2_per_dof <= bound) return c;
  c.passed = false;
  c.detail = input + ": stage-2 chi2 per dof " + number(s2.chi2_per_dof, 3) + " over " +
             std::to_string(s2.dof) + " dof (bound " + number(bound, 3) + ", its " +
             number(l.stage2_fit_z, 2) +
             "-sigma quantile): the dwells' equivalent inputs do not fit one set of the model's "
             "coefficients (errors the model lacks, a stage 1 beyond its linear range, or noise "
             "densities too small)";
  return c;
}

std::vector<std::string> failed_rate_table_triads(const RateTableResult& r,
                                                  const PlausibilityLimits& l) {
  std::vector<std::string> out;
  for (const auto& t : r.triad_fits)
    if (t.dof > 0 && t.chi2 / t.dof > chi2_per_dof_bound(t.dof, l.stage2_fit_z))
      out.push_back(t.triad);
  return out;
}

PlausibilityCheck check_rate_table_fit(const RateTableResult& r, const PlausibilityLimits& l,
                                       const std::string& input) {
  Findings bad;
  bad.items = "triads";
  const std::vector<std::string> failed = failed_rate_table_triads(r, l);
  for (const auto& t : r.triad_fits) {
    if (std::find(failed.begin(), failed.end(), t.triad) == failed.end()) continue;
    const double per_dof = t.chi2 / t.dof, bound = chi2_per_dof_bound(t.dof, l.stage2_fit_z);
    bad.add(input + ": the " + (t.triad == "gyro" ? "gyros" : "accelerometers") +
            "' chi2 per dof " + number(per_dof, 3) + " over " + std::to_string(t.dof) +
            " dof (bound " + number(bound, 3) + ", its " + number(l.stage2_fit_z, 2) +
            "-sigma quantile): the segments' means do not fit the model (a segment not at its "
            "commanded rate, a gyro offset while turning the model lacks (across a turn's axis "
            "and depending on its direction: --cross-asymmetry models it), or noise densities "
            "too small)");
  }
  return bad.check("rate-table fit");
}

}  // namespace sinscal
