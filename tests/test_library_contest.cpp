// The library's contest with a catalog family on held-out data (filter/diagnosis/term_library.hpp
// contest_family, issue 33): a family is refused when a library term explains its share of the
// held-out dwells and turns better. Generated here: a clean rot19 nav-fog session whose gyro z
// gets either a bias step half-way (outside the catalog: a library term) or a bias linear in time
// (the catalog's gyro.bias_drift), injected into the log by test code. The drift's columns see
// part of the step (a line through a step), so the contest must refuse the drift for the step's
// term and keep it for the true drift. A sign of the contest's comparisons flipped turns one of
// the two red.
#include <catch2/catch.hpp>

#include "filter/diagnosis/term_library.hpp"
#include "out_of_catalog.hpp"

using namespace sinscal;
using namespace sinscal::test;

namespace {

constexpr double kContestRate = 20.0;  // Hz, as the open-world matrix

// A term injected into the log, given the log time of the plan's middle (s).
using TermAt = std::function<ExtraTerm(double mid_s)>;

// The contest of gyro.bias_drift against the library on a clean rot19 nav-fog session (seed)
// with `term_at` injected into its log, set up as the table diagnosis sets up its dwells and turns
// (the dwells' model with the bias wander and the session grade's priors, the turns with the
// table's attitude sigma).
HeldoutContest drift_contest(std::uint64_t seed, const TermAt& term_at) {
  HiddenCase c = hidden_case("library_contest", "rot19.ini", "nav-fog.ini", {}, seed, kContestRate);
  const double mid =
      c.session.time_offset + 0.5 * PlanTimeline::of(c.session.plan, c.session.site).duration;
  inject_into_log(c.session.dir + "/imu.csv", kContestRate, term_at(mid));
  c.session = Session::load(c.session.path);
  const CaseCalibration cc = calibrate_case(c);
  const TurnModel& model = cc.model;
  const ClosedFormReport& cal = cc.calibration;
  Stage2Options base = cal.stage2_options;
  base.bias_wander = model.base.noise;
  DiagnosisOptions o;
  o.prior_sigma = grade_priors(model.base);
  const DwellTests dwells(cal.stage1, c.session.site, base, o);
  LibraryTurns lt;
  lt.session = &c.session;
  lt.attitude_sigma = model.base.attitude_sigma;
  lt.noise = model.base.noise;
  lt.about = model.base.initial_model ? &*model.base.initial_model : nullptr;
  std::vector<int> drift;
  const auto& cat = coefficient_catalog();
  for (std::size_t k = 0; k < cat.size(); ++k)
    if (cat[k].family == "gyro.bias_drift") drift.push_back(static_cast<int>(k));
  return contest_family(dwells, base.parameters, drift, 0.01, &lt);
}

std::string summary(const HeldoutContest& c) {
  return "replaced " + std::to_string(c.replaced) + ", alternative " +
         std::to_string(c.alternative) + ": " + c.reason() + " (held-out chi2 " +
         std::to_string(c.before) + " -> family " + std::to_string(c.family) + ")";
}

}  // namespace

TEST_CASE("Library contest: a bias step refuses the bias drift, a true drift keeps it",
          "[diagnosis][library_contest]") {
  const double dph = units::deg_per_h;
  SECTION("gyro z bias step 0.1 deg/h half-way: the step's term explains the drift's share") {
    const HeldoutContest c = drift_contest(81, [dph](double mid) -> ExtraTerm {
      return [dph, mid](double t, auto&, auto& w) {
        if (t > mid) w(2) += 0.1 * dph;
      };
    });
    INFO(summary(c));
    // The drift alone gains on the held-out data (the library sees the family), the step's term
    // gains with the drift in, the drift gains nothing with the term in.
    CHECK(c.before - c.family > c.family_needed);
    REQUIRE(c.replaced);
    CHECK_FALSE(c.alternative);
    CHECK(c.term.sensor == "gyro");
    CHECK(c.term.axis == 2);
    CHECK(c.term.formula.rfind("step", 0) == 0);
    CHECK(std::abs(c.term.value - 0.1) < 3.0 * c.term.sigma);
    CHECK(c.term_gain >= c.term_needed);
    CHECK(c.family_gain < c.family_needed);
  }
  SECTION("gyro z bias linear in time, 0.6 deg/h per hour: the drift is not refused") {
    const HeldoutContest c = drift_contest(82, [dph](double) -> ExtraTerm {
      return [dph](double t, auto&, auto& w) { w(2) += 0.6 * dph * t / 3600.0; };
    });
    INFO(summary(c));
    CHECK(c.before - c.family > c.family_needed);
    CHECK_FALSE(c.replaced);
  }
}

// The same step through the whole table diagnosis (as `sinscal diagnose`): the round's drift is
// refused by the contest itself (its reason the term's), not only demoted at the end by the
// residual check, and the library reports the step.
TEST_CASE("Library contest: the table diagnosis refuses the drift for a bias step's term",
          "[diagnosis][library_contest]") {
  const HiddenCase c = open_world_case("rot19.ini", "nav-fog.ini", 4, 83, kContestRate);
  const DiagnosisOutcome o = diagnose_hidden(c, {});
  std::string refused;
  for (const auto& r : o.result.rejected) refused += r.finding.family + ": " + r.reason + "; ";
  INFO(o.story << " | refused: " << refused);
  CHECK(o.result.findings.empty());
  REQUIRE_FALSE(o.result.rejected.empty());
  const auto& r = o.result.rejected.front();
  CHECK(r.finding.family == "gyro.bias_drift");
  CHECK(r.reason.find("step after") != std::string::npos);
  CHECK(r.reason.find("predicts the held-out dwells and turns better") != std::string::npos);
}
