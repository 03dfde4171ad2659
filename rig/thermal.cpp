#include "rig/thermal.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "models/config.hpp"

namespace sinscal {

double ChamberAir::at(double time) const {
  if (t.empty()) return 0.0;
  if (time <= t.front()) return celsius.front();
  if (time >= t.back()) return celsius.back();
  const auto k = static_cast<std::size_t>(std::upper_bound(t.begin(), t.end(), time) - t.begin());
  const double w = (time - t[k - 1]) / (t[k] - t[k - 1]);
  return celsius[k - 1] + w * (celsius[k] - celsius[k - 1]);
}

SensorTemperature::SensorTemperature(ChamberAir air, double time_constant_s)
    : air_(std::move(air)), tau_(time_constant_s) {
  if (air_.t.empty() || air_.t.size() != air_.celsius.size())
    throw std::invalid_argument("a chamber's air needs knots with temperatures");
  if (!(tau_ >= 0.0)) throw std::invalid_argument("a sensor's time constant must not be negative");
  start_.resize(air_.t.size());
  start_[0] = air_.celsius[0];
  for (std::size_t k = 1; k < air_.t.size(); ++k) {
    const double h = air_.t[k] - air_.t[k - 1];
    if (!(h > 0.0)) throw std::invalid_argument("a chamber's knots must increase");
    if (tau_ == 0.0) {
      start_[k] = air_.celsius[k];
      continue;
    }
    // On a piece with air a + b s: T(s) = a + b (s - tau) + (T0 - a + b tau) exp(-s / tau).
    const double a = air_.celsius[k - 1], b = (air_.celsius[k] - a) / h;
    start_[k] = a + b * (h - tau_) + (start_[k - 1] - a + b * tau_) * std::exp(-h / tau_);
  }
}

void SensorTemperature::piece(double time, std::size_t& k, double& slope) const {
  if (time <= air_.t.front()) {
    k = 0;
    slope = 0.0;
    return;
  }
  k = static_cast<std::size_t>(std::upper_bound(air_.t.begin(), air_.t.end(), time) -
                               air_.t.begin()) -
      1;
  slope = k + 1 < air_.t.size()
              ? (air_.celsius[k + 1] - air_.celsius[k]) / (air_.t[k + 1] - air_.t[k])
              : 0.0;
}

double SensorTemperature::at(double time) const {
  std::size_t k = 0;
  double b = 0.0;
  piece(time, k, b);
  if (time <= air_.t.front()) return start_[0];
  const double s = time - air_.t[k], a = air_.celsius[k];
  if (tau_ == 0.0) return a + b * s;
  return a + b * (s - tau_) + (start_[k] - a + b * tau_) * std::exp(-s / tau_);
}

double SensorTemperature::rate(double time) const {
  std::size_t k = 0;
  double b = 0.0;
  piece(time, k, b);
  if (time <= air_.t.front()) return 0.0;
  if (tau_ == 0.0) return b;
  const double s = time - air_.t[k], a = air_.celsius[k];
  return b - (start_[k] - a + b * tau_) / tau_ * std::exp(-s / tau_);
}

double TemperatureRate::add(double t, double celsius) {
  const std::size_t newest = (head_ + count_ + kKept - 1) % kKept;
  if (count_ == 0 || t - t_[newest] >= window_ / (kKept - 1)) {
    const std::size_t at = (head_ + count_) % kKept;
    if (count_ == kKept)
      head_ = (head_ + 1) % kKept;
    else
      ++count_;
    t_[at] = t;
    c_[at] = celsius;
  }
  const double span = t - t_[head_];
  if (count_ < 2 || !(span >= 0.1 * window_)) return 0.0;
  return (celsius - c_[head_]) / span;
}

namespace {

// Knots of the air in program time: from `start` at 0 to `to` at the air's rate.
void move_air(ChamberAir& air, double to, double rate) {
  const double from = air.celsius.back();
  if (to == from) return;
  air.t.push_back(air.t.back() + std::abs(to - from) / rate);
  air.celsius.push_back(to);
}

ChamberAir shifted(ChamberAir air, double by) {
  for (double& t : air.t) t -= by;
  return air;
}

}  // namespace

ChamberAir ChamberProgram::soak_air(std::size_t k, double plan_s) const {
  if (k >= soaks_c.size()) throw std::out_of_range("no such soak");
  ChamberAir air{{0.0}, {start_c}};
  double plan_start = 0.0;
  for (std::size_t j = 0; j <= k; ++j) {
    if (j > 0) {  // the previous soak's plan: the air holds
      air.t.push_back(plan_start + plan_s);
      air.celsius.push_back(soaks_c[j - 1]);
    }
    move_air(air, soaks_c[j], air_rate_c_per_s);
    plan_start = air.t.back() + settle_s;
  }
  return shifted(air, plan_start);
}

ChamberAir ChamberProgram::ramp_air() const {
  ChamberAir air{{0.0}, {start_c}};
  move_air(air, from_c, air_rate_c_per_s);
  const double plan_start = air.t.back() + settle_s;
  air.t.push_back(plan_start);
  air.celsius.push_back(from_c);
  air.t.push_back(plan_start + ramp_duration());
  air.celsius.push_back(to_c);
  return shifted(air, plan_start);
}

ChamberProgram ChamberProgram::load(const std::string& path) {
  const IniFile ini(path);
  ChamberProgram c;
  c.path = path;
  ini.check_keys("chamber", {"type", "start", "soaks", "settle", "from", "to", "rate", "air_rate"});
  for (const auto& key : ini.keys())
    if (key.rfind("chamber.", 0) != 0) throw ConfigError(ini.where(key) + "unknown section");
  const std::vector<UnitToken> celsius = {{"C", 1.0}};
  auto temperature = [&](const std::string& key, double fallback) {
    if (!ini.has(key)) return fallback;
    const double v = ini.get_quantities(key, celsius, "C", 1).front();
    if (!(v >= -60.0 && v <= 130.0))
      throw ConfigError(ini.where(key) + "expected -60 ... 130 C, where sensors work");
    return v;
  };
  auto per_minute = [&](const std::string& key, double fallback) {
    if (!ini.has(key)) return fallback;
    const double v =
        ini.get_quantities(key, {{"C/min", 1.0 / 60.0}, {"C/s", 1.0}, {"C/h", 1.0 / 3600.0}},
                           "C/min", 1)
            .front();
    if (!(v > 0.0 && v <= 10.0))
      throw ConfigError(ini.where(key) + "expected a rate above 0 and at most 10 C/s");
    return v;
  };
  const std::string type = ini.get_string("chamber.type");
  c.start_c = temperature("chamber.start", 25.0);
  c.settle_s = ini.has("chamber.settle")
                   ? ini.get_quantity("chamber.settle", QuantityKind::Time, "s")
                   : 3600.0;
  if (!(c.settle_s >= 0.0)) throw ConfigError(ini.where("chamber.settle") + "must not be negative");
  c.air_rate_c_per_s = per_minute("chamber.air_rate", c.air_rate_c_per_s);
  if (type == "soaks") {
    c.type = Type::Soaks;
    if (!ini.has("chamber.soaks"))
      throw ConfigError(path + ": [chamber] type = soaks needs 'soaks'");
    c.soaks_c = ini.get_quantities("chamber.soaks", celsius, "C");
    for (double v : c.soaks_c)
      if (!(v >= -60.0 && v <= 130.0))
        throw ConfigError(ini.where("chamber.soaks") +
                          "expected -60 ... 130 C, where sensors work");
    for (const char* k : {"chamber.from", "chamber.to", "chamber.rate"})
      if (ini.has(k)) throw ConfigError(ini.where(k) + "a key of type = ramp in type = soaks");
  } else if (type == "ramp") {
    c.type = Type::Ramp;
    for (const char* k : {"chamber.from", "chamber.to", "chamber.rate"})
      if (!ini.has(k)) throw ConfigError(path + ": [chamber] type = ramp needs '" + (k + 8) + "'");
    if (ini.has("chamber.soaks"))
      throw ConfigError(ini.where("chamber.soaks") + "a key of type = soaks in type = ramp");
    c.from_c = temperature("chamber.from", 0.0);
    c.to_c = temperature("chamber.to", 0.0);
    c.rate_c_per_s = per_minute("chamber.rate", 0.0);
    if (c.from_c == c.to_c)
      throw ConfigError(ini.where("chamber.to") + "a ramp needs 'to' different from 'from'");
  } else {
    throw ConfigError(ini.where("chamber.type") + "expected 'soaks' or 'ramp', got '" + type + "'");
  }
  return c;
}

}  // namespace sinscal
