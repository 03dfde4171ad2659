// Effects outside the family catalog, injected into a simulated session's log by test code (the
// simulator and the estimators never see them): each sample's specific force and rate, read back
// from the log's increments, get an extra term, and the log is written again. Shared by the
// out-of-catalog tests and their Monte Carlo matrix (tests/test_diagnosis_open_world.cpp).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <functional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "diagnosis_cases.hpp"
#include "models/units.hpp"
#include "rig/timeline.hpp"

namespace sinscal::test {

/// An extra term on one sample: specific force f_b (m/s^2) and rate omega_ib_b (rad/s) at log
/// time t (s), changed in place.
using ExtraTerm = std::function<void(double t, Eigen::Vector3d& f_b, Eigen::Vector3d& omega_ib_b)>;

/// Rewrites the native log `path` (increments over 1/rate_hz) with `term` added to each sample.
inline void inject_into_log(const std::string& path, double rate_hz, const ExtraTerm& term) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::ostringstream out;
  std::string line;
  const double dt = 1.0 / rate_hz;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#' || line[0] == 't') {
      out << line << "\n";
      continue;
    }
    std::vector<std::string> fields;
    std::stringstream parts(line);
    std::string field;
    while (std::getline(parts, field, ',')) fields.push_back(field);
    if (fields.size() < 7) throw std::runtime_error(path + ": short row " + line);
    const double t = std::stod(fields[0]);
    Eigen::Vector3d w, f;
    for (int i = 0; i < 3; ++i) {
      w(i) = std::stod(fields[static_cast<std::size_t>(1 + i)]) / dt;
      f(i) = std::stod(fields[static_cast<std::size_t>(4 + i)]) / dt;
    }
    term(t, f, w);
    char b[64];
    out << fields[0];
    for (int i = 0; i < 3; ++i) {
      std::snprintf(b, sizeof b, ",%.17g", w(i) * dt);
      out << b;
    }
    for (int i = 0; i < 3; ++i) {
      std::snprintf(b, sizeof b, ",%.17g", f(i) * dt);
      out << b;
    }
    for (std::size_t k = 7; k < fields.size(); ++k) out << "," << fields[k];
    out << "\n";
  }
  in.close();
  write_file(path, out.str());
}

/// One out-of-catalog effect: its name, the term, and the library term that should explain it
/// (empty: none expected).
struct OpenWorldEffect {
  std::string name;
  ExtraTerm term;
  /// The library term that explains it on the dwells (filter/diagnosis/term_library.hpp): sensor,
  /// axis, the formula's beginning and the value in the term's unit; sensor empty: none.
  std::string sensor;
  int axis = 0;
  std::string formula;
  double value = 0.0;
};

constexpr double kG = units::g0;

/// Effects the library does not anticipate (issue 33's "cases that these do not anticipate"; no
/// library term is theirs): the gyro scale factor stepping half-way, a gyro cross-rate product
/// omega_x omega_y (zero on plans whose turns are about one body axis), a gyro bias that follows
/// the direction of the table's last turn (hysteresis in the rate).
inline void append_unanticipated_effects(std::vector<OpenWorldEffect>& e, double mid_s) {
  const double dph = units::deg_per_h;
  e.push_back({"gyro scale += 100 ppm (3 axes) at mid-session",
               [mid_s](double t, auto&, auto& w) {
                 if (t > mid_s) w *= 1.0 + 100e-6;
               },
               "", 0, "", 0.0});
  e.push_back({"gyro z += 3000 ppm/(rad/s) omega_x omega_y",
               [](double, auto&, auto& w) { w(2) += 3000e-6 * w(0) * w(1); }, "", 0, "", 0.0});
  // The sign of the last sample turning faster than 1 deg/s (the sum of its body rates).
  e.push_back({"gyro x bias 0.1 deg/h times the last turn's direction",
               [dph, last = 1.0](double, auto&, auto& w) mutable {
                 if (w.norm() > units::deg_per_s) last = w.sum() >= 0.0 ? 1.0 : -1.0;
                 w(0) += 0.1 * dph * last;
               },
               "", 0, "", 0.0});
}

/// The jitter's random sequence for the session of `seed`: its own per seed (a cell of 30 seeds is
/// 30 jitter realizations, not one under 30 noise draws), deterministic, and apart from the
/// simulator's noise of the same seed (a second word in the seed sequence).
inline std::mt19937_64 jitter_generator(std::uint64_t seed) {
  std::seed_seq seq{static_cast<std::uint32_t>(seed), static_cast<std::uint32_t>(seed >> 32U),
                    0x6a177e5U};
  return std::mt19937_64(seq);
}

/// More effects the library does not anticipate (issue 33, session 43): a gyro that saturates
/// just below the table's turn rate (rot19's turns peak at 11.46 deg/s), sample-timing jitter (each
/// increment spans dt (1 + e), e white, 100 ppm RMS: 5 us at 20 Hz; drawn per session `seed`), a
/// gyro scale factor that depends on the specific force across it, and a gyro bias transient (30
/// s, no temperature) starting at two thirds of mid-session.
inline void append_more_unanticipated_effects(std::vector<OpenWorldEffect>& e, double mid_s,
                                              std::uint64_t seed) {
  const double dph = units::deg_per_h, dps = units::deg_per_s;
  e.push_back({"gyro y clipped at 11.4 deg/s",
               [dps](double, auto&, auto& w) { w(1) = std::clamp(w(1), -11.4 * dps, 11.4 * dps); },
               "", 0, "", 0.0});
  e.push_back({"sample timing jitter 100 ppm RMS",
               [rng = jitter_generator(seed), n = std::normal_distribution<double>(0.0, 100e-6)](
                   double, auto& f, auto& w) mutable {
                 const double k = 1.0 + n(rng);
                 f *= k;
                 w *= k;
               },
               "", 0, "", 0.0});
  e.push_back({"gyro x scale += 100 ppm/g f_z",
               [](double, auto& f, auto& w) { w(0) += 100e-6 * w(0) * f(2) / kG; }, "", 0, "",
               0.0});
  const double t0 = 2.0 * mid_s / 3.0;
  e.push_back({"gyro y bias transient 0.1 deg/h for 30 s",
               [dph, t0](double t, auto&, auto& w) {
                 if (t > t0 && t <= t0 + 30.0) w(1) += 0.1 * dph;
               },
               "", 0, "", 0.0});
}

/// The effects of the open-world matrix (issue 33); the bias step at log time mid_s (s), the random
/// effects (the timing jitter) drawn for the session of `seed`.
inline std::vector<OpenWorldEffect> open_world_effects(double mid_s, std::uint64_t seed = 0) {
  const double ug = units::ug, dph = units::deg_per_h, g2 = kG * kG;
  std::vector<OpenWorldEffect> e;
  e.push_back({"accel x += 100 ug/g^2 f_y f_z",
               [ug, g2](double, auto& f, auto&) { f(0) += 100.0 * ug * f(1) * f(2) / g2; }, "accel",
               0, "f_y f_z", 100.0});
  e.push_back({"gyro x += 0.2 deg/h/g^2 f_z^2",
               [dph, g2](double, auto& f, auto& w) { w(0) += 0.2 * dph * f(2) * f(2) / g2; },
               "gyro", 0, "f_z^2", 0.2});
  // 3000 ppm/(rad/s) = 52.36 ppm/(deg/s): the library's unit.
  e.push_back({"gyro x += 3000 ppm/(rad/s) omega_x |omega_x|",
               [](double, auto&, auto& w) { w(0) += 3000e-6 * w(0) * std::abs(w(0)); }, "gyro", 0,
               "omega_x |omega_x|", 3000.0 * units::deg_per_s});
  e.push_back(
      {"accel y += 20 ug sin(2 pi t / 29 s)",
       [ug](double t, auto& f, auto&) { f(1) += 20.0 * ug * std::sin(2.0 * M_PI * t / 29.0); },
       "accel", 1, "sin(2 pi t / 29 s)", 20.0});  // rot19's cycle (the library's period there)
  e.push_back({"gyro z bias step 0.1 deg/h at mid-session",
               [dph, mid_s](double t, auto&, auto& w) {
                 if (t > mid_s) w(2) += 0.1 * dph;
               },
               "gyro", 2, "step", 0.1});
  e.push_back({"gyro x += 0.2 deg/h/g^2 f_y f_z",
               [dph, g2](double, auto& f, auto& w) { w(0) += 0.2 * dph * f(1) * f(2) / g2; },
               "gyro", 0, "f_y f_z", 0.2});
  e.push_back({"gyro y += 3000 ppm/(rad/s) omega_y^2",
               [](double, auto&, auto& w) { w(1) += 3000e-6 * w(1) * w(1); }, "gyro", 1,
               "omega_y^2", 3000.0 * units::deg_per_s});
  // 20 ug at 600 s: 720 ug/h^2.
  e.push_back({"accel z += 20 ug (t / 600 s)^2",
               [ug](double t, auto& f, auto&) { f(2) += 20.0 * ug * (t / 600.0) * (t / 600.0); },
               "accel", 2, "t^2", 20.0 * 36.0});
  append_unanticipated_effects(e, mid_s);
  append_more_unanticipated_effects(e, mid_s, seed);
  return e;
}

/// A clean simulated session with the effect `index` of open_world_effects injected, `scale` times
/// its size (its mid-session: the plan's; a random effect drawn for `seed`, as the noise).
inline HiddenCase open_world_case(const std::string& plan, const std::string& profile,
                                  std::size_t index, std::uint64_t seed, double rate_hz,
                                  double scale = 1.0) {
  HiddenCase c = hidden_case("open_world", plan, profile, {}, seed, rate_hz);
  const double duration = PlanTimeline::of(c.session.plan, c.session.site).duration;
  const auto effects = open_world_effects(c.session.time_offset + 0.5 * duration, seed);
  const ExtraTerm term = effects.at(index).term;
  inject_into_log(c.session.dir + "/imu.csv", rate_hz,
                  [&term, scale](double t, Eigen::Vector3d& f, Eigen::Vector3d& w) {
                    Eigen::Vector3d f1 = f, w1 = w;
                    term(t, f1, w1);
                    f += scale * (f1 - f);
                    w += scale * (w1 - w);
                  });
  c.session = Session::load(c.session.path);
  return c;
}

}  // namespace sinscal::test
