#include "filter/design/bound.hpp"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <limits>
#include <stdexcept>

#include "filter/design/grower.hpp"
#include "filter/kalman/kalman_run.hpp"
#include "models/coefficient_families.hpp"

namespace sinscal {

namespace {

using Orientation = Eigen::Matrix3i;  // body axes after turns, relative to the first start

// A body-axis turn (axis 0..5: +x -x +y -y +z -z) by `quarters` quarter turns.
Orientation turned(const Orientation& o, int axis, int quarters) {
  Orientation r = Orientation::Identity();
  const int a = axis / 2, b = (a + 1) % 3, c = (a + 2) % 3;
  const int sign = axis % 2 == 0 ? 1 : -1;
  for (int q = 0; q < quarters; ++q) {
    Orientation step = Orientation::Zero();
    step(a, a) = 1;
    step(b, c) = -sign;
    step(c, b) = sign;
    r = r * step;
  }
  return o * r;
}

struct Scaling {
  Eigen::VectorXd scale;  // SI per unit of the scaled states
  std::vector<int> catalog;
  std::vector<bool> targeted;
  Eigen::VectorXd prior_sigma;  // SI
};

// The prior sigma (rad, North East Down) of the rotation shared by every dwell's attitude (the
// oracle's table base): the smaller of the calibration's prior on its base and on its start
// attitude, so that the oracle knows at least what the calibration does at the start.
Eigen::Vector3d shared_rotation_sigma(const CalibratorOptions& options) {
  const double heading =
      gyros_find_north(options) ? kBaseHeadingPriorSigma : std::max(options.attitude_sigma, 0.0);
  const double start = initial_attitude_sigma(options);
  return {std::min(kBaseLevelPriorSigma, start), std::min(kBaseLevelPriorSigma, start),
          std::min(heading > 0.0 ? heading : start, start)};
}

Scaling scaling_of(const Grower& g, const std::map<std::string, double>& targets,
                   const std::vector<CoefficientEstimate>& estimates,
                   const Eigen::Vector3d& shared_sigma) {
  Scaling s;
  for (const auto& cb : g.layout().coefficients)
    for (int k = 0; k < cb.block.size; ++k) s.catalog.push_back(cb.catalog[std::size_t(k)]);
  const std::size_t n = s.catalog.size();
  s.scale.resize(Eigen::Index(n + 3));
  s.prior_sigma.resize(s.scale.size());
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < n; ++i) {
    const auto c = std::size_t(s.catalog[i]);
    const auto t = targets.find(cat[c].family);
    const bool has = t != targets.end() && t->second > 0.0;
    s.targeted.push_back(has);
    s.prior_sigma(Eigen::Index(i)) = estimates[c].prior_sigma;
    s.scale(Eigen::Index(i)) = has ? t->second : estimates[c].prior_sigma;
  }
  for (int a = 0; a < 3; ++a) {  // the shared rotation, last: in units of its prior, untargeted
    s.catalog.push_back(-1);
    s.targeted.push_back(false);
    s.scale(Eigen::Index(n) + a) = s.prior_sigma(Eigen::Index(n) + a) = shared_sigma(a);
  }
  return s;
}

// The scaled information of a grown plan's coefficients.
Eigen::MatrixXd information(const Grower& g, const Scaling& s) {
  const Eigen::MatrixXd P = s.scale.cwiseInverse().asDiagonal() *
                            g.coefficient_and_base_covariance() *
                            s.scale.cwiseInverse().asDiagonal();
  const Eigen::MatrixXd sym = 0.5 * (P + P.transpose());
  return sym.ldlt().solve(Eigen::MatrixXd::Identity(sym.rows(), sym.cols()));
}

// The increase from `before` to `after`, per `per` seconds, made positive semi-definite (a
// negative eigenvalue is the filter's rounding: dropping it only raises the bound's information).
Eigen::MatrixXd increase(const Eigen::MatrixXd& after, const Eigen::MatrixXd& before, double per) {
  const Eigen::MatrixXd d = 0.5 * ((after - before) + (after - before).transpose()) / per;
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(d);
  const Eigen::VectorXd ev = es.eigenvalues().cwiseMax(0.0);
  return es.eigenvectors() * ev.asDiagonal() * es.eigenvectors().transpose();
}

struct Node {
  Grower grower;
  Orientation orientation;
};

// One grown plan ending at each orientation reachable by 90 deg turns (breadth first).
std::vector<Node> orientation_nodes(const Context& c, double pause) {
  std::vector<Node> nodes;
  auto seen = [&](const Orientation& o) {
    return std::any_of(nodes.begin(), nodes.end(),
                       [&](const Node& n) { return n.orientation == o; });
  };
  PlanGenome root;
  root.start = 0;
  root.start_dwell = pause;
  for (int axis = 0; axis < 6; ++axis) {
    PlanGenome g = root;
    g.turns = {{axis, 90.0 * units::deg, pause}};
    const Orientation o = turned(Orientation::Identity(), axis, 1);
    if (!seen(o)) nodes.push_back({Grower(g, c), o});
  }
  for (std::size_t i = 0; i < nodes.size(); ++i)
    for (int axis = 0; axis < 6; ++axis) {
      const Orientation o = turned(nodes[i].orientation, axis, 1);
      if (!seen(o))
        nodes.push_back({nodes[i].grower.extended({axis, 90.0 * units::deg, pause}, c), o});
    }
  return nodes;
}

}  // namespace

CalibratorOptions oracle_options(const CalibratorOptions& options) {
  CalibratorOptions o = options;
  // The same coefficients as the calibration reports: in the triad frame (without attitude
  // updates, or converted after them) the oracle's body frame is the accelerometer triad, whose
  // attitude it is told (the table's mounting of the triads then no longer matters).
  if (reported_frame(options) == MisalignmentFrame::Triad) {
    o.layout.accel_triad_frame = true;
    o.misalignment_frame = MisalignmentFrame::ByMode;
  }
  o.attitude = CalibratorOptions::AttitudeUpdates::Every;
  o.attitude_hold = true;
  o.attitude_sigma = kOracleAttitudeSigma;
  o.hold_sigma = kOracleAttitudeSigma;
  o.initial_attitude_sigma = kOracleAttitudeSigma;
  o.base_attitude = true;  // the rotation shared by every dwell's attitude: a nuisance
  o.bias_wander_states = false;
  return o;
}

InformationLibrary information_library(const CalibratorOptions& options, const TableSpec& table,
                                       const Site& site,
                                       const std::map<std::string, double>& targets,
                                       double rate_hz) {
  if (targets.empty()) throw std::invalid_argument("design bound: no targets");
  const std::clock_t c0 = std::clock();
  const CalibratorOptions oracle = oracle_options(options);
  SearchOptions so;
  so.rate_hz = rate_hz;
  so.targets = targets;
  const Context c{oracle, table, site, so};
  const double pause = shortest_pause(table), rest = 20.0;
  const std::vector<Node> nodes = orientation_nodes(c, pause);
  InformationLibrary lib;
  lib.orientations = int(nodes.size());
  while (lib.start < lib.orientations &&
         nodes[std::size_t(lib.start)].orientation != Orientation::Identity())
    ++lib.start;
  const Scaling s =
      scaling_of(nodes.front().grower, targets,
                 predict_plan(plan_of(nodes.front().grower.genome(), table, site, "prior"), oracle,
                              {}, DesignOptions{rate_hz, 1e9})
                     .run.estimates,
                 shared_rotation_sigma(options));
  lib.catalog = s.catalog;
  lib.targeted = s.targeted;
  lib.prior = s.scale.cwiseQuotient(s.prior_sigma).array().square().matrix().asDiagonal();
  std::vector<bool> rested(nodes.size(), false);
  const char* axes[6] = {"+x", "-x", "+y", "-y", "+z", "-z"};
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Eigen::MatrixXd before = information(nodes[i].grower, s);
    for (int axis = 0; axis < 6; ++axis)
      for (int quarters : {1, 2}) {
        const TurnChoice turn{axis, quarters * 90.0 * units::deg, pause};
        const Grower g = nodes[i].grower.extended(turn, c);
        const Eigen::MatrixXd after = information(g, s);
        const Orientation to = turned(nodes[i].orientation, axis, quarters);
        std::size_t k = 0;
        while (nodes[k].orientation != to) ++k;
        lib.segments.push_back(
            {"o" + std::to_string(i) + " " + axes[axis] + " " + std::to_string(90 * quarters),
             g.duration() - nodes[i].grower.duration(), increase(after, before, 1.0), int(i),
             int(k), axis, quarters});
        if (rested[k]) continue;
        rested[k] = true;
        TurnChoice longer = turn;
        longer.pause += rest;
        const Grower l = nodes[i].grower.extended(longer, c);
        lib.segments.push_back({"o" + std::to_string(k) + " static", 1.0,
                                increase(information(l, s), after, rest), int(k), int(k)});
      }
  }
  lib.cpu_s = double(std::clock() - c0) / CLOCKS_PER_SEC;
  return lib;
}

namespace {

// The targeted states' diagonal of M^-1 and the minimax's smoothed weights over them.
struct Iterate {
  Eigen::MatrixXd Minv;
  Eigen::VectorXd r;  // (sigma / target)^2 of each targeted state
};

Iterate iterate_at(const InformationLibrary& lib, const std::vector<Eigen::MatrixXd>& J,
                   const Eigen::VectorXd& x, const std::vector<int>& targeted) {
  Eigen::MatrixXd M = lib.prior;
  for (std::size_t j = 0; j < J.size(); ++j)
    if (x(Eigen::Index(j)) > 0.0) M.noalias() += x(Eigen::Index(j)) * J[j];
  Iterate it;
  it.Minv = M.ldlt().solve(Eigen::MatrixXd::Identity(M.rows(), M.cols()));
  it.r.resize(Eigen::Index(targeted.size()));
  for (std::size_t k = 0; k < targeted.size(); ++k)
    it.r(Eigen::Index(k)) = it.Minv(targeted[k], targeted[k]);
  return it;
}

}  // namespace

namespace {

// The best certificate at a design: max over the weights mu of the targeted coefficients of
// phi_mu - (max_j s_j(mu) - sum_j x_j s_j(mu)), a concave piecewise-linear function of mu
// (s_j(mu) = sum_k mu_k G_jk, G_jk = v_k' J_j v_k with v_k = M^-1 e_k), maximized by
// exponentiated subgradient steps. Every value it takes is a valid lower bound.
double best_certificate(const std::vector<Eigen::MatrixXd>& J, const Eigen::VectorXd& x,
                        const Iterate& it, const std::vector<int>& targeted) {
  const auto K = static_cast<Eigen::Index>(targeted.size());
  const auto m = static_cast<Eigen::Index>(J.size());
  Eigen::MatrixXd V(it.Minv.rows(), K);
  for (Eigen::Index k = 0; k < K; ++k) V.col(k) = it.Minv.col(targeted[std::size_t(k)]);
  Eigen::MatrixXd G(m, K);
  for (Eigen::Index j = 0; j < m; ++j)
    G.row(j) = (J[std::size_t(j)] * V).cwiseProduct(V).colwise().sum();
  const Eigen::VectorXd c = it.r + G.transpose() * x;
  Eigen::VectorXd mu = Eigen::VectorXd::Constant(K, 1.0 / double(K));
  double best = 0.0;
  const double step = 1.0 / std::max(1e-300, c.maxCoeff());
  for (int n = 1; n <= 400; ++n) {
    const Eigen::VectorXd s = G * mu;
    Eigen::Index j_max = 0;
    const double s_max = s.maxCoeff(&j_max);
    best = std::max(best, mu.dot(c) - s_max);
    // Supergradient c - G(j_max, :), steps shrinking as 1/sqrt(n).
    const Eigen::VectorXd g = c - G.row(j_max).transpose();
    mu = mu.cwiseProduct((2.0 * step / std::sqrt(double(n)) * g).array().exp().matrix());
    mu /= mu.sum();
  }
  return best;
}

}  // namespace

namespace {

// The smoothed maximum tau log sum exp(r / tau) of the squared ratios, and its weights (the
// soft maximum's).
double smooth_max(const Eigen::VectorXd& r, double tau, Eigen::VectorXd* mu = nullptr) {
  const double m = r.maxCoeff();
  const Eigen::ArrayXd e = ((r.array() - m) / tau).exp();
  if (mu) *mu = e.matrix() / e.sum();
  return m + tau * std::log(e.sum());
}

// The multiplicative step of the weighted criterion sum_k mu_k (M^-1)_kk at `it`: x_j times
// (s_j / sum_i x_i s_i)^delta, s_j = tr(M^-1 C_mu M^-1 J_j).
Eigen::VectorXd multiplicative_step(const std::vector<Eigen::MatrixXd>& J, const Eigen::VectorXd& x,
                                    const Iterate& it, const Eigen::VectorXd& mu,
                                    const std::vector<int>& targeted, double delta) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(it.Minv.rows(), it.Minv.cols());
  for (std::size_t k = 0; k < targeted.size(); ++k)
    A.noalias() +=
        mu(Eigen::Index(k)) * it.Minv.col(targeted[k]) * it.Minv.col(targeted[k]).transpose();
  Eigen::VectorXd s(static_cast<Eigen::Index>(J.size()));
  for (std::size_t j = 0; j < J.size(); ++j) s(Eigen::Index(j)) = A.cwiseProduct(J[j]).sum();
  Eigen::VectorXd next = x.cwiseProduct((s / x.dot(s)).array().pow(delta).matrix());
  return next / next.sum();
}

}  // namespace

DesignBound relaxed_bound(const InformationLibrary& lib, double budget_s, double tolerance,
                          int max_iterations, double decide) {
  std::vector<int> targeted;
  for (std::size_t i = 0; i < lib.targeted.size(); ++i)
    if (lib.targeted[i]) targeted.push_back(int(i));
  if (targeted.empty() || lib.segments.empty() || !(budget_s > 0.0))
    throw std::invalid_argument("design bound: no targeted coefficient, segment or budget");
  const std::size_t m = lib.segments.size();
  std::vector<Eigen::MatrixXd> J(m);  // the information of all the budget spent on segment j
  for (std::size_t j = 0; j < m; ++j)
    J[j] = lib.segments[j].information * (budget_s / lib.segments[j].duration);
  Eigen::VectorXd x = Eigen::VectorXd::Constant(Eigen::Index(m), 1.0 / double(m));
  Iterate it = iterate_at(lib, J, x, targeted);
  DesignBound b;
  b.budget_s = budget_s;
  double lower = 0.0, beta = 10.0, delta = 1.0;
  Eigen::Index k_max = 0;
  double best = it.r.maxCoeff(&k_max);
  int worst = targeted[std::size_t(k_max)];
  for (b.iterations = 1; b.iterations <= max_iterations; ++b.iterations) {
    if (b.iterations % 50 == 1) lower = std::max(lower, best_certificate(J, x, it, targeted));
    if (best - lower <= tolerance * best) break;
    if (decide > 0.0 && (lower > decide * decide || best < decide * decide)) break;
    // A damped step on the smoothed maximum (sharpness beta relative to the current maximum),
    // taken when it lowers it, else the damping halved (backtracking).
    const double tau = it.r.maxCoeff() / beta;
    Eigen::VectorXd mu;
    const double f = smooth_max(it.r, tau, &mu);
    const Eigen::VectorXd trial = multiplicative_step(J, x, it, mu, targeted, delta);
    Iterate next = iterate_at(lib, J, trial, targeted);
    if (!(smooth_max(next.r, tau) < f)) {
      delta *= 0.5;
      if (delta < 1e-3) {  // no descent at this sharpness: smoother
        delta = 1.0;
        beta = std::max(1.0, beta * 0.5);
      }
      continue;
    }
    x = trial;
    it = std::move(next);
    delta = std::min(1.0, 2.0 * delta);
    beta = std::min(1e3, beta * 1.05);
    const double r_max = it.r.maxCoeff(&k_max);
    if (r_max < best) {
      best = r_max;
      worst = targeted[std::size_t(k_max)];
      b.time_s.assign(m, 0.0);
      for (std::size_t j = 0; j < m; ++j) b.time_s[j] = x(Eigen::Index(j)) * budget_s;
    }
  }
  b.lower = std::sqrt(std::max(0.0, lower));
  b.upper = std::sqrt(best);
  b.family = coefficient_catalog()[std::size_t(lib.catalog[std::size_t(worst)])].family;
  if (b.time_s.empty()) b.time_s.assign(m, budget_s / double(m));
  return b;
}

double bound_time_for_targets(const InformationLibrary& lib, double resolution_s, double max_s) {
  double lo = 0.0, hi = max_s;  // lo: certified not to meet (0: nothing at all)
  while (hi - lo > resolution_s) {
    const double mid = 0.5 * (lo + hi);
    if (relaxed_bound(lib, mid, 0.02, 4000, 1.0).lower > 1.0)
      lo = mid;
    else
      hi = mid;
  }
  return lo;
}

}  // namespace sinscal
