// The thermal diagnosis on soaks (filter/diagnosis/thermal_diagnosis.hpp): its test's false-alarm
// rate and power against theory on synthetic soaks, and hidden thermal families named first on
// simulated chambers calibrated soak by soak (one seed here, 30 in the documented Monte Carlo).
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/distributions/non_central_chi_squared.hpp>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "catalog.hpp"
#include "filter/diagnosis/diagnosis.hpp"
#include "filter/diagnosis/diagnosis_table.hpp"
#include "filter/diagnosis/thermal_diagnosis.hpp"
#include "filter/thermal/soak_run.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "rig/thermal.hpp"

using namespace sinscal;

namespace {

// Synthetic soaks of gyro.bias.x/y/z and accel.scale.x/y/z at six temperatures: gyro bias
// quadratic, accel scale linear plus `scale_quadratic` (SI per C^2) on each axis, with a
// correlated covariance; `noise` false: the values exactly.
std::vector<SoakEstimate> synthetic_soaks(std::mt19937_64& rng, double scale_quadratic,
                                          bool noise = true) {
  const double T0 = 20.0;
  const std::vector<double> temps = {-40, -20, 0, 20, 40, 60};
  std::vector<int> idx;
  for (const char* n : {"gyro.bias.x", "gyro.bias.y", "gyro.bias.z", "accel.scale.x",
                        "accel.scale.y", "accel.scale.z"})
    idx.push_back(test::coefficient_index(n));
  const double sb = 0.01 * units::deg_per_h, ss = 2 * units::ppm;
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  for (int i = 0; i < 3; ++i) {
    C(i, i) = sb * sb;
    C(i + 3, i + 3) = ss * ss;
    C(i, i + 3) = C(i + 3, i) = 0.4 * sb * ss;
  }
  C(3, 4) = C(4, 3) = 0.3 * ss * ss;
  const Eigen::Matrix<double, 6, 6> L = C.llt().matrixL();
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<SoakEstimate> soaks;
  for (double T : temps) {
    const double d = T - T0;
    SoakEstimate e;
    e.accel_temperature_c = e.gyro_temperature_c = T;
    e.catalog = idx;
    Eigen::Matrix<double, 6, 1> x;
    for (int i = 0; i < 3; ++i) {
      x(i) = (0.2 + 0.01 * d + 2e-4 * d * d) * units::deg_per_h * (i + 1);
      x(i + 3) = (30.0 - 10.0 * i + 1.0 * d) * units::ppm + scale_quadratic * d * d * (1 - i);
    }
    Eigen::Matrix<double, 6, 1> w;
    for (int i = 0; i < 6; ++i) w(i) = n(rng);
    e.value = noise ? Eigen::VectorXd(x + L * w) : Eigen::VectorXd(x);
    e.covariance = C;
    soaks.push_back(e);
  }
  return soaks;
}

const std::vector<std::string> kSyntheticModel = {"gyro.bias_temp1", "gyro.bias_temp2",
                                                  "accel.scale_temp1"};

}  // namespace

TEST_CASE("Thermal diagnosis: false alarms at alpha, power as the noncentral chi-square says",
          "[thermal][diagnosis]") {
  // accel.scale_temp2 hidden at the size whose noncentrality (the model's chi-square on the
  // noiseless soaks) gives a 60 % chance to beat the Bonferroni threshold: over 400 draws the
  // share named must match the noncentral chi-square's power within 3 binomial sigmas; clean
  // soaks (no quadratic) name a family in at most alpha plus 3 binomial sigmas of the draws.
  std::mt19937_64 rng(5);
  ThermalDiagnosisOptions o;
  o.model = kSyntheticModel;
  // Tested candidates: gyro.bias_temp3 and accel.scale_temp2 (the others' base coefficients are
  // not in the soaks, or need a ramp; accel.scale_temp3 waits for accel.scale_temp2).
  const ThermalDiagnosis probe = diagnose_soaks(synthetic_soaks(rng, 0.0), 20.0, o);
  REQUIRE(probe.rounds.size() == 1);
  const auto tested = probe.rounds.front().size();
  CHECK(tested == 2);
  const double threshold = o.alpha / static_cast<double>(tested);
  // Hidden on two axes (x and z: the factor 1 - i); the test has the family's 3 dof.
  const auto lambda_of = [&](double a) {
    std::mt19937_64 r(1);
    return fit_soaks_with(synthetic_soaks(r, a, false), kSyntheticModel, 20.0).chi2;
  };
  const double a1 = 1e-3 * units::ppm;  // per C^2
  const double lambda1 = lambda_of(a1);
  // lambda grows as a^2: the size at the aimed power.
  const boost::math::chi_squared_distribution<double> null3(3);
  const double q3 = boost::math::quantile(boost::math::complement(null3, threshold));
  const auto power_at = [&](double l) {
    return boost::math::cdf(boost::math::complement(
        boost::math::non_central_chi_squared_distribution<double>(3, l), q3));
  };
  double lo = 1.0, hi = 200.0;
  for (int it = 0; it < 60; ++it) (power_at(0.5 * (lo + hi)) < 0.6 ? lo : hi) = 0.5 * (lo + hi);
  const double lambda = 0.5 * (lo + hi);
  const double power = power_at(lambda);
  const double a = a1 * std::sqrt(lambda / lambda1);
  CAPTURE(q3, lambda, power, a / units::ppm);
  const int draws = 400;
  int named = 0, false_alarms = 0;
  for (int k = 0; k < draws; ++k) {
    const ThermalDiagnosis hidden = diagnose_soaks(synthetic_soaks(rng, a), 20.0, o);
    if (!hidden.findings.empty() && hidden.findings.front().test.family == "accel.scale_temp2")
      ++named;
    const ThermalDiagnosis clean = diagnose_soaks(synthetic_soaks(rng, 0.0), 20.0, o);
    if (!clean.findings.empty()) ++false_alarms;
  }
  const double share = static_cast<double>(named) / draws;
  const double sd = std::sqrt(power * (1.0 - power) / draws);
  CAPTURE(named, false_alarms, share, sd);
  std::printf(
      "thermal diagnosis, synthetic soaks: named %d of %d at power %.3f (lambda %.1f), false "
      "alarms %d of %d at alpha %g\n",
      named, draws, power, lambda, false_alarms, draws, o.alpha);
  CHECK(std::abs(share - power) < 3.0 * sd + 0.02);  // + the F test's and the ranking's share
  CHECK(false_alarms <= o.alpha * draws + 3.0 * std::sqrt(o.alpha * draws));
}

TEST_CASE("Thermal diagnosis: a polynomial in the temperature is extended degree by degree",
          "[thermal][diagnosis]") {
  // The gyro bias is quadratic in the synthetic soaks; the model has its degree 1 only. Degree 3
  // waits until degree 2 is in the model: in the first round it is not tested (with the reason),
  // and degree 2 is named first. Without the hierarchy T - T0 cubed can take the round with a
  // zero truth (issue 33: accel.bias_temp3 named first in an all-hidden chamber).
  std::mt19937_64 rng(11);
  ThermalDiagnosisOptions o;
  o.model = {"gyro.bias_temp1", "accel.scale_temp1"};
  const ThermalDiagnosis d = diagnose_soaks(synthetic_soaks(rng, 0.0), 20.0, o);
  REQUIRE(!d.rounds.empty());
  for (const auto& t : d.rounds.front()) CHECK(t.family != "gyro.bias_temp3");
  REQUIRE(!d.findings.empty());
  CHECK(d.findings.front().test.family == "gyro.bias_temp2");
  ThermalDiagnosisOptions first = o;
  first.max_findings = 0;  // the first round's untestable candidates
  const ThermalDiagnosis r1 = diagnose_soaks(synthetic_soaks(rng, 0.0), 20.0, first);
  bool waits = false;
  for (const auto& t : r1.not_testable)
    waits =
        waits || (t.family == "gyro.bias_temp3" &&
                  t.not_testable.find("gyro.bias_temp2 is not in the model") != std::string::npos);
  CHECK(waits);
}

TEST_CASE("Thermal diagnosis: the held-out soaks and the family's error, before and after",
          "[thermal][diagnosis]") {
  std::mt19937_64 rng(9);
  ThermalDiagnosisOptions o;
  o.model = {"gyro.bias_temp1", "gyro.bias_temp2"};  // accel.scale_temp1 hidden (1 ppm/C)
  const ThermalDiagnosis d = diagnose_soaks(synthetic_soaks(rng, 0.0), 20.0, o);
  REQUIRE(!d.findings.empty());
  const ThermalFinding& f = d.findings.front();
  CHECK(f.test.family == "accel.scale_temp1");
  // 1 ppm/C over soaks 20-60 C from T0: the held-out soaks miss by tens of ppm before, by about
  // the soaks' 2 ppm sigma (and the extrapolation's) after.
  CHECK(f.family_error_before / units::ppm > 20.0);
  CHECK(f.family_error_after / units::ppm < 6.0);
  CHECK(f.before.sigmas > 5.0);
  CHECK(f.after.sigmas < 2.0);
  REQUIRE(f.coefficients.size() == 3);
  for (const auto& c : f.coefficients) {
    CHECK(c.value == Approx(1.0 * units::ppm).margin(4.0 * c.sigma));
  }
  // The gyro bias in dT/dt is not testable on soaks; nor are families whose coefficient at T0
  // the soaks lack.
  bool rate = false, missing = false;
  for (const auto& t : d.not_testable) {
    rate = rate ||
           (t.family == "gyro.bias_temp_rate" && t.not_testable.find("ramp") != std::string::npos);
    missing = missing || (t.family == "accel.bias_temp1" &&
                          t.not_testable.find("do not estimate accel.bias") != std::string::npos);
  }
  CHECK(rate);
  CHECK(missing);
}

namespace {

// A sensor profile: `base` with `drop` removed (key `family` without its triad, in the triad's
// section) and `add` lines appended to their sections ({"accel", "scale_temp2 = 1 1 ppm/C^2"}).
std::string profile_variant(const std::string& dir, const std::string& name,
                            const std::vector<std::string>& drop,
                            const std::vector<std::pair<std::string, std::string>>& add = {}) {
  std::ifstream in(test::source_path("config/sensors/nav-fog-thermal.ini"));
  std::ostringstream out;
  std::string line, section;
  while (std::getline(in, line)) {
    if (!line.empty() && line.front() == '[') {
      section = line.substr(1, line.find(']') - 1);
      out << line << "\n";
      for (const auto& [s, l] : add)
        if (s == section) out << l << "\n";
      continue;
    }
    bool dropped = false;
    for (const auto& f : drop) {
      const std::string key = f.substr(f.find('.') + 1);
      dropped = dropped || (f.substr(0, f.find('.')) == section && line.rfind(key + " ", 0) == 0);
    }
    if (!dropped) out << line << "\n";
  }
  const std::string path = dir + "/" + name + ".ini";
  std::ofstream(path) << out.str();
  return path;
}

std::vector<std::string> model_of(const std::string& profile_path) {
  const SensorProfile p = SensorProfile::load(profile_path);
  std::vector<std::string> out;
  for (const auto& f : coefficient_families())
    if (f.thermal() && p.has(f.name)) out.push_back(f.name);
  return out;
}

std::vector<SoakEstimate> chamber_soaks(const std::string& dir, const std::string& profile,
                                        std::uint64_t seed) {
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/rot19.ini");
  spec.data_sensor_path = profile;
  spec.seed = seed;
  const ChamberSimulation soaks = simulate_chamber(
      dir, spec, ChamberProgram::load(test::source_path("config/chambers/soaks6.ini")));
  ChamberSoaks chamber = ChamberSoaks::load(soaks.path);
  chamber.table_sigma = 0.05 * units::arcsec;  // the simulated table (test_thermal.cpp)
  std::vector<SoakEstimate> out;
  for (const auto& s : chamber.sessions) out.push_back(calibrate_soak(s, chamber).estimate);
  return out;
}

// The diagnosis of `soaks` with the model of `profile` minus `hidden`: the families named, in
// order.
std::vector<std::string> named(const std::vector<SoakEstimate>& soaks, const std::string& profile,
                               const std::vector<std::string>& hidden) {
  ThermalDiagnosisOptions o;
  for (const auto& m : model_of(profile))
    if (std::find(hidden.begin(), hidden.end(), m) == hidden.end()) o.model.push_back(m);
  const ThermalDiagnosis d =
      diagnose_soaks(soaks, SensorProfile::load(profile).reference_temperature_c, o);
  std::vector<std::string> out;
  for (const auto& f : d.findings) out.push_back(f.test.family);
  return out;
}

struct Case {
  std::string label;
  std::vector<std::string> hidden;  // families left out of the model (empty: clean)
};

const std::vector<Case> kCases = {
    {"clean", {}},
    {"accel.scale_temp1 hidden", {"accel.scale_temp1"}},
    {"gyro.bias_temp2 hidden (degree 1 in the model)", {"gyro.bias_temp2"}},
    {"gyro.misalignment_temp1 hidden", {"gyro.misalignment_temp1"}},
    {"two at once: accel.misalignment_temp1, gyro.scale_temp1",
     {"accel.misalignment_temp1", "gyro.scale_temp1"}},
};

// Whether the diagnosis named the hidden families first (in any order), and nothing else first.
bool right(const std::vector<std::string>& got, const std::vector<std::string>& hidden) {
  if (got.size() < hidden.size()) return false;
  for (std::size_t k = 0; k < hidden.size(); ++k)
    if (std::find(hidden.begin(), hidden.end(), got[k]) == hidden.end()) return false;
  return hidden.empty() ? got.empty() : true;
}

}  // namespace

TEST_CASE("Thermal diagnosis: hidden thermal families named first on a simulated chamber",
          "[thermal][diagnosis][long]") {
  const std::string dir = test::temp_dir("thermal_diagnosis");
  const std::string profile = test::source_path("config/sensors/nav-fog-thermal.ini");
  const auto soaks = chamber_soaks(dir + "/soaks", profile, 4);
  for (const auto& c : kCases) {
    const auto got = named(soaks, profile, c.hidden);
    std::string names;
    for (const auto& g : got) names += g + " ";
    CAPTURE(c.label, names);
    CHECK(right(got, c.hidden));
  }
}

TEST_CASE("Thermal diagnosis: every thermal family hidden: a real family first, every stop said",
          "[thermal][diagnosis][long]") {
  // A chamber of nav-fog-thermal diagnosed with no thermal family in the model: the first finding
  // is a family the unit has (degree 1 or a misalignment: the hierarchy), the findings cap is
  // stated with what is still significant, and the residual left (chi2 about 1e5 on 105 dof)
  // scales the sigmas by sqrt(chi2 / dof).
  const std::string dir = test::temp_dir("thermal_diagnosis_all_hidden");
  const std::string profile = test::source_path("config/sensors/nav-fog-thermal.ini");
  const auto soaks = chamber_soaks(dir + "/soaks", profile, 2);
  ThermalDiagnosisOptions o;  // no thermal family in the model
  const ThermalDiagnosis d =
      diagnose_soaks(soaks, SensorProfile::load(profile).reference_temperature_c, o);
  REQUIRE(d.findings.size() == 4);
  const auto truth = model_of(profile);
  CHECK(std::find(truth.begin(), truth.end(), d.findings.front().test.family) != truth.end());
  bool cap = false, untested = false;
  for (const auto& s : d.stops) {
    cap = cap || s.find("findings cap (4) was reached; still significant") != std::string::npos;
    untested = untested || s.find("only thermal families tested") != std::string::npos;
  }
  CHECK(cap);
  CHECK(untested);
  REQUIRE(d.unexplained);
  CHECK(d.sigma_scale == Approx(std::sqrt(d.final_fit.chi2 / d.final_fit.dof)));
  CHECK(d.sigma_scale > 1.0);
}

TEST_CASE("Thermal diagnosis: a soak whose filter diverges is set aside, the others go on",
          "[thermal][diagnosis]") {
  // Three soaks of rot19 (20 Hz); the second soak's filter profile claims gyro and accelerometer
  // noise 100 times below the data's, so its filter diverges. The chamber's calibration sets that
  // soak aside with the filter's cause and calibrates the others (before, the first diverging
  // soak stopped the whole chamber diagnosis: issue 33); its stop names the soak.
  const std::string dir = test::temp_dir("thermal_diagnosis_diverging");
  std::ofstream(dir + "/three.ini") << "[chamber]\ntype = soaks\nstart = 20 C\nsoaks = 0 20 40 C\n"
                                       "air_rate = 3 C/min\nsettle = 3600 s\n";
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/rot19.ini");
  spec.data_sensor_path = test::source_path("config/sensors/nav-fog-thermal.ini");
  spec.rate_hz = 20.0;
  spec.seed = 7;
  const ChamberSimulation sim =
      simulate_chamber(dir + "/soaks", spec, ChamberProgram::load(dir + "/three.ini"));
  ChamberSoaks chamber = ChamberSoaks::load(sim.path);
  chamber.table_sigma = 0.05 * units::arcsec;
  REQUIRE(chamber.sessions.size() == 3);
  const std::string quiet =
      profile_variant(dir, "quiet", {"gyro.arw", "accel.vrw"},
                      {{"gyro", "arw = 1e-5 deg/sqrt(h)"}, {"accel", "vrw = 0.1 ug/sqrt(Hz)"}});
  const std::string soak2 = std::filesystem::path(chamber.sessions[1]).parent_path().string();
  std::filesystem::copy_file(quiet, soak2 + "/sensor.ini",
                             std::filesystem::copy_options::overwrite_existing);
  CHECK_THROWS_AS(calibrate_soak(chamber.sessions[1], chamber), SoakStopped);
  const ChamberRuns runs = calibrate_soaks_keep_going(chamber);
  REQUIRE(runs.failed.size() == 1);
  CHECK(runs.failed.front().index == 1);
  CHECK_THAT(runs.failed.front().cause, Catch::Contains("diverging"));
  CHECK(runs.index == std::vector<std::size_t>{0, 2});
  REQUIRE(runs.runs.size() == 2);
  for (const auto& r : runs.runs) CHECK(r.run.nis_per_dof < 1.0);
  CHECK_THAT(soak_failure_stop(runs.failed.front(), 3),
             Catch::StartsWith("soak 2 of 3 set aside") && Catch::Contains("diverging"));
}

TEST_CASE("Thermal diagnosis: Monte Carlo, hidden families named first, clean names none",
          "[thermal][diagnosis][montecarlo][.]") {
  // SINSCAL_THERMAL_SEEDS seeds (default 30) of nav-fog-thermal in six soaks: each case's
  // share of seeds named right (issue 19: >= 95 %). Plus the case near the detection limit:
  // accel.scale_temp2, absent from nav-fog-thermal, added to the truth at 3.5 times the sigma
  // its fit gives per component (noncentrality about 37 on 3 dof: power about 0.98).
  const char* seeds_env = std::getenv("SINSCAL_THERMAL_SEEDS");
  const int seeds = seeds_env ? std::atoi(seeds_env) : 30;
  const std::string dir = test::temp_dir("thermal_diagnosis_mc");
  const std::string profile = test::source_path("config/sensors/nav-fog-thermal.ini");
  std::vector<int> right_count(kCases.size(), 0);
  int near_right = 0;
  std::string near_profile;
  for (int seed = 1; seed <= seeds; ++seed) {
    const auto soaks =
        chamber_soaks(dir + "/" + std::to_string(seed), profile, static_cast<std::uint64_t>(seed));
    for (std::size_t k = 0; k < kCases.size(); ++k)
      if (right(named(soaks, profile, kCases[k].hidden), kCases[k].hidden)) ++right_count[k];
    if (near_profile.empty()) {
      // The candidate's sigma per component on these soaks sets the size near the limit.
      std::vector<std::string> model;
      for (const auto& f : model_of(profile))
        if (thermal_family_parts(f).second > 0) model.push_back(f);  // not the rate's
      model.push_back("accel.scale_temp2");
      const ThermalFit fit = fit_soaks_with(soaks, model, 20.0);
      double sigma = 0.0;
      for (std::size_t i = 0; i < fit.catalog.size(); ++i)
        if (coefficient_catalog()[static_cast<std::size_t>(fit.catalog[i])].family ==
            "accel.scale_temp2")
          sigma = std::max(sigma, std::sqrt(fit.covariance(static_cast<Eigen::Index>(i),
                                                           static_cast<Eigen::Index>(i))));
      const double m = 3.5 * sigma / units::ppm;
      std::printf("near the limit: accel.scale_temp2 = %.4g ppm/C^2 (3.5 sigma)\n", m);
      std::ostringstream key;
      key.precision(6);
      key << "scale_temp2 = " << m << " " << m << " ppm/C^2";
      near_profile = profile_variant(dir, "near", {}, {{"accel", key.str()}});
    }
    const auto near = chamber_soaks(dir + "/" + std::to_string(seed) + "-near", near_profile,
                                    static_cast<std::uint64_t>(seed));
    if (right(named(near, profile, {}), {"accel.scale_temp2"})) ++near_right;
  }
  for (std::size_t k = 0; k < kCases.size(); ++k) {
    std::printf("%-60s right in %d of %d seeds\n", kCases[k].label.c_str(), right_count[k], seeds);
    CHECK(right_count[k] >= 0.95 * seeds);
  }
  std::printf("%-60s right in %d of %d seeds\n", "accel.scale_temp2 near the limit (3.5 sigma)",
              near_right, seeds);
  CHECK(near_right >= 0.95 * seeds);
}

namespace {

// A ramp's session (rot19 repeated in config/chambers/ramp.ini) of nav-fog-thermal at `rate_hz`,
// its filter profile without `hidden`, diagnosed as `sinscal diagnose` does (`run_filter` false:
// as with --no-kalman, the turns then only in the term library's test).
struct RampDiagnosis {
  TableDiagnosis d;
  ImuErrorModel truth;
  bool linearized = false;  // about the filter's passes (linearize)
};

RampDiagnosis ramp_table_diagnosis(const std::string& dir, const std::vector<std::string>& hidden,
                                   std::uint64_t seed, bool run_filter, double rate_hz,
                                   int max_findings = 0, const std::string& data_profile = "") {
  std::filesystem::create_directories(dir);
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/rot19.ini");
  spec.data_sensor_path =
      data_profile.empty() ? test::source_path("config/sensors/nav-fog-thermal.ini") : data_profile;
  spec.filter_sensor_path = profile_variant(dir, "filter", hidden);
  spec.rate_hz = rate_hz;
  spec.seed = seed;
  const ChamberSimulation ramp = simulate_chamber(
      dir + "/ramp", spec, ChamberProgram::load(test::source_path("config/chambers/ramp.ini")));
  const Session session = Session::load(ramp.path);
  const SensorProfile profile = SensorProfile::load(session.sensor_file);
  const TableAttitudeError table{kDefaultTableAttitudeSigma};
  TurnModel model = turn_model_of(session, profile, table.sigma);
  model.run_filter = run_filter;
  // The measure case's SINSCAL_RAMP_PASSES (as --passes; unset: 0, the automatic choice).
  const char* e_passes = std::getenv("SINSCAL_RAMP_PASSES");
  const auto about = linearize(model, e_passes ? std::atoi(e_passes) : 0);
  const ClosedFormReport cal =
      run_closed_form(session, default_stage1(&profile), table, !about, about ? &*about : nullptr);
  TableDiagnosisOptions to;
  to.dwells.thermal = true;
  to.heldout_turns = run_filter;
  if (max_findings > 0) to.dwells.max_findings = max_findings;
  Stage2Options s2 = cal.stage2_options;
  s2.reference_temperature_c = profile.reference_temperature_c;
  return {diagnose_table(cal.stage1, session.site, s2, to, &model), ramp.sessions.front().truth,
          about.has_value()};
}

// A ramp's session (rot19 repeated in config/chambers/ramp.ini, 50 Hz) of nav-fog-thermal, its
// filter profile without `hidden`; diagnosed as `sinscal diagnose --no-kalman` does (the dwells,
// each at its mean temperature and rate): the first finding's family and its ambiguous set.
struct RampFinding {
  std::vector<std::string> first;  // the first finding's family, then those ambiguous with it
  int findings = 0;
  /// The first finding's coefficients, each (estimate - truth) / sigma.
  std::vector<double> z;
};

RampFinding ramp_diagnosis(const std::string& dir, const std::vector<std::string>& hidden,
                           std::uint64_t seed) {
  const RampDiagnosis r = ramp_table_diagnosis(dir, hidden, seed, false, 50.0);
  const TableDiagnosis& d = r.d;
  RampFinding out;
  out.findings = static_cast<int>(d.findings.size());
  if (!d.findings.empty()) {
    out.first.push_back(d.findings.front().family);
    for (const auto& a : d.findings.front().ambiguous_with) out.first.push_back(a);
    const Eigen::VectorXd truth = r.truth.vector();
    for (const auto& c : d.findings.front().coefficients)
      if (!c.source.empty()) out.z.push_back((c.value - truth(c.catalog)) / c.sigma);
  }
  return out;
}

struct RampCase {
  std::string label;
  std::vector<std::string> hidden;
};

const std::vector<RampCase> kRampCases = {
    {"ramp, clean", {}},
    {"ramp, accel.scale_temp1 hidden", {"accel.scale_temp1"}},
    {"ramp, gyro.bias_temp2 hidden (degree 1 in the model)", {"gyro.bias_temp2"}},
};

// Named first, alone: the hidden family (clean: no finding).
bool ramp_right(const RampFinding& f, const std::vector<std::string>& hidden) {
  if (hidden.empty()) return f.findings == 0;
  return f.first.size() == 1 && f.first.front() == hidden.front();
}

}  // namespace

TEST_CASE("Thermal diagnosis: a ramp's dwells, each at its temperature, name a hidden family",
          "[thermal][diagnosis][long]") {
  // One case here (20 s); the clean ramp, the degree and the rate term in the Monte Carlo.
  const std::string dir = test::temp_dir("thermal_diagnosis_ramp");
  const RampCase& c = kRampCases[1];
  const RampFinding f = ramp_diagnosis(dir, c.hidden, 3);
  std::string names;
  for (const auto& n : f.first) names += n + " ";
  CAPTURE(c.label, names, f.findings);
  CHECK(ramp_right(f, c.hidden));
  // Its magnitude: each component within 4 sigma of the truth.
  CHECK(f.z.size() == 3);
  for (double z : f.z) CHECK(std::abs(z) < 4.0);
}

TEST_CASE("Thermal diagnosis: Monte Carlo of ramps, hidden families named first",
          "[thermal][diagnosis][montecarlo][.]") {
  // SINSCAL_THERMAL_SEEDS seeds (default 30), each case a ramp of nav-fog-thermal at 50 Hz.
  const char* seeds_env = std::getenv("SINSCAL_THERMAL_SEEDS");
  const int seeds = seeds_env ? std::atoi(seeds_env) : 30;
  const std::string dir = test::temp_dir("thermal_diagnosis_ramp_mc");
  std::vector<int> right_count(kRampCases.size(), 0);
  int rate_in_set = 0, rate_alone = 0;
  for (int seed = 1; seed <= seeds; ++seed) {
    const auto at = dir + "/" + std::to_string(seed);
    for (std::size_t k = 0; k < kRampCases.size(); ++k)
      if (ramp_right(ramp_diagnosis(at + "-" + std::to_string(k), kRampCases[k].hidden,
                                    static_cast<std::uint64_t>(seed)),
                     kRampCases[k].hidden))
        ++right_count[k];
    const RampFinding rate =
        ramp_diagnosis(at + "-rate", {"gyro.bias_temp_rate"}, static_cast<std::uint64_t>(seed));
    if (std::find(rate.first.begin(), rate.first.end(), "gyro.bias_temp_rate") != rate.first.end())
      ++rate_in_set;
    if (rate.first.size() == 1 && rate.first.front() == "gyro.bias_temp_rate") ++rate_alone;
  }
  for (std::size_t k = 0; k < kRampCases.size(); ++k) {
    std::printf("%-60s right in %d of %d seeds\n", kRampCases[k].label.c_str(), right_count[k],
                seeds);
    CHECK(right_count[k] >= 0.95 * seeds);
  }
  std::printf(
      "ramp, gyro.bias_temp_rate hidden: in the first finding's set in %d of %d seeds, alone in "
      "%d (a linear ramp makes it one with a bias drift)\n",
      rate_in_set, seeds, rate_alone);
  CHECK(rate_in_set >= 0.95 * seeds);
}

namespace {

// The library term "omega_a (T - T0)" on gyro axis a (the scale factor's slope), or null.
const LibraryTerm* scale_slope_term(const LibraryFit& fit, int axis) {
  const std::string formula = std::string("omega_") + "xyz"[axis] + " (T - T0)";
  for (const auto& t : fit.terms)
    if (t.sensor == "gyro" && t.axis == axis && t.formula == formula) return &t;
  return nullptr;
}

}  // namespace

TEST_CASE("Thermal diagnosis: a clean ramp's turns hold with the model's thermal terms",
          "[thermal][diagnosis][long]") {
  // The turns' attitude residual (term_library.hpp) with the profile's whole thermal model: each
  // sample's temperature in the model's columns, so the turns' test does not reject (before, the
  // thermal columns were taken at T0 and the clean ramp's turns rejected at chi2 about 1e4).
  const std::string dir = test::temp_dir("thermal_diagnosis_ramp_turns_clean");
  const RampDiagnosis r = ramp_table_diagnosis(dir, {}, 5, false, 20.0);
  CHECK(r.d.findings.empty());
  REQUIRE(r.d.unexplained.library.has_value() == r.d.unexplained.present);
  CHECK_FALSE(r.d.unexplained.present);
}

TEST_CASE("Thermal diagnosis: a ramp's turns show a hidden gyro scale slope as omega (T - T0)",
          "[thermal][diagnosis][long]") {
  // gyro.scale_temp1 hidden, the filter's test off (as --no-kalman): the dwells see the scale
  // factor only through the earth's rate, the turns' attitude residual rejects, and the library's
  // temperature terms of the turns give the slope on each axis within 4 sigma of the truth.
  const std::string dir = test::temp_dir("thermal_diagnosis_ramp_turns_scale");
  const RampDiagnosis r = ramp_table_diagnosis(dir, {"gyro.scale_temp1"}, 5, false, 20.0);
  REQUIRE(r.d.unexplained.present);
  REQUIRE(r.d.unexplained.library.has_value());
  const LibraryFit& fit = *r.d.unexplained.library;
  CHECK(fit.turns_reject);
  int found = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const LibraryTerm* t = scale_slope_term(fit, axis);
    const double truth = r.truth.gyro.scale_temp(axis, 0) / units::ppm;  // ppm/C
    CAPTURE(axis, truth, t ? t->text() : std::string("none"));
    if (!t) continue;
    ++found;
    CHECK(std::abs(t->value - truth) < 4.0 * t->sigma);
  }
  CHECK(found >= 2);
}

namespace {

// Whether any component of `family` is among the catalog indices `components`.
bool has(const std::vector<int>& components, const std::string& family) {
  return std::any_of(components.begin(), components.end(), [&](int c) {
    return coefficient_catalog()[static_cast<std::size_t>(c)].family == family;
  });
}

}  // namespace

TEST_CASE("Thermal diagnosis: a ramp's dwells test degree by degree, time after temperature",
          "[thermal][diagnosis]") {
  // On a session whose temperature varies the default candidates wait: degree d of a coefficient
  // for degree d - 1, a bias drift in time for the bias's degree-1 temperature term (on a ramp
  // time and temperature rise together; a line in time fitted the hidden linear and quadratic
  // temperature terms better and was the all-hidden ramp's first candidate with a zero truth).
  using diagnosis_detail::candidate_components;
  const std::vector<int> none = candidate_components({}, {}, true);
  for (const char* f : {"accel.bias_temp1", "gyro.bias_temp1", "gyro.scale_temp1",
                        "gyro.misalignment_temp1", "gyro.bias_temp_rate", "accel.k2"})
    CHECK(has(none, f));
  for (const char* f : {"accel.bias_temp2", "accel.bias_temp3", "gyro.bias_temp2",
                        "accel.bias_drift", "gyro.bias_drift"})
    CHECK_FALSE(has(none, f));
  const std::vector<int> after =
      candidate_components({}, test::family_coefficients("accel.bias_temp1"), true);
  CHECK(has(after, "accel.bias_temp2"));
  CHECK(has(after, "accel.bias_drift"));
  CHECK_FALSE(has(after, "accel.bias_temp3"));
  CHECK_FALSE(has(after, "gyro.bias_drift"));
  CHECK_FALSE(has(after, "accel.bias_temp1"));  // in the model
  // A session at one temperature: no thermal candidate, the drifts as before; the user's list
  // is tested as given.
  const std::vector<int> table = candidate_components({}, {}, false);
  CHECK(has(table, "accel.bias_drift"));
  CHECK_FALSE(has(table, "accel.bias_temp1"));
  CHECK(has(candidate_components({"accel.bias_temp2"}, {}, true), "accel.bias_temp2"));
}

TEST_CASE("Thermal diagnosis: a ramp with every thermal family hidden names a family it has first",
          "[thermal][diagnosis][long]") {
  // nav-fog-thermal's nine thermal families all missing from the filter's profile, the dwells'
  // test (the filter's test off, one round): on a ramp time and temperature rise together, and
  // a line in time (accel.bias_drift, truth zero) fitted the accelerometers' hidden linear and
  // quadratic temperature terms better than the line in temperature (F 2321 against 2145 on
  // seed 2). The degree hierarchy and time after temperature make the first finding a family
  // whose truth is not zero.
  const std::vector<std::string> all = {
      "gyro.bias_temp1",         "gyro.bias_temp2",     "gyro.scale_temp1",
      "gyro.misalignment_temp1", "gyro.bias_temp_rate", "accel.bias_temp1",
      "accel.bias_temp2",        "accel.scale_temp1",   "accel.misalignment_temp1"};
  const std::string dir = test::temp_dir("thermal_diagnosis_ramp_all_hidden");
  const RampDiagnosis r = ramp_table_diagnosis(dir, all, 2, false, 20.0, 1);
  // Round 1's finding, named or refused at the end (the residual is unexplained with one
  // finding of nine).
  std::string round1;
  for (const auto& f : r.d.findings)
    if (f.round == 1) round1 = f.family;
  for (const auto& f : r.d.rejected)
    if (f.finding.round == 1) round1 = f.finding.family;
  CAPTURE(round1);
  REQUIRE(!round1.empty());
  CHECK(std::find(all.begin(), all.end(), round1) != all.end());
  // Honest sigmas (issue 33): the model is still rejected at the stop (its one finding refused,
  // the turns' attitude residual rejecting), so the sigmas are said not to hold, and they carry the
  // largest scale of the rejecting data, the turns' among them.
  const ResidualCheck& c = r.d.check;
  CAPTURE(c.sigmas_note, c.turns_chi2, c.turns_dof, c.sigma_scale);
  CHECK_FALSE(c.sigmas_hold);
  CHECK(c.sigmas_note.find("turns' attitude residual rejects") != std::string::npos);
  REQUIRE(c.turns_tested);
  CHECK_FALSE(c.turns_hold);
  CHECK(c.turns_sigma_scale == Approx(std::sqrt(c.turns_chi2 / c.turns_dof)));
  CHECK(c.sigma_scale >= c.turns_sigma_scale);
  CHECK(c.sigma_scale >= c.dwells_sigma_scale);
  CHECK(c.sigma_scale >= c.heldout_sigma_scale);
}

namespace {

// A ramp whose data hold `sensor`'s bias drift (`drift`, a profile line; "" none: the bias's
// degree-1 temperature term instead), neither its degree-1 nor degree-2 temperature term in the
// filter's profile: the first finding's family, then those ambiguous with it.
std::vector<std::string> time_or_temperature_first(const std::string& dir,
                                                   const std::string& sensor,
                                                   const std::string& drift, std::uint64_t seed) {
  std::filesystem::create_directories(dir);
  const std::vector<std::string> hidden = {sensor + ".bias_temp1", sensor + ".bias_temp2"};
  const std::string data = drift.empty() ? profile_variant(dir, "data", {sensor + ".bias_temp2"})
                                         : profile_variant(dir, "data", hidden, {{sensor, drift}});
  const RampDiagnosis r = ramp_table_diagnosis(dir + "/run", hidden, seed, false, 20.0, 1, data);
  // Round 1's finding, named or refused at the end.
  const TableFinding* first = nullptr;
  for (const auto& f : r.d.findings)
    if (f.round == 1) first = &f;
  for (const auto& f : r.d.rejected)
    if (f.finding.round == 1) first = &f.finding;
  std::vector<std::string> out;
  if (first == nullptr) return out;
  out.push_back(first->family);
  for (const auto& a : first->ambiguous_with) out.push_back(a);
  return out;
}

bool holds(const std::vector<std::string>& set, const std::string& family) {
  return std::find(set.begin(), set.end(), family) != set.end();
}

}  // namespace

TEST_CASE("Thermal diagnosis: a true bias drift on a ramp is not named a temperature slope alone",
          "[thermal][diagnosis][long]") {
  // A gyro bias drift of 0.015 deg/h/h (about 5 sigma per axis) on a ramp, the gyro bias's
  // temperature terms missing from the model: the degree-1 temperature term is tested first (a
  // drift waits for it), and the held-out dwells do not let it stand alone (the ramp cannot tell
  // time from temperature): the pair is reported.
  const auto set = time_or_temperature_first(test::temp_dir("thermal_diagnosis_ramp_drift"), "gyro",
                                             "bias_drift = 0.015 0.015 deg/h/h", 1);
  std::string names;
  for (const auto& n : set) names += n + " ";
  CAPTURE(names);
  CHECK(holds(set, "gyro.bias_drift"));
}

TEST_CASE("Thermal diagnosis: a true temperature slope on a ramp is named, alone or in its pair",
          "[thermal][diagnosis][long]") {
  const auto set =
      time_or_temperature_first(test::temp_dir("thermal_diagnosis_ramp_temp1"), "gyro", "", 1);
  std::string names;
  for (const auto& n : set) names += n + " ";
  CAPTURE(names);
  REQUIRE(!set.empty());
  CHECK(set.front() == "gyro.bias_temp1");
}

TEST_CASE("Thermal diagnosis: a linearized ramp's turns are compensated at T0 as its dwells are",
          "[thermal][diagnosis][long]") {
  // accel.bias_temp1 hidden on a ramp (up to 400 ug over the ramp): the first filter run's NIS
  // asks for the linearization about the filter's 3 passes, whose model holds the profile's
  // thermal terms. The dwells' samples are compensated with it at T0 (the closed form), so the
  // library's turns must be too: compensated at each sample's temperature they held the model's
  // thermal share that the dwells' fit of the thermal columns puts back (seed 1: chi2 1.53e5 on
  // 1156 dof, the sigmas scaled x11.5 and said not to hold; 597 at T0).
  const std::string dir = test::temp_dir("thermal_diagnosis_ramp_linearized");
  const std::vector<std::string> hidden = {"accel.bias_temp1", "accel.bias_temp2"};
  const std::string data = profile_variant(dir, "data", {"accel.bias_temp2"});
  const RampDiagnosis r = ramp_table_diagnosis(dir + "/run", hidden, 1, false, 20.0, 1, data);
  REQUIRE(r.linearized);
  const ResidualCheck& c = r.d.check;
  CAPTURE(c.turns_chi2, c.turns_dof, c.sigmas_note);
  REQUIRE(c.turns_tested);
  CHECK(c.turns_hold);  // the chi-square quantile at kTurnsResidualLevel
  CHECK(c.sigmas_hold);
  REQUIRE(!r.d.findings.empty());
  const TableFinding& f = r.d.findings.front();
  CHECK(f.family == "accel.bias_temp1");
  // Its magnitude: each component within 4 of its (unscaled) sigmas of the truth.
  const Eigen::VectorXd truth = r.truth.vector();
  for (const auto& k : f.coefficients) {
    CAPTURE(k.catalog, k.value, k.sigma, truth(k.catalog));
    CHECK(std::abs(k.value - truth(k.catalog)) < 4.0 * k.sigma);
  }
}

TEST_CASE(
    "Thermal diagnosis: measure ramps (env SINSCAL_RAMP_CASE _SEEDS _FILTER _HZ _HIDDEN _PASSES)",
    "[thermal][diagnosis][measure][.]") {
  const char* e_case = std::getenv("SINSCAL_RAMP_CASE");
  const std::string which = e_case ? e_case : "all";
  const char* e_seeds = std::getenv("SINSCAL_RAMP_SEEDS");
  const char* e_filter = std::getenv("SINSCAL_RAMP_FILTER");
  const char* e_hz = std::getenv("SINSCAL_RAMP_HZ");
  const char* e_drift = std::getenv("SINSCAL_RAMP_DRIFT");  // the data's drift line
  const bool filter = e_filter && std::atoi(e_filter) != 0;
  const double hz = e_hz ? std::atof(e_hz) : 20.0;
  std::vector<int> seeds;
  {
    std::stringstream ss(e_seeds ? e_seeds : "1,2,13,14");
    std::string t;
    while (std::getline(ss, t, ',')) seeds.push_back(std::atoi(t.c_str()));
  }
  const std::string dir = test::temp_dir("thermal_measure_" + which);
  std::vector<std::string> hidden;
  std::string data;
  if (which == "all")
    hidden = {"gyro.bias_temp1",         "gyro.bias_temp2",     "gyro.scale_temp1",
              "gyro.misalignment_temp1", "gyro.bias_temp_rate", "accel.bias_temp1",
              "accel.bias_temp2",        "accel.scale_temp1",   "accel.misalignment_temp1"};
  const std::string sensor = which.substr(which.find('_') + 1);  // gyro / accel
  if (which.rfind("drift_", 0) == 0) {
    hidden = {sensor + ".bias_temp1", sensor + ".bias_temp2"};
    std::filesystem::create_directories(dir);
    data = profile_variant(dir, "data", hidden, {{sensor, e_drift ? e_drift : ""}});
  }
  if (which == "hidden") {  // SINSCAL_RAMP_HIDDEN: families left out of the filter's profile
    const char* e_hidden = std::getenv("SINSCAL_RAMP_HIDDEN");
    std::stringstream ss(e_hidden ? e_hidden : "");
    std::string t;
    while (std::getline(ss, t, ',')) hidden.push_back(t);
  }
  if (which.rfind("temp1_", 0) == 0) {
    hidden = {sensor + ".bias_temp1", sensor + ".bias_temp2"};
    std::filesystem::create_directories(dir);
    data = profile_variant(dir, "data", {sensor + ".bias_temp2"});
  }
  for (int seed : seeds) {
    const RampDiagnosis r =
        ramp_table_diagnosis(dir + "/" + std::to_string(seed), hidden,
                             static_cast<std::uint64_t>(seed), filter, hz, 0, data);
    const Eigen::VectorXd truth = r.truth.vector();
    const ResidualCheck& c = r.d.check;
    std::printf(
        "seed %d: dwells %.4g/%d hold %d heldout %.4g/%d (q %.4g) hold %d filter %d nis %.3g "
        "holds %d\n",
        seed, c.dwells_chi2, c.dwells_dof, c.dwells_hold, c.heldout_chi2, c.heldout_inputs,
        c.heldout_quantile, c.heldout_hold, c.filter, c.nis_per_dof, c.filter_holds);
    std::printf(
        "  turns %d %.4g/%.4g hold %d; scales dwells %.3g heldout %.3g filter %.3g turns %.3g "
        "-> %.3g; sigmas hold %d: %s\n",
        c.turns_tested, c.turns_chi2, c.turns_dof, c.turns_hold, c.dwells_sigma_scale,
        c.heldout_sigma_scale, c.filter_sigma_scale, c.turns_sigma_scale, c.sigma_scale,
        c.sigmas_hold, c.sigmas_note.c_str());
    if (r.d.unexplained.library)
      std::printf("  library turns %.4g / %.4g (q %.4g) reject %d\n",
                  r.d.unexplained.library->turns_chi2, r.d.unexplained.library->turns_dof,
                  r.d.unexplained.library->turns_quantile, r.d.unexplained.library->turns_reject);
    if (r.d.unexplained.library)
      for (const auto& t : r.d.unexplained.library->terms)
        std::printf("  library term %s\n", t.text().c_str());
    for (const auto& f : r.d.findings) {
      std::printf("  %d %s (%s) p %.3g amb:", f.round, f.family.c_str(),
                  f.source == TableFinding::Source::Dwells ? "dwells" : "turns", f.p_value);
      for (const auto& a : f.ambiguous_with) std::printf(" %s", a.c_str());
      std::printf(" picked_by %s [%s]\n   z:", f.picked_by.c_str(), f.time_temperature.c_str());
      for (const auto& k : f.coefficients) {
        const double old_sigma =
            k.sigma / c.sigma_scale *
            (k.source == "kalman" ? c.filter_sigma_scale : c.dwells_sigma_scale);
        std::printf(" %s %.3g/%.3g(%.3g)", k.source.c_str(),
                    (k.value - truth(k.catalog)) / old_sigma,
                    (k.value - truth(k.catalog)) / k.sigma, truth(k.catalog) / k.sigma);
      }
      std::printf("\n");
    }
    for (const auto& f : r.d.rejected)
      std::printf("  rejected %d %s: %s\n", f.finding.round, f.finding.family.c_str(),
                  f.reason.c_str());
    for (const auto& s : r.d.stops) std::printf("  stop: %s\n", s.c_str());
    std::fflush(stdout);
  }
}
