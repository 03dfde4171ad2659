#include "filter/design/anneal.hpp"

#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "filter/design/structure_moves.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

// Body axes as PlanGenome numbers them (search.hpp TurnChoice).
constexpr int kPlusX = 0, kMinusX = 1, kPlusY = 2, kMinusY = 3, kPlusZ = 4, kMinusZ = 5;

struct Chain {
  PlanGenome genome;
  Excess excess;
};

// What the annealing needs beside the chain.
struct Annealer {
  double budget, min_dwell;
  const TableSpec& table;
  const Site& site;
  const AnnealOptions& o;
  const std::function<Excess(const PlanGenome&)>& score;
  std::mt19937 rng;
  AnnealResult r;
  double uniform() { return std::uniform_real_distribution<double>(0.0, 1.0)(rng); }
  std::size_t index(std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  }
  // One structure move drawn uniformly from structure_moves' list for `g`.
  PlanGenome structure_proposal(const PlanGenome& g) {
    const std::vector<StructureMove> moves = structure_moves(g, static_cast<unsigned>(rng()));
    return applied(g, moves[index(moves.size())], min_dwell);
  }
  // One dwell gains `dwell_step` of itself or gives that share of its time above the shortest.
  std::optional<PlanGenome> dwell_proposal(const PlanGenome& g) {
    std::vector<double> d = {g.start_dwell};
    for (const TurnChoice& t : g.turns) d.push_back(t.pause);
    const std::size_t i = index(d.size());
    if (uniform() < 0.5)
      d[i] += o.dwell_step * d[i];
    else
      d[i] -= o.dwell_step * std::max(0.0, d[i] - min_dwell);
    return fitted(g, d, budget, min_dwell, table, site);
  }
  std::optional<PlanGenome> proposal(const PlanGenome& g) {
    if (uniform() < o.dwell_share) return dwell_proposal(g);
    return fitted(structure_proposal(g), budget, min_dwell, table, site);
  }
  Excess scored(const PlanGenome& g) {
    Excess e = score(g);
    ++r.evaluations;
    if (e.worst_ratio < r.excess.worst_ratio) {
      r.genome = g;
      r.excess = e;
    }
    return e;
  }
  void step(Chain& c, int k) {
    const auto g = proposal(c.genome);
    const double u = uniform();  // drawn for every proposal: the sequence does not depend on it
    if (!g) return;
    const double best = r.excess.worst_ratio;
    const Excess e = scored(*g);
    if (r.excess.worst_ratio < best) r.improvements.emplace_back(k, r.excess.worst_ratio);
    if (!anneal_accepts(c.excess.soft_worst, e.soft_worst, anneal_temperature(o, k), u)) return;
    ++r.accepted;
    if (e.soft_worst > c.excess.soft_worst) ++r.accepted_worse;
    c = {*g, e};
  }
};

void append_block(PlanGenome& g, int plus, int minus, double step, int n, double dwell) {
  for (int i = 0; i < n; ++i) g.turns.push_back({plus, step, dwell});
  for (int i = 0; i < n; ++i) g.turns.push_back({minus, step, dwell});
}

}  // namespace

double anneal_temperature(const AnnealOptions& o, int k) {
  if (o.iterations <= 1) return o.t_start;
  const double x = static_cast<double>(k) / static_cast<double>(o.iterations - 1);
  return o.t_start * std::pow(o.t_end / o.t_start, x);
}

bool anneal_accepts(double current_soft, double candidate_soft, double temperature, double u) {
  if (candidate_soft <= current_soft) return true;
  if (!(temperature > 0.0)) return false;
  const double delta = std::log(candidate_soft / current_soft);
  return u < std::exp(-delta / temperature);
}

std::optional<AnnealResult> anneal(const PlanGenome& start, double budget, const TableSpec& table,
                                   const Site& site, const AnnealOptions& o,
                                   const std::function<Excess(const PlanGenome&)>& score) {
  if (!(o.t_start > 0.0 && o.t_end > 0.0 && o.dwell_share >= 0.0 && o.dwell_share <= 1.0 &&
        o.dwell_step > 0.0 && o.iterations >= 0))
    throw std::invalid_argument("annealing: temperatures, dwell share or step out of range");
  Annealer a{budget, shortest_pause(table), table, site, o, score, std::mt19937(o.seed), {}};
  const auto f = fitted(start, budget, a.min_dwell, table, site);
  if (!f) return std::nullopt;
  a.r.excess.worst_ratio = std::numeric_limits<double>::infinity();
  Chain c{*f, a.scored(*f)};
  a.r.start = c.excess;
  for (int k = 0; k < o.iterations; ++k) a.step(c, k);
  return a.r;
}

std::optional<AnnealResult> anneal_search_result(SearchResult& r, const CalibratorOptions& options,
                                                 const TableSpec& table, const Site& site,
                                                 const SearchOptions& search,
                                                 const AnnealOptions& o) {
  const auto start = genome_of(r.plan, table);
  if (!(search.budget_s > 0.0) || !start) return std::nullopt;
  const auto score = [&](const PlanGenome& g) {
    return evaluate_genome(g, options, table, site, search);
  };
  auto a = anneal(*start, search.budget_s, table, site, o, score);
  if (!a) return a;
  r.evaluations += a->evaluations;
  if (!(a->excess.worst_ratio < r.excess.worst_ratio)) return a;
  r.best = a->genome;
  r.plan = plan_of(r.best, table, site, search.name);
  r.text = plan_text(r.best, table, site, search.name);
  r.excess = a->excess;
  r.meets = r.excess.J <= 0.0;
  r.origin = "annealing";
  return a;
}

PlanGenome north_carousel(double step, double dwell) {
  const double turns = 360.0 * units::deg / step;
  const int n = static_cast<int>(std::lround(turns));
  if (!(step >= 1.0 * units::deg && step <= 180.0 * units::deg) || std::abs(turns - n) > 1e-9)
    throw std::invalid_argument("north carousel: 360 deg is not a whole number of steps");
  PlanGenome g;
  g.start = kPlusX;  // body x up; heading 0: body z north
  g.start_dwell = dwell;
  append_block(g, kPlusZ, kMinusZ, step, n, dwell);
  g.turns.push_back({kPlusX, 90.0 * units::deg, dwell});  // about the vertical: body y north
  append_block(g, kPlusY, kMinusY, step, n, dwell);
  g.turns.push_back({kPlusZ, 90.0 * units::deg, dwell});  // about the horizontal z: x north
  append_block(g, kPlusX, kMinusX, step, n, dwell);
  return g;
}

}  // namespace sinscal
