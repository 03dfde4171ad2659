// The library's contest with a catalog family on held-out data (filter/diagnosis/term_library.hpp
// contest_family, issue 33): a family is refused when a library term explains its share of the
// held-out dwells and turns better. Generated here: a clean rot19 nav-fog session whose gyro z
// gets either a bias step half-way (outside the catalog: a library term) or a bias linear in time
// (the catalog's gyro.bias_drift), injected into the log by test code. The drift's columns see
// part of the step (a line through a step), so the contest must refuse the drift for the step's
// term and keep it for the true drift. A sign of the contest's comparisons flipped turns one of
// the two red.
#include <catch2/catch.hpp>

#include "catalog.hpp"
#include "filter/diagnosis/term_library.hpp"
#include "out_of_catalog.hpp"

using namespace sinscal;
using namespace sinscal::test;

namespace {

constexpr double kContestRate = 20.0;  // Hz, as the open-world matrix

// A term injected into the log, given the log time of the plan's middle (s).
using TermAt = std::function<ExtraTerm(double mid_s)>;

// The dwells and turns of a case set up as the table diagnosis sets them up (the dwells' model
// with the bias wander and the session grade's priors, with `turn_families` also the families the
// turns' model has on: dwells_model; the turns with the table's attitude sigma), handed to
// `use(dwells, parameters, turns)`.
template <class Use>
auto with_library_inputs(const HiddenCase& c, bool turn_families, const Use& use) {
  const CaseCalibration cc = calibrate_case(c);
  const TurnModel& model = cc.model;
  const ClosedFormReport& cal = cc.calibration;
  Stage2Options base = cal.stage2_options;
  base.bias_wander = model.base.noise;
  if (turn_families) base = dwells_model(cal.stage2_options, &model);  // the diagnosis's own
  DiagnosisOptions o;
  o.prior_sigma = grade_priors(model.base);
  const DwellTests dwells(cal.stage1, c.session.site, base, o);
  LibraryTurns lt;
  lt.session = &c.session;
  lt.attitude_sigma = model.base.attitude_sigma;
  lt.noise = model.base.noise;
  lt.about = model.base.initial_model ? &*model.base.initial_model : nullptr;
  return use(dwells, base.parameters, lt);
}

// The contest of gyro.bias_drift against the library on a clean rot19 nav-fog session (seed)
// with `term_at` injected into its log.
HeldoutContest drift_contest(std::uint64_t seed, const TermAt& term_at) {
  HiddenCase c = hidden_case("library_contest", "rot19.ini", "nav-fog.ini", {}, seed, kContestRate);
  const double mid =
      c.session.time_offset + 0.5 * PlanTimeline::of(c.session.plan, c.session.site).duration;
  inject_into_log(c.session.dir + "/imu.csv", kContestRate, term_at(mid));
  c.session = Session::load(c.session.path);
  const std::vector<int> drift = family_coefficients("gyro.bias_drift");
  return with_library_inputs(
      c, false,
      [&](const DwellTests& dwells, const std::vector<int>& parameters, const LibraryTurns& lt) {
        return contest_family(dwells, parameters, drift, 0.01, &lt);
      });
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

// The library's rate columns on the turns are functions of the table's known motion, not of the
// gyros' outputs (errors in variables): on clean MEMS rot19 sessions the turns' residual along
// gyro i's omega_i |omega_i| is then N(0, 1) at most per seed and axis, zero on average. Built from
// the outputs, whose angle random walk and bias wander the residual integrates too, the columns
// (after the scale factor is projected out, the same rate profile every turn) are mostly that
// noise, and the residual along them averages -2.3 (issue 33: 3 of 4 clean rot19 sessions that
// came out "unexplained" were this term, z^2 16.3-21.8 against 15.5). The mean over the seeds of
// each seed's mean over the three axes: its sigma is at most 1 / sqrt(seeds), whatever the axes'
// correlation; the limit is 4 of those sigmas.
TEST_CASE("Library turns: clean MEMS rot19 rate terms are unbiased",
          "[diagnosis][library_contest]") {
  constexpr int kSeeds = 10;
  double sum = 0.0;
  std::string all;
  for (int k = 0; k < kSeeds; ++k) {
    const HiddenCase c = hidden_case("library_turns_mems", "rot19.ini", "mems.ini", {},
                                     29000 + static_cast<std::uint64_t>(k), kContestRate);
    const LibraryFit f = with_library_inputs(
        c, true,
        [](const DwellTests& dwells, const std::vector<int>& parameters, const LibraryTurns& lt) {
          return fit_term_library(dwells, parameters, 0.01, &lt, false);
        });
    int axes = 0;
    double seed_sum = 0.0;
    for (const auto& [name, z] : f.turns_term_z)
      for (const char* a : {"x", "y", "z"})
        if (name ==
            std::string("gyro ") + a + ": omega_" + a + " |omega_" + a + "| (library term)") {
          ++axes;
          seed_sum += z;
          all += " " + std::to_string(z);
        }
    REQUIRE(axes == 3);
    sum += seed_sum / 3.0;
  }
  const double mean = sum / kSeeds;
  INFO("mean z " << mean << ", each:" << all);
  CHECK(std::abs(mean) < 4.0 / std::sqrt(static_cast<double>(kSeeds)));
}
