#include "filter/design/rounding.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <stdexcept>

#include "models/units.hpp"
#include "rig/plan.hpp"

namespace sinscal {

namespace {

// A turn is taken while its remaining design count is above this: the relaxed designs spread the
// time thinly (nav-fog-extended at 491 s: about 0.2 of a turn on each of the 288 turns).
constexpr double kTaken = 1e-6;

struct Walk {
  std::vector<int> turns;   // library segment of each turn taken
  std::vector<int> visits;  // orientation of each dwell (the start's first)
  double used = 0.0;        // s: the start's shortest dwell and the turns' segments
};

// The turn segments out of each orientation.
std::vector<std::vector<int>> turns_from(const InformationLibrary& lib) {
  std::vector<std::vector<int>> out(std::size_t(lib.orientations));
  for (std::size_t j = 0; j < lib.segments.size(); ++j)
    if (lib.segments[j].axis >= 0) out[std::size_t(lib.segments[j].from)].push_back(int(j));
  return out;
}

// The turn out of orientation `k` of most remaining count, when it is above kTaken; else -1.
int best_turn(int k, const std::vector<std::vector<int>>& out, const std::vector<double>& count) {
  int best = -1;
  for (int j : out[std::size_t(k)])
    if (count[std::size_t(j)] > kTaken &&
        (best < 0 || count[std::size_t(j)] > count[std::size_t(best)]))
      best = j;
  return best;
}

// The turn to take at `o`: its best, or the first turn of the shortest way (breadth first over
// the library's turns) to an orientation that has one; -1 when no turn is left.
int next_turn(const InformationLibrary& lib, int o, const std::vector<std::vector<int>>& out,
              const std::vector<double>& count) {
  if (const int j = best_turn(o, out, count); j >= 0) return j;
  std::vector<int> first(out.size(), -2);  // the first turn on the way to each orientation
  first[std::size_t(o)] = -1;
  std::deque<int> queue{o};
  while (!queue.empty()) {
    const int k = queue.front();
    queue.pop_front();
    if (k != o && best_turn(k, out, count) >= 0) return first[std::size_t(k)];
    for (int j : out[std::size_t(k)]) {
      const int to = lib.segments[std::size_t(j)].to;
      if (first[std::size_t(to)] != -2) continue;
      first[std::size_t(to)] = k == o ? j : first[std::size_t(k)];
      queue.push_back(to);
    }
  }
  return -1;
}

Walk walk(const InformationLibrary& lib, const DesignBound& bound, double start_dwell) {
  const auto out = turns_from(lib);
  std::vector<double> count(lib.segments.size(), 0.0);
  for (std::size_t j = 0; j < count.size(); ++j)
    if (lib.segments[j].axis >= 0) count[j] = bound.time_s[j] / lib.segments[j].duration;
  Walk w;
  w.visits = {lib.start};
  w.used = start_dwell;
  for (int o = lib.start;;) {
    const int j = next_turn(lib, o, out, count);
    if (j < 0 || w.used + lib.segments[std::size_t(j)].duration > bound.budget_s) break;
    count[std::size_t(j)] -= 1.0;
    w.turns.push_back(j);
    w.used += lib.segments[std::size_t(j)].duration;
    o = lib.segments[std::size_t(j)].to;
    w.visits.push_back(o);
  }
  return w;
}

// Each dwell's rest beyond the shortest: its orientation's design rest time shared among its
// visits, all scaled to the time left (evenly when the design rests nowhere it goes).
std::vector<double> extra_rest(const InformationLibrary& lib, const DesignBound& bound,
                               const Walk& w) {
  std::vector<double> rest(std::size_t(lib.orientations), 0.0);
  std::vector<int> visits(rest.size(), 0);
  for (std::size_t j = 0; j < lib.segments.size(); ++j)
    if (lib.segments[j].axis < 0) rest[std::size_t(lib.segments[j].from)] += bound.time_s[j];
  for (int k : w.visits) ++visits[std::size_t(k)];
  std::vector<double> extra;
  double sum = 0.0;
  for (int k : w.visits) {
    extra.push_back(rest[std::size_t(k)] / visits[std::size_t(k)]);
    sum += extra.back();
  }
  const double left = std::max(0.0, bound.budget_s - w.used);
  for (double& e : extra) e = sum > 0.0 ? e * left / sum : left / static_cast<double>(extra.size());
  return extra;
}

double floor_grid(double s) { return std::floor(s * 10.0 + 1e-9) / 10.0; }

}  // namespace

Plan rounded_design(const InformationLibrary& lib, const DesignBound& bound, const TableSpec& table,
                    const Site& site, const std::string& name) {
  if (bound.time_s.size() != lib.segments.size() || lib.start < 0 || lib.start >= lib.orientations)
    throw std::invalid_argument("rounded design: the design is not of this library");
  const double pause = shortest_pause(table);
  const Walk w = walk(lib, bound, pause);
  if (w.turns.empty())
    throw std::invalid_argument("rounded design: the budget does not hold one turn");
  const std::vector<double> extra = extra_rest(lib, bound, w);
  PlanGenome g;
  g.start = 0;  // body x up: the library's start
  g.start_dwell = floor_grid(pause + extra[0]);
  for (std::size_t i = 0; i < w.turns.size(); ++i) {
    const auto& s = lib.segments[std::size_t(w.turns[i])];
    g.turns.push_back({s.axis, s.quarters * 90.0 * units::deg, floor_grid(pause + extra[i + 1])});
  }
  return plan_of(g, table, site, name);
}

}  // namespace sinscal
