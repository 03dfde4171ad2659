// Model discovery from the Kalman filter's innovations (filter/diagnosis/diagnosis_kalman.hpp): an
// effect of the turns hidden in a simulated rot19 session, which the calibrating profile lacks,
// must be named first with every component within 3 sigma of the truth; a clean session names
// nothing.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "filter/diagnosis/diagnosis_kalman.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"

using namespace sinscal;

namespace {

const std::vector<std::string> kTurnFamilies = {"accel.lever_arm", "time_delay", "gyro.scale_asym"};

// nav-fog with `line` added to `section` ("" : the profile as it is).
std::string profile_with(const std::string& dir, const std::string& section,
                         const std::string& line) {
  std::ifstream in(test::source_path("config/sensors/nav-fog.ini"));
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  if (!section.empty()) {
    const std::string header = "[" + section + "]\n";
    const auto at = s.find(header);
    if (at == std::string::npos)
      s += "\n" + header + line + "\n";
    else
      s.insert(at + header.size(), line + "\n");
  }
  const std::string path = dir + "/data-sensor.ini";
  test::write_file(path, s);
  return path;
}

struct Simulated {
  Session session;
  ImuErrorModel truth;
};

Simulated simulate_rot19(const std::string& name, std::uint64_t seed, const std::string& section,
                         const std::string& line) {
  const std::string dir = test::temp_dir(name);
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/rot19.ini");
  spec.data_sensor_path = profile_with(dir, section, line);
  spec.filter_sensor_path = test::source_path("config/sensors/nav-fog.ini");
  spec.name = name;
  spec.seed = seed;
  spec.rate_hz = 50.0;
  const SimulatedSession sim = simulate_session(dir + "/session", spec);
  return {Session::load(sim.session_path), sim.truth};
}

KalmanDiagnosis diagnose(const Session& session) {
  CalibratorOptions o = calibrator_options_from_profile(SensorProfile::load(session.sensor_file));
  KalmanDiagnosisOptions d;
  d.candidates = kTurnFamilies;
  return diagnose_kalman(session, o, d);
}

}  // namespace

TEST_CASE("Kalman diagnosis: an effect of the turns hidden in rot19 is named first, within 3 sigma",
          "[diagnosis][kalman]") {
  struct Case {
    std::string family, section, line;
  };
  const std::vector<Case> cases = {{"time_delay", "timing", "time_delay = 0.5 1 ms"},
                                   {"accel.lever_arm", "accel", "lever_arm = 20 40 mm"},
                                   {"gyro.scale_asym", "gyro", "scale_asym = 20 40 ppm"}};
  for (const auto& c : cases) {
    SECTION(c.family) {
      const Simulated s = simulate_rot19("kdiag_" + c.family, 11, c.section, c.line);
      const KalmanDiagnosis d = diagnose(s.session);
      REQUIRE(!d.findings.empty());
      const KalmanCandidateTest& first = d.findings.front();
      CHECK(first.family == c.family);
      CHECK(first.dof > 0);
      CHECK(first.p_value < first.threshold);
      CHECK(first.nis_per_dof < d.initial_nis_per_dof);
      ImuErrorModel truth = s.truth;
      const auto refs = truth.coefficient_refs();
      double worst = 0.0, smallest_z = INFINITY;
      for (int k : first.catalog) {
        const CoefficientEstimate& e = first.estimates[static_cast<std::size_t>(k)];
        const double t = *refs[static_cast<std::size_t>(k)].second;
        worst = std::max(worst, std::abs(e.value - t) / e.sigma);
        smallest_z = std::min(smallest_z, std::abs(t) / e.sigma);
      }
      INFO(c.family << ": worst |error|/sigma " << worst << ", smallest |truth|/sigma "
                    << smallest_z << ", W " << first.statistic << " on " << first.dof);
      CHECK(worst < 3.0);
      CHECK(smallest_z > 5.0);  // the scenario hides it at 5 detection sigmas or more
    }
  }
}

TEST_CASE("Kalman diagnosis: a clean rot19 session names nothing", "[diagnosis][kalman]") {
  const Simulated s = simulate_rot19("kdiag_clean", 12, "", "");
  const KalmanDiagnosis d = diagnose(s.session);
  INFO("initial NIS per dof " << d.initial_nis_per_dof);
  CHECK(d.findings.empty());
  REQUIRE(d.rounds.size() == 1);
  for (const auto& c : d.rounds.front()) {
    INFO(c.family << ": W " << c.statistic << " on " << c.dof << ", p " << c.p_value);
    CHECK(c.dof > 0);  // rot19's turns separate every effect of the turns
    CHECK(!c.significant);
  }
}

TEST_CASE("Kalman diagnosis: candidates must be extended families not in the model",
          "[diagnosis][kalman]") {
  const Session session = Session::load(test::source_path("tests/data/segments/session.ini"));
  CalibratorOptions o;
  KalmanDiagnosisOptions d;
  d.candidates = {"gyro.bias"};
  CHECK_THROWS_AS(diagnose_kalman(session, o, d), std::invalid_argument);
  o.layout.set("time_delay", true);
  d.candidates = {"time_delay"};
  CHECK_THROWS_AS(diagnose_kalman(session, o, d), std::invalid_argument);
}

TEST_CASE("Kalman diagnosis Monte Carlo: effects of the turns named, clean sessions quiet (rot19)",
          "[long][diagnosis][kalman][monte_carlo]") {
  // Every component of the family hidden at 5 to 10 times its detection sigma on rot19 at 20 Hz
  // (the sigmas of the run with the family: time delay 5 us, lever arms 0.23-0.34 mm, gyro scale
  // asymmetry 0.8-0.92 ppm), random signs; 30 seeds each, and 30 clean sessions.
  struct Case {
    std::string family, section, line;
  };
  const std::vector<Case> cases = {{"time_delay", "timing", "time_delay = 0.025 0.05 ms"},
                                   {"accel.lever_arm", "accel", "lever_arm = 1.7 3.4 mm"},
                                   {"gyro.scale_asym", "gyro", "scale_asym = 4.6 9.2 ppm"},
                                   {"", "", ""}};
  const int seeds = 30;
  for (const auto& c : cases) {
    int right = 0, within = 0, named_any = 0;
    for (int seed = 1; seed <= seeds; ++seed) {
      const Simulated s =
          simulate_rot19("kdiag_mc", static_cast<std::uint64_t>(100 + seed), c.section, c.line);
      const KalmanDiagnosis d = diagnose(s.session);
      if (!d.findings.empty()) ++named_any;
      if (c.family.empty() || d.findings.empty() || d.findings.front().family != c.family) continue;
      ++right;
      const KalmanCandidateTest& first = d.findings.front();
      ImuErrorModel truth = s.truth;
      const auto refs = truth.coefficient_refs();
      double worst = 0.0;
      for (int k : first.catalog) {
        const CoefficientEstimate& e = first.estimates[static_cast<std::size_t>(k)];
        worst = std::max(worst,
                         std::abs(e.value - *refs[static_cast<std::size_t>(k)].second) / e.sigma);
      }
      if (worst < 3.0) ++within;
    }
    std::printf("Kalman diagnosis MC, %s: named first %d of %d, within 3 sigma %d; any named %d\n",
                c.family.empty() ? "clean" : c.family.c_str(), right, seeds, within, named_any);
    if (c.family.empty()) {
      CHECK(seeds - named_any >= 29);  // nothing named in at least 95 %
    } else {
      CHECK(right >= 29);  // the right effect first in at least 95 %
      CHECK(within >= 27);
    }
  }
}
