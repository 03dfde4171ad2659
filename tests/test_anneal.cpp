// Plan design's simulated annealing (filter/design/anneal.hpp): the Metropolis rule takes better
// plans and worse ones only with their probability, a seed gives one result, the best plan is
// never worse than the start, on a short budget it is at least as good as the structure moves
// alone from the same start with the same passes, and its plan reads back and simulates. Also
// the north carousel's geometry.
#include <catch2/catch.hpp>
#include <cmath>

#include "filter/design/anneal.hpp"
#include "filter/design/prediction.hpp"
#include "filter/design/search.hpp"
#include "filter/design/structure_moves.hpp"
#include "helpers.hpp"
#include "models/config.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "plan_playback.hpp"
#include "rig/imu_sim.hpp"
#include "rig/table_spec.hpp"

using namespace sinscal;

namespace {

const char* kFog = "config/sensors/nav-fog-extended.ini";

// The toolbox's mode and targets (issue 36) on two-axis-20, scored at `rate_hz`.
struct Case {
  TableSpec table = TableSpec::load(test::source_path("config/tables/two-axis-20.ini"));
  CalibratorOptions ko;
  SearchOptions so;
  Site site = test::load_plan("rot19.ini").site;
  explicit Case(double rate_hz) {
    ko = calibrator_options_from_profile(SensorProfile::load(test::source_path(kFog)));
    ko.attitude = CalibratorOptions::AttitudeUpdates::None;
    ko.zero_velocity_in_motion = table.reference_on_axes;
    so.targets =
        read_sigma_targets(IniFile(test::source_path("config/targets/reference-toolbox.ini")));
    so.rate_hz = rate_hz;
  }
  std::function<Excess(const PlanGenome&)> score() const {
    return [this](const PlanGenome& g) { return evaluate_genome(g, ko, table, site, so); };
  }
};

// The small case of the tests below: rot19's 18 turns (body x up), fitted to a short budget.
PlanGenome short_start(const TableSpec& table) {
  return *genome_of(test::load_plan("rot19.ini"), table);
}

// The body axis (0 x, 1 y, 2 z; negative: its opposite, -1 - axis) along `n` after the first
// `turns` turns of `g`.
int body_axis_along(const PlanGenome& g, std::size_t turns, const Eigen::Vector3d& n,
                    const TableSpec& table, const Site& site) {
  PlanGenome h = g;
  h.turns.resize(turns);
  if (h.turns.empty()) h.turns = {{0, 360.0 * units::deg, 10.0}};  // a full turn: the start
  const Plan p = plan_of(h, table, site, "h");
  const Motion m = build_motion(p, p.site);
  const Eigen::Vector3d n_b = m.at(m.duration()).C_b_n.transpose() * n;
  for (int i = 0; i < 3; ++i)
    if (std::abs(std::abs(n_b[i]) - 1.0) < 1e-9) return n_b[i] > 0.0 ? i : -1 - i;
  return 99;
}

}  // namespace

TEST_CASE("Annealing: the Metropolis rule on the log of the smooth worst ratio", "[design]") {
  // A plan no worse is always taken; one 1 % worse at the temperature 0.01 with probability
  // exp(-ln 1.01 / 0.01) = 0.370, at 1e-4 practically never; geometric cooling between.
  CHECK(anneal_accepts(1.0, 0.99, 1e-4, 0.999999));
  CHECK(anneal_accepts(1.0, 1.0, 0.0, 0.5));
  const double p = std::exp(-std::log(1.01) / 0.01);
  CHECK(p == Approx(0.3697).epsilon(1e-3));
  CHECK(anneal_accepts(1.0, 1.01, 0.01, 0.99 * p));
  CHECK_FALSE(anneal_accepts(1.0, 1.01, 0.01, 1.01 * p));
  CHECK_FALSE(anneal_accepts(1.0, 1.01, 1e-4, 1e-12));
  CHECK_FALSE(anneal_accepts(1.0, 1.5, 0.0, 0.0));
  AnnealOptions o;
  o.iterations = 101;
  CHECK(anneal_temperature(o, 0) == Approx(o.t_start));
  CHECK(anneal_temperature(o, 50) == Approx(std::sqrt(o.t_start * o.t_end)));
  CHECK(anneal_temperature(o, 100) == Approx(o.t_end));
}

TEST_CASE("North carousel: each body axis north in turn while the table turns about it",
          "[design]") {
  const Case c(5.0);
  const double step = 45.0 * units::deg;
  const PlanGenome g = north_carousel(step, 5.0);
  REQUIRE(g.turns.size() == 50);
  const Eigen::Vector3d north = Eigen::Vector3d::UnitX(), up = -Eigen::Vector3d::UnitZ();
  CHECK(body_axis_along(g, 0, up, c.table, c.site) == 0);
  CHECK(body_axis_along(g, 0, north, c.table, c.site) == 2);
  // Forwards then back: after each block the start; after 4 steps of the first, z still north.
  CHECK(body_axis_along(g, 4, north, c.table, c.site) == 2);
  CHECK(body_axis_along(g, 16, up, c.table, c.site) == 0);
  CHECK(body_axis_along(g, 17, north, c.table, c.site) == 1);  // y north
  CHECK(body_axis_along(g, 25, north, c.table, c.site) == 1);  // y north, half way about it
  CHECK(body_axis_along(g, 34, north, c.table, c.site) == 0);  // x north
  CHECK(body_axis_along(g, 42, north, c.table, c.site) == 0);
  CHECK(body_axis_along(g, 50, north, c.table, c.site) == 0);
  CHECK_THROWS_AS(north_carousel(50.0 * units::deg, 5.0), std::invalid_argument);
  // Fitted to 491 s with equal dwells it is a plan file the table runs.
  const auto f = fitted(g, 491.0, shortest_pause(c.table), c.table, c.site);
  REQUIRE(f);
  const Plan p = plan_of(*f, c.table, c.site, "carousel");
  CHECK(build_motion(p, p.site).duration() <= 491.0 + 1e-6);
  CHECK(check_against_table(build_motion(p, p.site), c.table, 0.5).empty());
  for (const TurnChoice& t : f->turns) CHECK(t.pause == Approx(f->start_dwell).margin(0.1 + 1e-9));
}

TEST_CASE("Annealing: deterministic, never worse than its start, as good as the moves alone",
          "[design][search]") {
  // A small case: rot19's turns within 250 s, scored at 5 Hz. The structure moves
  // alone and the annealing from the same start with the same number of passes.
  const Case c(5.0);
  const double budget = 250.0;
  const PlanGenome start = short_start(c.table);
  AnnealOptions o;
  o.iterations = 150;
  o.seed = 7;
  const auto a = anneal(start, budget, c.table, c.site, o, c.score());
  const auto b = anneal(start, budget, c.table, c.site, o, c.score());
  REQUIRE(a);
  REQUIRE(b);
  CAPTURE(a->start.worst_ratio, a->excess.worst_ratio, a->excess.worst_family, a->evaluations,
          a->accepted, a->accepted_worse);
  // Deterministic with a seed: the same plan, score and path.
  CHECK(plan_text(a->genome, c.table, c.site, "a") == plan_text(b->genome, c.table, c.site, "a"));
  CHECK(a->excess.worst_ratio == b->excess.worst_ratio);
  CHECK(a->evaluations == b->evaluations);
  CHECK(a->accepted == b->accepted);
  // Never worse than its start, and it went somewhere: it took worse plans on the way (the
  // temperature lets it) and ended better.
  CHECK(a->excess.worst_ratio <= a->start.worst_ratio);
  CHECK(a->accepted_worse > 0);
  CHECK(a->accepted_worse < a->accepted);
  CHECK(a->excess.worst_ratio < a->start.worst_ratio);
  // The structure moves alone from the same start with as many passes.
  const auto s = structure_search({start}, budget, c.table, c.site, a->evaluations, c.score());
  REQUIRE(s);
  CAPTURE(s->excess.worst_ratio, s->evaluations);
  CHECK(a->excess.worst_ratio <= s->excess.worst_ratio);
  // The plan reads back, lasts at most the budget, is the plan scored and simulates.
  const Plan p = plan_of(a->genome, c.table, c.site, "annealed");
  const Plan again = Plan::parse("again.ini", p.text);
  CHECK(again.text == p.text);
  const double duration = build_motion(again, again.site).duration();
  CHECK(duration <= budget + 1e-6);
  CHECK(check_against_table(build_motion(again, again.site), c.table, 0.5).empty());
  const auto back = genome_of(again, c.table);
  REQUIRE(back);
  CHECK(c.score()(*back).worst_ratio == Approx(a->excess.worst_ratio).epsilon(1e-9));
  CHECK(samples_played(again, 10.0) == Approx(duration * 10.0).margin(1.0));
  WARN("250 s, 5 Hz, " << a->evaluations << " passes: start " << a->start.worst_ratio
                       << ", annealing " << a->excess.worst_ratio << " (" << a->accepted
                       << " taken, " << a->accepted_worse << " worse), structure moves "
                       << s->excess.worst_ratio);
}

TEST_CASE("Annealing in the search's result: replaces the plan only when better", "[design]") {
  const Case c(5.0);
  SearchResult r;
  SearchOptions so = c.so;
  so.budget_s = 250.0;
  r.best = *fitted(short_start(c.table), so.budget_s, shortest_pause(c.table), c.table, c.site);
  r.plan = plan_of(r.best, c.table, c.site, so.name);
  r.text = plan_text(r.best, c.table, c.site, so.name);
  r.excess = c.score()(r.best);
  r.origin = "beam";
  AnnealOptions o;
  o.iterations = 40;
  SearchResult annealed = r;
  const auto a = anneal_search_result(annealed, c.ko, c.table, c.site, so, o);
  REQUIRE(a);
  CHECK(a->start.worst_ratio == Approx(r.excess.worst_ratio).epsilon(1e-9));
  REQUIRE(a->excess.worst_ratio < r.excess.worst_ratio);
  CHECK(annealed.origin == "annealing");
  CHECK(annealed.excess.worst_ratio == a->excess.worst_ratio);
  CHECK(annealed.evaluations == a->evaluations);
  CHECK(annealed.text == plan_text(a->genome, c.table, c.site, so.name));
  // A result already better than anything the annealing finds stays as it is.
  SearchResult kept = r;
  kept.excess.worst_ratio = 0.5 * a->excess.worst_ratio;
  REQUIRE(anneal_search_result(kept, c.ko, c.table, c.site, so, o));
  CHECK(kept.origin == "beam");
  CHECK(kept.text == r.text);
  // Without a budget there is nothing to anneal within.
  so.budget_s = 0.0;
  CHECK_FALSE(anneal_search_result(kept, c.ko, c.table, c.site, so, o));
}
