#include "filter/design/structure_moves.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "models/units.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

namespace {

const char* const kAxisNames[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
constexpr double kGrid = 0.1;  // s, the search's grid (filter/design/search.cpp)
constexpr double kSplitAbove = 59.0 * units::deg;  // a turn split into halves (60 deg: 30 + 30)
constexpr double kInsertAngle = 45.0 * units::deg;
const double kAngles[] = {30.0 * units::deg, 45.0 * units::deg, 60.0 * units::deg,
                          90.0 * units::deg, 180.0 * units::deg};

int tenths(double s) { return static_cast<int>(std::floor(s / kGrid + 1e-6)); }

std::vector<double> dwells_of(const PlanGenome& g) {
  std::vector<double> d = {g.start_dwell};
  for (const TurnChoice& t : g.turns) d.push_back(t.pause);
  return d;
}

double duration_of(const PlanGenome& g, const TableSpec& table, const Site& site) {
  return build_motion(plan_of(g, table, site, "structure"), site).duration();
}

// `spare` grid steps shared in proportion to `weights` (largest remainders), each a whole step.
std::vector<int> shared_steps(const std::vector<double>& weights, int spare) {
  double total = 0.0;
  for (double w : weights) total += w;
  std::vector<int> out(weights.size(), 0);
  std::vector<std::pair<double, std::size_t>> rest;
  int given = 0;
  for (std::size_t i = 0; i < weights.size(); ++i) {
    const double share = total > 0.0
                             ? spare * weights[i] / total
                             : static_cast<double>(spare) / static_cast<double>(weights.size());
    out[i] = static_cast<int>(std::floor(share));
    given += out[i];
    rest.emplace_back(share - out[i], i);
  }
  std::stable_sort(rest.begin(), rest.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  for (std::size_t k = 0; given < spare && k < rest.size(); ++k, ++given) ++out[rest[k].second];
  return out;
}

bool is_vertical_start(int start) { return start >= 0 && start < 6; }

void add_global_moves(const PlanGenome& g, std::vector<StructureMove>& out) {
  using K = StructureMove::Kind;
  if (std::any_of(g.turns.begin(), g.turns.end(),
                  [](const TurnChoice& t) { return t.angle > kSplitAbove; }))
    out.push_back({K::SplitAll, 0, 0, 0.0});
  if (!is_vertical_start(g.start)) return;
  // Body axis `start` is up at the start (search.hpp): a turn about it is about the vertical.
  out.push_back({K::Insert, 0, g.start, kInsertAngle});
  out.push_back({K::Insert, 0, g.start ^ 1, kInsertAngle});
}

void add_turn_moves(const PlanGenome& g, std::size_t i, std::vector<StructureMove>& out) {
  using K = StructureMove::Kind;
  const TurnChoice& t = g.turns[i];
  if (t.angle > kSplitAbove) out.push_back({K::Split, i, 0, 0.0});
  if (g.turns.size() > 1) out.push_back({K::Remove, i, 0, 0.0});
  for (int a = 0; a < 6; ++a)
    if (a != t.axis) out.push_back({K::Axis, i, a, 0.0});
  for (double angle : kAngles)
    if (std::abs(angle - t.angle) > 1e-9) out.push_back({K::Angle, i, 0, angle});
  if (i + 1 < g.turns.size() &&
      (g.turns[i + 1].axis != t.axis || std::abs(g.turns[i + 1].angle - t.angle) > 1e-9))
    out.push_back({K::Swap, i, 0, 0.0});
}

struct State {
  PlanGenome genome;
  Excess excess;
};

// The moves rank by the smooth worst ratio; the result is the plan of the smallest worst ratio
// seen.
bool better(const Excess& a, const Excess& b) { return a.soft_worst < b.soft_worst * (1.0 - 1e-6); }

// What structure_search needs beside the state.
struct Search {
  double budget, min_dwell;
  const TableSpec& table;
  const Site& site;
  int max_evaluations;
  const std::function<Excess(const PlanGenome&)>& score;
  int evaluations = 0;
  std::optional<State> best;  // of the smallest worst ratio
  bool spent() const { return evaluations >= max_evaluations; }
  Excess scored(const PlanGenome& g) {
    Excess e = score(g);
    ++evaluations;
    if (!best || e.worst_ratio < best->excess.worst_ratio) best = State{g, e};
    return e;
  }
  // The candidate's score when it fits the budget and beats `s` (then it replaces `s`).
  bool try_candidate(State& s, const PlanGenome& g, const std::vector<double>& dwells) {
    const auto f = fitted(g, dwells, budget, min_dwell, table, site);
    if (!f) return false;
    const Excess e = scored(*f);
    if (!better(e, s.excess)) return false;
    s = {*f, e};
    return true;
  }
};

// Time moved between the dwells while the worst ratio falls (as search.cpp's improve for seeds):
// a dwell gains `step` of itself, taken from the others in proportion to their time above the
// shortest dwell; the step halves after a sweep without a gain, down to `last_step`.
void improve_dwells(State& s, Search& k, double step, double last_step) {
  for (; step >= last_step && !k.spent();) {
    bool improved = false;
    for (std::size_t i = 0; i <= s.genome.turns.size() && !k.spent(); ++i) {
      const std::vector<double> d = dwells_of(s.genome);
      std::vector<double> t = d;
      t[i] += step * d[i];
      improved = k.try_candidate(s, s.genome, t) || improved;
    }
    if (!improved) step *= 0.5;
  }
}

// The first move (in structure_moves' order) that lowers the worst ratio, taken.
bool one_move(State& s, Search& k, unsigned round, std::vector<StructureStep>& path) {
  for (const StructureMove& m : structure_moves(s.genome, 36u + round)) {
    if (k.spent()) return false;
    const PlanGenome g = applied(s.genome, m, k.min_dwell);
    if (k.try_candidate(s, g, dwells_of(g))) {
      path.push_back({m.describe(), s.excess.worst_ratio, k.evaluations});
      return true;
    }
  }
  return false;
}

}  // namespace

std::string StructureMove::describe() const {
  const std::string n = std::to_string(index + 1);
  const std::string deg = std::to_string(static_cast<int>(std::lround(angle / units::deg)));
  switch (kind) {
    case Kind::SplitAll:
      return "every turn above 60 deg split into two halves";
    case Kind::Split:
      return "turn " + n + " split into two halves";
    case Kind::Insert:
      return deg + " deg turn about " + kAxisNames[axis] + " inserted as turn " + n;
    case Kind::Remove:
      return "turn " + n + " removed";
    case Kind::Axis:
      return "turn " + n + " about " + kAxisNames[axis];
    case Kind::Angle:
      return "turn " + n + " of " + deg + " deg";
    case Kind::Swap:
      return "turns " + n + " and " + std::to_string(index + 2) + " swapped";
  }
  return "";
}

std::optional<PlanGenome> genome_of(const Plan& plan, const TableSpec& table) {
  if (plan.type != Plan::Type::Rotations || plan.convention != AngleConvention::NedFrd)
    return std::nullopt;
  PlanGenome g;
  g.start = -1;
  for (int s = 0; s < 6 && g.start < 0; ++s) {
    PlanGenome h;  // a plan file has at least one turn
    h.start = s;
    h.start_dwell = 10.0;
    h.turns = {{0, 90.0 * units::deg, 10.0}};
    const EulerAngles a = plan_of(h, table, plan.site, "start").start;
    if (std::abs(a.heading - plan.start.heading) < 1e-9 &&
        std::abs(a.pitch - plan.start.pitch) < 1e-9 && std::abs(a.roll - plan.start.roll) < 1e-9)
      g.start = s;
  }
  if (g.start < 0 || plan.steps.empty()) return std::nullopt;
  g.start_dwell = tenths(plan.start_dwell) * kGrid;
  for (const RotationStep& s : plan.steps) {
    const auto* name = std::find(std::begin(kAxisNames), std::end(kAxisNames), s.axis_name);
    if (s.kind != RotationStep::Axis::Body || s.constant_rate || name == std::end(kAxisNames) ||
        !(s.angle > 0.0))
      return std::nullopt;
    g.turns.push_back(
        {static_cast<int>(name - std::begin(kAxisNames)), s.angle, tenths(s.pause) * kGrid});
  }
  return g;
}

std::optional<PlanGenome> fitted(const PlanGenome& g, const std::vector<double>& dwells,
                                 double budget, double min_dwell, const TableSpec& table,
                                 const Site& site) {
  if (dwells.size() != g.turns.size() + 1)
    throw std::invalid_argument("structure moves: not one duration per dwell");
  double dwell_sum = 0.0;
  for (double d : dwells_of(g)) dwell_sum += d;
  const double turns_time = duration_of(g, table, site) - dwell_sum;
  const int n = static_cast<int>(dwells.size());
  const int available = tenths(budget - turns_time);
  const int shortest = static_cast<int>(std::lround(min_dwell / kGrid));
  if (available < n * shortest) return std::nullopt;
  std::vector<double> above;
  above.reserve(dwells.size());
  for (double d : dwells) above.push_back(std::max(0.0, d - min_dwell));
  const std::vector<int> extra = shared_steps(above, available - n * shortest);
  PlanGenome out = g;
  out.start_dwell = (shortest + extra[0]) * kGrid;
  for (std::size_t i = 0; i < out.turns.size(); ++i)
    out.turns[i].pause = (shortest + extra[i + 1]) * kGrid;
  return out;
}

std::optional<PlanGenome> fitted(const PlanGenome& g, double budget, double min_dwell,
                                 const TableSpec& table, const Site& site) {
  return fitted(g, dwells_of(g), budget, min_dwell, table, site);
}

PlanGenome applied(const PlanGenome& g, const StructureMove& m, double min_dwell) {
  using K = StructureMove::Kind;
  const std::size_t n = g.turns.size();
  const bool at_turn = m.kind != K::SplitAll && m.kind != K::Insert;
  if ((at_turn && m.index >= n) || (m.kind == K::Insert && m.index > n) ||
      (m.kind == K::Swap && m.index + 1 >= n) || (m.kind == K::Remove && n < 2) || m.axis < 0 ||
      m.axis > 5)
    throw std::invalid_argument("structure moves: '" + m.describe() + "' does not apply");
  PlanGenome out = g;
  auto& t = out.turns;
  const auto at = t.begin() + static_cast<std::ptrdiff_t>(m.index);
  switch (m.kind) {
    case K::SplitAll:
      t.clear();
      for (const TurnChoice& c : g.turns)
        if (c.angle > kSplitAbove) {
          t.push_back({c.axis, 0.5 * c.angle, c.pause});
          t.push_back({c.axis, 0.5 * c.angle, c.pause});
        } else {
          t.push_back(c);
        }
      break;
    case K::Split:
      at->angle *= 0.5;
      t.insert(at, *at);
      break;
    case K::Insert: {
      // The dwell before the new turn is shared: the turn is followed by one as long.
      const double before = m.index == 0 ? g.start_dwell : g.turns[m.index - 1].pause;
      t.insert(at, TurnChoice{m.axis, m.angle, std::max(min_dwell, before)});
      break;
    }
    case K::Remove:
      t.erase(at);
      break;
    case K::Axis:
      at->axis = m.axis;
      break;
    case K::Angle:
      at->angle = m.angle;
      break;
    case K::Swap:
      std::swap(at->axis, (at + 1)->axis);
      std::swap(at->angle, (at + 1)->angle);
      break;
  }
  return out;
}

std::vector<StructureMove> structure_moves(const PlanGenome& g, unsigned seed) {
  std::vector<StructureMove> global, local;
  add_global_moves(g, global);
  for (std::size_t i = 0; i < g.turns.size(); ++i) add_turn_moves(g, i, local);
  for (std::size_t i = 0; i <= g.turns.size(); ++i)
    for (int a = 0; a < 6; ++a) local.push_back({StructureMove::Kind::Insert, i, a, kInsertAngle});
  std::mt19937 rng(seed);
  std::shuffle(local.begin(), local.end(), rng);
  global.insert(global.end(), local.begin(), local.end());
  return global;
}

int structure_pass_limit(int requested, double budget, double rate_hz, int states) {
  if (requested <= 0) return 0;
  const double cost = std::max(1.0, budget * rate_hz) * std::max(1.0, double(states) * states);
  const double affordable = std::floor(kStructureWork / cost);
  return std::max(1, static_cast<int>(std::min(static_cast<double>(requested), affordable)));
}

std::optional<StructureResult> structure_search(
    const std::vector<PlanGenome>& starts, double budget, const TableSpec& table, const Site& site,
    int max_evaluations, const std::function<Excess(const PlanGenome&)>& score) {
  Search k{budget, shortest_pause(table), table, site, max_evaluations, score, 0, std::nullopt};
  std::optional<State> s;
  for (const PlanGenome& g : starts) {
    const auto f = fitted(g, budget, k.min_dwell, table, site);
    if (!f) continue;
    const Excess e = k.scored(*f);
    if (!s || better(e, s->excess)) s = State{*f, e};
  }
  if (!s) return std::nullopt;
  StructureResult r;
  // Moves (each followed by one sweep of the dwells) until none improves, then time moved
  // between the dwells in finer steps; again while that improves.
  for (unsigned round = 0; !k.spent();) {
    while (!k.spent() && one_move(*s, k, round++, r.path)) improve_dwells(*s, k, 0.25, 0.25);
    const double before = s->excess.soft_worst;
    improve_dwells(*s, k, 0.25, 0.02);
    if (!(s->excess.soft_worst < before * (1.0 - 1e-6))) break;
  }
  r.genome = k.best->genome;
  r.excess = k.best->excess;
  r.evaluations = k.evaluations;
  return r;
}

}  // namespace sinscal
