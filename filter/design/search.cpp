#include "filter/design/search.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "filter/design/grower.hpp"
#include "filter/design/hand_plans.hpp"
#include "filter/design/structure_moves.hpp"
#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "rig/imu_sim.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

namespace {

const char* const kAxisNames[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
// Heading, pitch, roll (deg, ned-frd) that put body +x, -x, +y, -y, +z, -z up.
const double kStartAngles[6][3] = {{0, 90, 0}, {0, -90, 0}, {0, 0, -90},
                                   {0, 0, 90}, {0, 0, 180}, {0, 0, 0}};
constexpr double kGrid = 0.1;       // s: every duration of a searched plan is a multiple of it
constexpr double kSoftNorm = 16.0;  // Excess::soft_worst

double on_grid(double seconds) { return std::ceil(seconds / kGrid - 1e-9) * kGrid; }

// A plan's turn duration on the table: at its rate and acceleration limits, on the grid.
double turn_duration(double angle, const TableSpec& table) {
  return on_grid(
      TrapezoidProfile::by_rate(angle, table.max_rate, table.max_acceleration).duration());
}

std::vector<TurnChoice> turn_options(const SearchSpace& space) {
  std::vector<TurnChoice> out;
  for (int axis = 0; axis < 6; ++axis)
    for (double angle : space.angles)
      for (double pause : space.pauses) out.push_back({axis, angle, pause});
  return out;
}

SearchSpace completed(SearchSpace space, const TableSpec& table) {
  if (space.angles.empty()) space.angles = {90.0 * units::deg, 180.0 * units::deg};
  if (space.pauses.empty()) space.pauses = {shortest_pause(table), 10.0};
  if (space.starts.empty() || space.start_dwells.empty())
    throw std::invalid_argument("plan search: no start orientation or start dwell to search");
  return space;
}

struct Member {
  Grower grower;
  Excess excess;
  std::vector<SearchStep> path;  // its growth, turn by turn
  SearchStep step() const {
    return {grower.duration(), excess.J, excess.worst_ratio, excess.worst_family};
  }
};

// The members' extensions by every turn option, ranked by the decrease of J per second.
std::vector<Member> expand(const std::vector<Member>& beam, const std::vector<TurnChoice>& turns,
                           const Context& c, int& evaluations) {
  std::vector<Member> children;
  std::vector<double> gain;
  for (const Member& m : beam)
    for (const TurnChoice& t : turns) {
      Grower g = m.grower.extended(t, c);
      if (g.duration() > c.limit + 1e-9) continue;
      const Excess e = g.score(c);
      ++evaluations;
      gain.push_back((m.excess.J - e.J) / std::max(1e-9, g.duration() - m.grower.duration()));
      children.push_back(Member{std::move(g), e, m.path});
      children.back().path.push_back(children.back().step());
    }
  std::vector<std::size_t> order(children.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return gain[a] != gain[b] ? gain[a] > gain[b] : children[a].excess.J < children[b].excess.J;
  });
  std::vector<Member> out;
  for (std::size_t i = 0; i < order.size() && static_cast<int>(out.size()) < c.search.beam; ++i)
    out.push_back(children[order[i]]);
  return out;
}

// Plans of one turn (a rotation plan has at least one), from every start and start dwell: the
// best `beam` of them by J.
std::vector<Member> initial_beam(const SearchSpace& space, const std::vector<TurnChoice>& turns,
                                 const Context& c, int& evaluations) {
  std::vector<Member> all;
  for (int start : space.starts)
    for (double dwell : space.start_dwells)
      for (const TurnChoice& t : turns) {
        PlanGenome g;
        g.start = start;
        g.start_dwell = on_grid(dwell);
        g.turns = {t};
        Grower grower(g, c);
        if (grower.duration() > c.limit + 1e-9) continue;
        const Excess e = grower.score(c);
        ++evaluations;
        all.push_back({std::move(grower), e, {}});
        all.back().path = {all.back().step()};
      }
  std::vector<std::size_t> order(all.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return all[a].excess.J < all[b].excess.J; });
  std::vector<Member> kept;
  for (std::size_t i = 0; i < order.size() && static_cast<int>(kept.size()) < c.search.beam; ++i)
    kept.push_back(all[order[i]]);
  return kept;
}

bool meets(const Excess& e) { return e.J <= 0.0; }

std::string fmt_seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0fs", s);
  return buf;
}

// Turns removed, dwells shortened while the plan still meets every target.
PlanGenome refine(PlanGenome g, const Context& c, int& evaluations) {
  auto ok = [&](const PlanGenome& trial) {
    ++evaluations;
    return meets(evaluate_genome(trial, c.options, c.table, c.site, c.search));
  };
  const double min_pause = shortest_pause(c.table);
  for (bool changed = true; changed;) {
    changed = false;
    for (std::size_t i = g.turns.size(); i-- > 0 && g.turns.size() > 1;) {
      PlanGenome trial = g;
      trial.turns.erase(trial.turns.begin() + static_cast<std::ptrdiff_t>(i));
      if (ok(trial)) {
        g = trial;
        changed = true;
      }
    }
    for (std::size_t i = 0; i < g.turns.size(); ++i) {
      if (g.turns[i].pause <= min_pause) continue;
      PlanGenome trial = g;
      trial.turns[i].pause = std::max(min_pause, on_grid(0.5 * g.turns[i].pause));
      if (ok(trial)) {
        g = trial;
        changed = true;
      }
    }
    if (g.start_dwell > min_pause) {
      PlanGenome trial = g;
      trial.start_dwell = std::max(min_pause, on_grid(0.5 * g.start_dwell));
      if (ok(trial)) {
        g = trial;
        changed = true;
      }
    }
  }
  return g;
}

// A plan's excess by the design's pass at the search's rate (no history).
Excess plan_excess(const Plan& plan, const Context& c) {
  DesignOptions d;
  d.rate_hz = c.search.rate_hz;
  d.history_interval = 1e9;
  return excess(predict_plan(plan, c.options, c.search.targets, d).run.estimates, c.search.targets);
}

bool within(const Plan& plan, const Context& c) {
  const Motion m = build_motion(plan, plan.site);
  return m.duration() <= c.search.budget_s + 1e-6 &&
         check_against_table(m, c.table, c.options.static_margin).empty();
}

// The seeds as they are and scaled to the budget: the best on the worst ratio replaces the
// beam's plan when it is better.
void seeded(SearchResult& r, const Context& c) {
  const double min_dwell = shortest_pause(c.table);
  for (const Plan& seed : c.search.seeds) {
    std::vector<Plan> candidates;
    if (within(seed, c)) candidates.push_back(seed);
    if (auto scaled = dwell_scaled(seed, c.search.budget_s, min_dwell);
        scaled && within(*scaled, c))
      candidates.push_back(*scaled);
    for (const Plan& p : candidates) {
      const Excess e = plan_excess(p, c);
      ++r.evaluations;
      r.candidates.emplace_back(p.name, e.worst_ratio);
      if (e.worst_ratio < r.excess.worst_ratio) {
        r.excess = e;
        r.plan = p;
        r.text = p.text;
        r.origin = p.name;
      }
    }
  }
}

// Time moved between the result's dwells while its worst ratio falls, the total kept: a dwell
// gains a fraction of itself, taken from the others in proportion to their time above the
// shortest dwell; the fraction halves when no dwell gains.
void improve(SearchResult& r, const Context& c) {
  std::vector<double> d = plan_dwells(r.plan);
  const double min_dwell = shortest_pause(c.table);
  int left = c.search.improvement_passes;
  for (double step = 0.25; left > 0 && step > 0.02;) {
    bool improved = false;
    for (std::size_t i = 0; i < d.size() && left > 0; ++i) {
      double spare = 0.0;
      for (std::size_t j = 0; j < d.size(); ++j)
        if (j != i) spare += std::max(0.0, d[j] - min_dwell);
      const double add = step * d[i];
      if (spare < 2.0 * add) continue;
      std::vector<double> t = d;
      for (std::size_t j = 0; j < d.size(); ++j)
        t[j] = j == i ? d[j] + add : d[j] - add * std::max(0.0, d[j] - min_dwell) / spare;
      const Plan p = with_dwells(r.plan, t);
      if (!within(p, c)) continue;
      const Excess e = plan_excess(p, c);
      --left;
      ++r.evaluations;
      if (e.worst_ratio < r.excess.worst_ratio) {
        r.excess = e;
        r.plan = p;
        r.text = p.text;
        d = t;
        improved = true;
      }
    }
    if (!improved) step *= 0.5;
  }
}

// The structure moves (filter/design/structure_moves.hpp) from the best plan so far and from the
// beam's and the seeds' rotation plans at the table's limits: their plan replaces the best when
// its worst ratio is smaller.
void restructure(SearchResult& r, const Context& c) {
  std::vector<PlanGenome> starts;
  if (auto g = genome_of(r.plan, c.table)) starts.push_back(*g);
  if (r.origin != "beam") starts.push_back(r.best);
  for (const Plan& seed : c.search.seeds)
    if (auto g = genome_of(seed, c.table)) starts.push_back(*g);
  const auto score = [&](const PlanGenome& g) { return Grower(g, c).score(c); };
  if (starts.empty()) return;
  // The passes by the cost of one: the filter's states from a pass over a start's first turn.
  PlanGenome probe = starts.front();
  probe.turns.resize(1);
  const int states = Grower(probe, c).layout().size;
  r.structure_limit = structure_pass_limit(c.search.structure_evaluations, c.search.budget_s,
                                           c.search.rate_hz, states);
  const auto s =
      structure_search(starts, c.search.budget_s, c.table, c.site, r.structure_limit, score);
  if (!s) return;
  r.evaluations += s->evaluations;
  r.structure_evaluations = s->evaluations;
  for (const auto& step : s->path) r.structure.emplace_back(step.move, step.worst_ratio);
  if (!(s->excess.worst_ratio < r.excess.worst_ratio)) return;
  r.best = s->genome;
  r.plan = plan_of(r.best, c.table, c.site, c.search.name);
  r.text = plan_text(r.best, c.table, c.site, c.search.name);
  r.excess = s->excess;
  r.origin = "structure moves";
}

}  // namespace

Grower::Grower(const PlanGenome& genome, const Context& c) : g_(genome) {
  const Plan plan = plan_of(g_, c.table, c.site, c.search.name);
  kf_ = std::make_shared<Calibrator>(PlanTimeline::of(plan, c.site), c.site,
                                     design_filter_options(c.options));
  run(plan, c);
}

Grower Grower::extended(const TurnChoice& turn, const Context& c) const {
  Grower next = *this;
  next.kf_ = std::make_shared<Calibrator>(*kf_);  // the copy goes on, this one stays
  next.g_.turns.push_back(turn);
  const Plan plan = plan_of(next.g_, c.table, c.site, c.search.name);
  next.kf_->extend_timeline(PlanTimeline::of(plan, c.site));
  next.run(plan, c);
  return next;
}

Excess Grower::score(const Context& c) const {
  Calibrator done = *kf_;
  done.finish();
  return excess(estimates_in_reported_frame(done, c.options), c.search.targets);
}

Eigen::MatrixXd Grower::coefficient_and_base_covariance() const {
  Calibrator done = *kf_;
  done.finish();
  const StateLayout& l = done.layout();
  const int first = l.nav_size, n = l.coefficient_states();
  if (l.base.size != 3 || l.base.index != first + n)
    throw std::logic_error("design bound: the table base's states do not follow the coefficients");
  const int m = n + l.base.size;
  return done.covariance().block(first, first, m, m);
}

Eigen::MatrixXd Grower::coefficient_covariance() const {
  Calibrator done = *kf_;
  done.finish();
  const StateLayout& l = done.layout();
  const int first = l.nav_size, n = l.coefficient_states();
  return done.covariance().block(first, first, n, n);
}

void Grower::run(const Plan& plan, const Context& c) {
  const auto shared = std::make_shared<const Motion>(build_motion(plan, c.site));
  const Motion& motion = *shared;
  // Along the plan's motion, as run_kalman's pass of the design over the whole plan.
  if (follows_plan_motion(design_filter_options(c.options))) kf_->set_reference_motion(shared);
  SimulatorOptions so;
  so.rate_hz = c.search.rate_hz;
  so.noise = false;
  ImuSimulator ideal(motion, ImuErrorModel{}, NoiseModel{}, so);
  ideal.skip_to(pushed_);
  ImuSample s;
  while (ideal.next(s)) kf_->push(s);
  pushed_ = ideal.total_samples();
  duration_ = motion.duration();
}

double shortest_pause(const TableSpec& table) { return on_grid(table.settling_time + 1.0 + 0.5); }

std::string plan_text(const PlanGenome& g, const TableSpec& table, const Site& site,
                      const std::string& name) {
  if (g.start < 0 || g.start > 5) throw std::invalid_argument("plan search: start out of range");
  std::ostringstream out;
  out.precision(12);
  out << "# Searched by sinscal design --optimize for the table " << table.name
      << ": turns at its limits (" << table.max_rate / units::deg_per_s << " deg/s, "
      << table.max_acceleration / units::deg_per_s << " deg/s^2).\n"
      << "[plan]\nname = " << name << "\ntype = rotations\nconvention = ned-frd\n"
      << "rotation_acceleration = " << table.max_acceleration / units::deg_per_s << " deg/s^2\n"
      << "\n[site]\nlatitude = " << site.lat_rad / units::deg
      << " deg\nlongitude = " << site.lon_rad / units::deg << " deg\nheight = " << site.h_m
      << " m\n"
      << "\n[start]\nheading = " << kStartAngles[g.start][0]
      << " deg\npitch = " << kStartAngles[g.start][1] << " deg\nroll = " << kStartAngles[g.start][2]
      << " deg\ndwell = " << g.start_dwell << " s\n";
  if (g.turns.empty()) return out.str();
  std::string axes, angles, durations, pauses;
  char buf[64];
  for (const auto& t : g.turns) {
    axes += std::string(axes.empty() ? "" : " ") + kAxisNames[t.axis];
    std::snprintf(buf, sizeof buf, "%s%.6g", angles.empty() ? "" : " ", t.angle / units::deg);
    angles += buf;
    std::snprintf(buf, sizeof buf, "%s%.1f", durations.empty() ? "" : " ",
                  turn_duration(t.angle, table));
    durations += buf;
    std::snprintf(buf, sizeof buf, "%s%.1f", pauses.empty() ? "" : " ", t.pause);
    pauses += buf;
  }
  out << "\n[rotations]\naxes = " << axes << "\nangles = " << angles
      << " deg\ndurations = " << durations << " s\npauses = " << pauses << " s\n";
  return out.str();
}

Plan plan_of(const PlanGenome& g, const TableSpec& table, const Site& site,
             const std::string& name) {
  return Plan::parse(name + ".ini", plan_text(g, table, site, name));
}

Excess excess(const std::vector<CoefficientEstimate>& estimates,
              const std::map<std::string, double>& targets) {
  std::map<std::string, double> worst;  // family: sigma / target
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (estimates[i].status != CoefficientEstimate::Status::Estimated) continue;
    const auto t = targets.find(cat[i].family);
    if (t == targets.end() || !(t->second > 0.0)) continue;
    double& w = worst[cat[i].family];
    w = std::max(w, estimates[i].sigma / t->second);
  }
  Excess e;
  for (const auto& [family, ratio] : worst) {
    e.soft_worst += std::pow(ratio, kSoftNorm);
    e.J += std::max(0.0, std::log(ratio));
    if (ratio > e.worst_ratio) {
      e.worst_ratio = ratio;
      e.worst_family = family;
    }
  }
  e.soft_worst = std::pow(e.soft_worst, 1.0 / kSoftNorm);
  return e;
}

std::map<std::string, double> required_targets(std::map<std::string, double> targets,
                                               const std::vector<std::string>& required,
                                               const std::vector<CoefficientEstimate>& estimates) {
  const auto& cat = coefficient_catalog();
  for (const std::string& family : required) {
    double prior = 0.0;
    for (std::size_t i = 0; i < cat.size(); ++i)
      if (cat[i].family == family && estimates[i].status == CoefficientEstimate::Status::Estimated)
        prior = prior > 0.0 ? std::min(prior, estimates[i].prior_sigma) : estimates[i].prior_sigma;
    if (!(prior > 0.0))
      throw std::invalid_argument("required family '" + family +
                                  "' is not estimated with this profile and these terms");
    const double t = kRequiredFraction * prior;
    const auto it = targets.find(family);
    if (it == targets.end() || !(it->second > 0.0) || it->second > t) targets[family] = t;
  }
  return targets;
}

Excess evaluate_genome(const PlanGenome& genome, const CalibratorOptions& options,
                       const TableSpec& table, const Site& site, const SearchOptions& search) {
  const Context c{options, table, site, search};
  return Grower(genome, c).score(c);
}

SearchResult search_plan(const CalibratorOptions& options, const TableSpec& table, const Site& site,
                         const SearchSpace& space_in, const SearchOptions& search) {
  if (search.targets.empty()) throw std::invalid_argument("plan search: no targets");
  const SearchSpace space = completed(space_in, table);
  const double limit = search.budget_s > 0.0 ? search.budget_s : search.max_duration;
  const Context c{options, table, site, search, limit};
  SearchResult r;
  const auto turns = turn_options(space);
  std::vector<Member> beam = initial_beam(space, turns, c, r.evaluations);
  std::optional<Member> best;  // meeting: the shortest; else (budget) the smallest J
  for (;;) {
    for (const Member& m : beam) {
      const bool better = !best ||
                          (meets(m.excess) && (!meets(best->excess) ||
                                               m.grower.duration() < best->grower.duration())) ||
                          (!meets(best->excess) && m.excess.J < best->excess.J);
      if (better) best = m;
    }
    if (best && meets(best->excess)) break;
    beam = expand(beam, turns, c, r.evaluations);
    if (beam.empty()) break;  // every extension beyond the limit
  }
  if (!best) throw std::runtime_error("plan search: no plan within the time limit");
  r.path = best->path;
  r.duration_before_refinement = best->grower.duration();
  r.best = best->grower.genome();
  if (meets(best->excess)) r.best = refine(r.best, c, r.evaluations);
  r.plan = plan_of(r.best, table, site, search.name);
  r.text = plan_text(r.best, table, site, search.name);
  r.excess = evaluate_genome(r.best, options, table, site, search);
  ++r.evaluations;
  if (search.budget_s > 0.0 && !search.seeds.empty()) seeded(r, c);
  if (search.budget_s > 0.0 && search.improvement_passes > 0 && r.origin != "beam") improve(r, c);
  if (search.budget_s > 0.0 && search.structure_evaluations > 0) restructure(r, c);
  r.meets = meets(r.excess);
  return r;
}

std::vector<SearchResult> search_budgets(const CalibratorOptions& options, const TableSpec& table,
                                         const Site& site, const SearchSpace& space,
                                         SearchOptions search, std::vector<double> budgets) {
  std::sort(budgets.begin(), budgets.end());
  const std::size_t given = search.seeds.size();
  std::vector<SearchResult> out;
  for (double b : budgets) {
    search.budget_s = b;
    out.push_back(search_plan(options, table, site, space, search));
    if (!search.carry_up) continue;
    // The last budget's plan is at least as good as every shorter one's: it alone is carried.
    search.seeds.resize(given);
    search.seeds.push_back(renamed(out.back().plan, "searched-" + fmt_seconds(b)));
  }
  return out;
}

std::pair<PlanGenome, Excess> enumerate_plans(const CalibratorOptions& options,
                                              const TableSpec& table, const Site& site,
                                              const SearchSpace& space_in,
                                              const SearchOptions& search, int turns, int* scored) {
  const SearchSpace space = completed(space_in, table);
  const Context c{options, table, site, search};
  PlanGenome root;
  root.start = space.starts.front();
  root.start_dwell = on_grid(space.start_dwells.front());
  const auto options_list = turn_options(space);
  std::pair<PlanGenome, Excess> best{root, Excess{1e300, 1e300, ""}};
  int count = 0;
  // Depth first: each prefix's filter is shared by its extensions.
  std::vector<std::pair<Grower, int>> stack;
  for (const TurnChoice& t : options_list) {
    PlanGenome g = root;
    g.turns = {t};
    stack.emplace_back(Grower(g, c), 1);
  }
  while (!stack.empty()) {
    auto [g, depth] = std::move(stack.back());
    stack.pop_back();
    if (depth == turns) {
      const Excess e = g.score(c);
      ++count;
      const bool better =
          search.minimax ? e.worst_ratio < best.second.worst_ratio : e.J < best.second.J;
      if (better) best = {g.genome(), e};
      continue;
    }
    for (const TurnChoice& t : options_list) stack.emplace_back(g.extended(t, c), depth + 1);
  }
  if (scored) *scored = count;
  return best;
}

std::pair<PlanGenome, Excess> beam_plans(const CalibratorOptions& options, const TableSpec& table,
                                         const Site& site, const SearchSpace& space_in,
                                         const SearchOptions& search, int turns) {
  const SearchSpace space = completed(space_in, table);
  const Context c{options, table, site, search};
  const auto options_list = turn_options(space);
  int evaluations = 0;
  SearchSpace one = space;
  one.starts = {space.starts.front()};
  one.start_dwells = {space.start_dwells.front()};
  std::vector<Member> beam = initial_beam(one, options_list, c, evaluations);
  for (int k = 1; k < turns; ++k) beam = expand(beam, options_list, c, evaluations);
  const auto it = std::min_element(beam.begin(), beam.end(), [](const Member& a, const Member& b) {
    return a.excess.J < b.excess.J;
  });
  return {it->grower.genome(), it->excess};
}

}  // namespace sinscal
