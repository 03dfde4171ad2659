#include "filter/diagnosis/time_structure.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "models/coefficient_families.hpp"

namespace sinscal {

namespace {

// The level of the differences' own noise test (as the dwells' test_statistic: chi-square while
// the residual is within this quantile, else F).
constexpr double kRevisitNoiseLevel = 0.99;

// The angle between two attitudes (rad).
double angle_between(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = 0.5 * ((a.transpose() * b).trace() - 1.0);
  return std::acos(std::clamp(c, -1.0, 1.0));
}

// Each dwell's previous visit of its orientation (-1: none), the dwells in time order.
std::vector<int> previous_visits(const std::vector<EquivalentInputs>& inputs) {
  std::vector<int> prev(inputs.size(), -1);
  for (std::size_t j = 0; j < inputs.size(); ++j)
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      if (i == j || !(inputs[i].dwell.t_end <= inputs[j].dwell.t_start)) continue;
      if (angle_between(inputs[i].dwell.C_b_n_known, inputs[j].dwell.C_b_n_known) >= kRevisitAngle)
        continue;
      const int p = prev[j];
      if (p < 0 || inputs[static_cast<std::size_t>(p)].dwell.t_start < inputs[i].dwell.t_start)
        prev[j] = static_cast<int>(i);
    }
  return prev;
}

// One stacked input row: its dwell and its NED input.
struct Row {
  std::size_t dwell;
  int input;
};

// The difference system: rows (later visit minus earlier), their covariance, the columns.
struct Differences {
  Eigen::VectorXd du;
  Eigen::MatrixXd dH, cov;
  int pairs = 0;
};

// The inputs the components act on (nonzero columns at some dwell).
std::vector<int> acted_inputs(const std::vector<Eigen::Matrix<double, 6, Eigen::Dynamic>>& H) {
  std::vector<int> out;
  for (int i = 0; i < 6; ++i)
    if (std::any_of(H.begin(), H.end(), [&](const auto& h) { return h.row(i).norm() > 0.0; }))
      out.push_back(i);
  return out;
}

Differences differences(const std::vector<EquivalentInputs>& inputs, const Site& site,
                        const Stage2Options& base, const std::vector<int>& components) {
  std::vector<Eigen::Matrix<double, 6, Eigen::Dynamic>> H;
  H.reserve(inputs.size());
  for (const auto& in : inputs)
    H.push_back(equivalent_input_map(in, site, components, base.reference_temperature_c));
  const std::vector<int> acted = acted_inputs(H);
  const std::vector<int> prev = previous_visits(inputs);
  std::vector<std::pair<Row, Row>> rows;  // (later, earlier)
  Differences d;
  for (std::size_t j = 0; j < inputs.size(); ++j) {
    if (prev[j] < 0) continue;
    const auto i = static_cast<std::size_t>(prev[j]);
    ++d.pairs;
    for (int k : acted)
      if (inputs[i].estimated[static_cast<std::size_t>(k)] &&
          inputs[j].estimated[static_cast<std::size_t>(k)])
        rows.push_back({{j, k}, {i, k}});
  }
  const auto m = static_cast<Eigen::Index>(rows.size());
  const auto p = static_cast<Eigen::Index>(components.size());
  d.du.resize(m);
  d.dH.resize(m, p);
  d.cov.resize(m, m);
  // Cov(u_a(k), u_b(l)): the dwell's own (stage 1 and the table) when a == b, the wander's always.
  const auto cov = [&](const Row& a, const Row& b) {
    double c = stage2_wander_covariance(inputs[a.dwell], inputs[b.dwell], base.bias_wander)(
        a.input, b.input);
    if (a.dwell == b.dwell)
      c += stage2_input_covariance(inputs[a.dwell], site, base.table)(a.input, b.input);
    return c;
  };
  for (Eigen::Index r = 0; r < m; ++r) {
    const auto& [late, early] = rows[static_cast<std::size_t>(r)];
    d.du(r) = inputs[late.dwell].u(late.input) - inputs[early.dwell].u(early.input);
    d.dH.row(r) = H[late.dwell].row(late.input) - H[early.dwell].row(early.input);
    for (Eigen::Index s = 0; s < m; ++s) {
      const auto& [late2, early2] = rows[static_cast<std::size_t>(s)];
      d.cov(r, s) = cov(late, late2) - cov(late, early2) - cov(early, late2) + cov(early, early2);
    }
  }
  return d;
}

}  // namespace

bool is_time_family(const std::string& family) {
  return coefficient_family_info(family).term == "bias_drift";
}

std::string RevisitCheck::text() const {
  if (pairs == 0) return "the plan revisits no orientation";
  char scaled[64] = "";
  if (scale > 1.0)
    std::snprintf(scaled, sizeof scaled, " (in their residual's scale x%.3g)", scale);
  char b[400];
  std::snprintf(b, sizeof b,
                "%d revisits of an orientation (%d rows): the fitted drift's trend over their "
                "differences %.3g, with it their chi-square %.3g %s than without%s, %.3g allowed",
                pairs, rows, trend, std::abs(statistic), statistic >= 0.0 ? "more" : "less", scaled,
                needed);
  return b;
}

RevisitCheck revisit_check(const std::vector<EquivalentInputs>& inputs, const Site& site,
                           const Stage2Options& base, const std::vector<int>& components,
                           const Eigen::VectorXd& values, double alpha) {
  RevisitCheck out;
  if (components.empty()) return out;
  const Differences d = differences(inputs, site, base, components);
  out.pairs = d.pairs;
  out.rows = static_cast<int>(d.du.size());
  if (out.rows == 0) return out;
  const Eigen::LLT<Eigen::MatrixXd> llt(d.cov);
  if (llt.info() != Eigen::Success)
    throw std::invalid_argument("diagnosis: the revisits' differences have no covariance");
  const Eigen::MatrixXd A = llt.matrixL().solve(d.dH);
  const Eigen::VectorXd y = llt.matrixL().solve(d.du);
  const Eigen::VectorXd p = A * values;
  out.trend = p.squaredNorm();
  out.statistic = (y - p).squaredNorm() - y.squaredNorm();
  // The differences' own scale: their residual after the drift's least squares, where it rejects
  // the noise model.
  const Eigen::VectorXd fit = A * A.completeOrthogonalDecomposition().solve(y);
  const auto rank = static_cast<int>(A.completeOrthogonalDecomposition().rank());
  const int rest_dof = out.rows - rank;
  const double rest = (y - fit).squaredNorm();
  if (rest_dof > 0 &&
      rest > boost::math::quantile(boost::math::chi_squared(rest_dof), kRevisitNoiseLevel)) {
    out.scale = rest / rest_dof;
    out.statistic /= out.scale;
  }
  out.needed = boost::math::quantile(boost::math::chi_squared(1), 1.0 - alpha);
  out.contradicts = out.statistic > out.needed;
  return out;
}

}  // namespace sinscal
