// Model discovery on hand-held sessions (filter/diagnosis/handheld_diagnosis.hpp): an effect hidden
// in a simulated hand-held session, which the table-free model lacks, must be named first with its
// magnitude; clean sessions must name nothing; the refit's columns must be the physics (a turn's
// sensitivity against re-integration); bad requests must say what is missing.
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "catalog.hpp"
#include "filter/diagnosis/handheld_diagnosis.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "rig/handheld.hpp"

using namespace sinscal;

namespace {

// A MEMS-like unit: base errors of a few percent, white noise only (the table-free model's).
SensorProfile profile() {
  SensorProfile p;
  p.name = "test-mems";
  p.ranges["gyro.bias"] = test::range(0.5 * units::deg_per_s, 1.0 * units::deg_per_s);
  p.ranges["gyro.scale"] = test::range(0.01, 0.03);
  p.ranges["gyro.misalignment"] = test::range(300 * units::arcsec, 3000 * units::arcsec);
  p.ranges["accel.bias"] = test::range(5 * units::mg, 20 * units::mg);
  p.ranges["accel.scale"] = test::range(0.01, 0.03);
  p.ranges["accel.misalignment"] = test::range(300 * units::arcsec, 3000 * units::arcsec);
  p.noise.gyro.white = 0.3 * units::deg_per_sqrt_h;
  p.noise.accel.white = 100 * units::ug_per_sqrt_hz;
  return p;
}

Site site() {
  Site s;
  s.lat_rad = 45.0 * units::deg;
  s.h_m = 100.0;
  return s;
}

struct Run {
  TableFreeResult cal;
  HandheldDiagnosis diagnosis;
  std::vector<ImuReading> readings;
};

// A short hand-held session (20 s first pose, 30 poses of 3-5 s) with the profile's base errors
// plus `hidden` (catalog index -> SI value), calibrated table-free and diagnosed.
Run simulate_and_diagnose(std::uint64_t seed, const std::map<int, double>& hidden,
                          const HandheldDiagnosisOptions& o = {}) {
  const SensorProfile prof = profile();
  HandheldOptions ho;
  ho.first_rest = 20.0;
  ho.poses = 30;
  ho.rest_min = 3.0;
  ho.rest_max = 5.0;
  const Motion m = handheld_motion(site(), ho, derive_seed(seed, 0));
  ImuErrorModel truth = prof.draw(derive_seed(seed, 1));
  auto refs = truth.coefficient_refs();
  for (const auto& [k, v] : hidden) *refs[static_cast<std::size_t>(k)].second = v;
  const auto samples = test::simulate(m, truth, 100.0, &prof.noise, derive_seed(seed, 2));
  Run r;
  r.readings = readings_from_samples(samples);
  TableFreeOptions to;
  to.site = site();
  r.cal = calibrate_table_free_counts(r.readings, RawScaling{}, to);
  r.diagnosis = diagnose_handheld(r.readings, r.cal, to, o);
  return r;
}

// The sigma of each single-component candidate of the first round (its detection sigma).
std::map<int, double> detection_sigmas(const HandheldDiagnosis& d, const std::string& family) {
  std::map<int, double> out;
  for (const auto& c : d.report.rounds.front())
    if (c.family == family && c.separable.size() == 1 && c.dof > 0) {
      const auto j = static_cast<Eigen::Index>(c.with.fit.parameters.size() - 1);
      out[c.separable.front()] = std::sqrt(c.with.fit.cov(j, j));
    }
  return out;
}

struct Tally {
  int runs = 0, named_first = 0, within_3_sigma = 0, ambiguous = 0, wrong = 0;
  std::vector<double> missed_at;  // the hidden size, in the pilot's detection sigmas, of misses
};

// One hidden effect over `runs` seeds at 5-10 of its detection sigmas (a pilot session's), a
// random separable axis and sign per seed.
Tally monte_carlo(const std::string& family, int runs, std::uint64_t seed0,
                  const std::vector<std::string>& accept_ambiguous) {
  const Run pilot = simulate_and_diagnose(seed0, {});
  const std::map<int, double> sigma = detection_sigmas(pilot.diagnosis, family);
  REQUIRE(!sigma.empty());
  std::mt19937_64 rng(seed0);
  Tally t;
  for (int k = 1; k <= runs; ++k) {
    auto it = sigma.begin();
    std::advance(it,
                 std::uniform_int_distribution<int>(0, static_cast<int>(sigma.size()) - 1)(rng));
    const double size = std::uniform_real_distribution<double>(5.0, 10.0)(rng) * it->second;
    const double value = std::bernoulli_distribution(0.5)(rng) ? size : -size;
    const Run r =
        simulate_and_diagnose(seed0 + static_cast<std::uint64_t>(k), {{it->first, value}});
    const DiagnosisReport& rep = r.diagnosis.report;
    ++t.runs;
    if (!rep.findings.empty() && rep.findings.front().family == family) {
      ++t.named_first;
      const CandidateTest& f = rep.findings.front();
      for (std::size_t j = 0; j < f.with.fit.parameters.size(); ++j)
        if (f.with.fit.parameters[j] == it->first) {
          const auto J = static_cast<Eigen::Index>(j);
          const double z = (f.with.fit.theta(J) - value) / std::sqrt(f.with.fit.cov(J, J));
          t.within_3_sigma += std::abs(z) < 3.0 ? 1 : 0;
        }
    } else if (rep.findings.empty() && !rep.ambiguous.empty()) {
      bool ok = false;
      const auto& a = rep.ambiguous.front();
      for (const auto& name : accept_ambiguous) ok = ok || a.family == name;
      t.ambiguous += ok ? 1 : 0;
      t.wrong += ok ? 0 : 1;
    } else {
      ++t.wrong;
      t.missed_at.push_back(size / it->second);
      UNSCOPED_INFO(family << " seed " << seed0 + static_cast<std::uint64_t>(k) << ": first "
                           << (rep.findings.empty() ? "nothing" : rep.findings.front().family));
    }
  }
  std::printf(
      "hand-held diagnosis, %s hidden: named first %d of %d (within 3 sigma %d), "
      "ambiguous %d, wrong %d\n",
      family.c_str(), t.named_first, t.runs, t.within_3_sigma, t.ambiguous, t.wrong);
  return t;
}

}  // namespace

TEST_CASE("Hand-held diagnosis: a clean session's refit matches the calibration",
          "[handheld_diagnosis]") {
  const Run r = simulate_and_diagnose(11, {});
  const DiagnosisReport& rep = r.diagnosis.report;
  // The linearization is at the table-free optimum: the base refit barely moves it; its
  // chi-square is the calibration's against the noise model the calibration completed (the
  // white noise's, 150 here, less what the small gyro wander found, 0.001 deg/s, takes).
  CHECK(rep.initial.fit.rank == 21 + 2 * static_cast<int>(r.cal.poses.size()));
  CAPTURE(r.cal.chi2, r.cal.gyro_rest_fit.wander, r.cal.turn_fit.sigma_scale);
  CHECK(rep.initial.chi2 <= 1.02 * r.cal.chi2);
  CHECK(rep.initial.chi2 > 0.8 * r.cal.chi2);
  CHECK(rep.initial.fit.chi2_per_dof > 0.7);
  CHECK(rep.initial.fit.chi2_per_dof < 1.4);
  // Held-out prediction of white noise: about one sigma.
  CHECK(rep.initial.heldout > 0.8);
  CHECK(rep.initial.heldout < 1.4);
  // Lever arms and the time delay have no signature in poses and turns of gyro rates alone.
  bool lever = false, delay = false;
  for (const auto& c : rep.not_separable) {
    lever = lever || c.family == "accel.lever_arm";
    delay = delay || c.family == "time_delay";
  }
  CHECK(lever);
  CHECK(delay);
  CHECK(r.diagnosis.poses.size() == r.cal.poses.size());
  CHECK(r.diagnosis.has_allan);
}

TEST_CASE(
    "Hand-held diagnosis: the base refit weighs each part by the calibration's completed noise "
    "model (a bias wander on the poses), names nothing on it",
    "[handheld_diagnosis]") {
  Run r = simulate_and_diagnose(12, {});
  // Each pose's accelerometers off by 1 mg and gyros by 0.02 deg/s per axis (steps: a bias
  // wander 10-20 times a pose mean's white noise), calibrated and diagnosed again.
  std::mt19937_64 rng(derive_seed(12, 7));
  std::normal_distribution<double> da(0.0, 1.0 * units::mg), dg(0.0, 0.02 * units::deg_per_s);
  for (const auto& p : r.cal.poses) {
    const Eigen::Vector3d a(da(rng), da(rng), da(rng)), g(dg(rng), dg(rng), dg(rng));
    for (std::size_t k = p.first; k <= p.last; ++k) {
      r.readings[k].accel += a;
      r.readings[k].gyro += g;
    }
  }
  TableFreeOptions to;
  to.site = site();
  const TableFreeResult cal = calibrate_table_free_counts(r.readings, RawScaling{}, to);
  const HandheldDiagnosis d = diagnose_handheld(r.readings, cal, to, {});
  const DiagnosisReport& rep = d.report;
  CAPTURE(cal.accel_fit.wander / units::mg, cal.gyro_rest_fit.wander / units::deg_per_s,
          rep.initial.fit.chi2_per_dof, rep.initial.fit.dof);
  CHECK(cal.accel_fit.wander > 0.5 * units::mg);
  CHECK(cal.gyro_rest_fit.wander > 0.01 * units::deg_per_s);
  // On the completed model the base fit's chi2 is its dof's (0.99 quantiles); on the white noise
  // alone (one factor for all parts) it was far beyond. (The held-out turns are not: they are
  // divided by their own noise, not by the left-out pose direction's wander: 2.1 sigma here.)
  const boost::math::chi_squared chi2(rep.initial.fit.dof);
  CHECK(rep.initial.chi2 > boost::math::quantile(chi2, 0.005));
  CHECK(rep.initial.chi2 < boost::math::quantile(chi2, 0.995));
  // The wander is no family's signature here: nothing named.
  for (const auto& f : rep.findings) UNSCOPED_INFO("named " << f.family);
  CHECK(rep.findings.empty());
}

TEST_CASE("Hand-held diagnosis: the turn columns are the integration's sensitivity",
          "[handheld_diagnosis]") {
  // A gyro scale asymmetry hidden at some 40 of its sigmas: adding it to the calibrated model
  // must remove the turn residual it caused (the linearized refit predicts what re-integration
  // gives) and recover it.
  const int c = test::coefficient_index("gyro.scale_asym.z");
  const double hidden = 0.002;
  const Run r = simulate_and_diagnose(12, {{c, hidden}});
  const DiagnosisReport& rep = r.diagnosis.report;
  REQUIRE(!rep.findings.empty());
  CHECK(rep.findings.front().family == "gyro.scale_asym");
  CHECK(rep.final_fit.turn_rms < 0.5 * rep.initial.turn_rms);
  const CandidateTest& f = rep.findings.front();
  for (std::size_t j = 0; j < f.with.fit.parameters.size(); ++j)
    if (f.with.fit.parameters[j] == c) {
      const auto J = static_cast<Eigen::Index>(j);
      CHECK(std::abs(f.with.fit.theta(J) - hidden) < 3.0 * std::sqrt(f.with.fit.cov(J, J)));
    }
}

TEST_CASE("Hand-held diagnosis: requests the poses cannot serve are refused",
          "[handheld_diagnosis]") {
  const Run r = simulate_and_diagnose(13, {});
  TableFreeOptions to;
  to.site = site();
  // Keep the first 11 poses only (the calibration of them is still possible: 10 needed).
  std::vector<ImuReading> part(
      r.readings.begin(),
      r.readings.begin() + static_cast<std::ptrdiff_t>(r.cal.poses[10].last + 50));
  const TableFreeResult cal = calibrate_table_free_counts(part, RawScaling{}, to);
  REQUIRE(cal.poses.size() == 11);
  HandheldDiagnosisOptions o;
  o.candidates = {"accel.k2"};
  const HandheldDiagnosis d = diagnose_handheld(part, cal, to, o);
  REQUIRE(d.refused.size() == 1);
  CHECK_THAT(d.refused.front(), Catch::Contains("needs at least 11 poses") ||
                                    Catch::Contains("needs at least 13 poses"));
  CHECK_THAT(d.refused.front(), Catch::Contains("found 11"));
  o.candidates = {"accel.nonsense"};
  CHECK_THROWS_AS(diagnose_handheld(part, cal, to, o), std::invalid_argument);
  o.candidates = {"gyro.bias"};
  CHECK_THROWS_AS(diagnose_handheld(part, cal, to, o), std::invalid_argument);
}

TEST_CASE("Hand-held diagnosis Monte Carlo: hidden effects named, clean sessions quiet",
          "[long][handheld_diagnosis][monte_carlo]") {
  const auto t0 = std::chrono::steady_clock::now();
  const int runs = 30;
  const std::vector<std::pair<std::string, std::vector<std::string>>> effects = {
      {"accel.k2", {"accel.k2", "accel.scale_asym"}},
      {"accel.scale_asym", {"accel.k2", "accel.scale_asym"}},
      {"gyro.g_sensitivity", {}},
      {"gyro.scale_asym", {}},
      {"gyro.bias_drift", {}},
      {"accel.bias_drift", {}}};
  std::uint64_t seed = 1000;
  for (const auto& [family, ambiguous_ok] : effects) {
    const Tally t = monte_carlo(family, runs, seed, ambiguous_ok);
    seed += 1000;
    CHECK(t.named_first + t.ambiguous >= 27);
    CHECK(t.within_3_sigma >= t.named_first - 2);
    if (ambiguous_ok.empty()) CHECK(t.named_first >= 27);
  }
  int quiet = 0;
  const int clean = 40;
  for (int k = 0; k < clean; ++k) {
    const Run r = simulate_and_diagnose(9000 + static_cast<std::uint64_t>(k), {});
    bool noise = false;
    for (const auto& n : r.diagnosis.noise) noise = noise || n.significant;
    quiet += r.diagnosis.report.findings.empty() && r.diagnosis.report.ambiguous.empty() && !noise;
  }
  std::printf("hand-held diagnosis, clean sessions: nothing named in %d of %d\n", quiet, clean);
  CHECK(quiet >= 38);
  std::printf("hand-held diagnosis Monte Carlo: %.1f s\n",
              std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
}

// The aim is 95 % named first; 30 seeds cannot tell 93 % from 95 %. Measured
// (docs/accuracy.md "Model discovery").
TEST_CASE("Hand-held diagnosis measured: gyro scale asymmetry over 300 seeds", "[.][measure]") {
  const Tally t = monte_carlo("gyro.scale_asym", 300, 4000, {});
  for (double s : t.missed_at) std::printf("missed at %.2f detection sigmas\n", s);
  std::printf("gyro.scale_asym: %d of %d named first, %d not named or wrong\n", t.named_first,
              t.runs, t.wrong);
}

TEST_CASE("Hand-held diagnosis: noise candidates from the Allan deviation",
          "[handheld_diagnosis]") {
  // A 200 s static stretch at 100 Hz: white noise alone names nothing; a gyro rate random walk
  // strong enough to double the deviation at the long cluster times is named on its axis as a
  // rate random walk, with its size.
  const double dt = 0.01, white = 0.01, K = 0.01 / std::sqrt(1.0);  // rad/s, rad/s/sqrt(s)
  auto record = [&](double walk, std::uint64_t seed) {
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> n(0.0, 1.0);
    std::vector<ImuReading> r(20000);
    double bias = 0.0;
    for (std::size_t k = 0; k < r.size(); ++k) {
      bias += walk * std::sqrt(dt) * n(rng);
      r[k].t = static_cast<double>(k) * dt;
      r[k].gyro = Eigen::Vector3d(white * n(rng) + bias, white * n(rng), white * n(rng));
      r[k].accel = Eigen::Vector3d(1e-3 * n(rng), 1e-3 * n(rng), 9.81 + 1e-3 * n(rng));
    }
    return r;
  };
  // White noise alone: the family-wise level 0.01 over 100 records (the bounds' degrees of
  // freedom are approximations: at most 4 % flagged).
  int quiet = 0;
  for (std::uint64_t seed = 1; seed <= 100; ++seed) {
    const auto r = record(0.0, seed);
    const auto c = noise_candidates(stretch_allan(r, 0, r.size() - 1, 0.01), 0.01);
    REQUIRE(c.size() == 6);
    bool any = false;
    for (const auto& x : c) any = any || x.significant;
    quiet += any ? 0 : 1;
  }
  CHECK(quiet >= 96);
  const auto r = record(K, 42);
  const auto c = noise_candidates(stretch_allan(r, 0, r.size() - 1, 0.01), 0.01);
  CHECK(c[0].channel == "gyro.x");
  CHECK(c[0].significant);
  CHECK(c[0].effect == "noise.rate_random_walk");
  CHECK(c[0].value == Approx(K).epsilon(0.5));
  CHECK(!c[1].significant);
  CHECK(!c[2].significant);
}
