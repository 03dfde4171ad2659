// The held-out dwells' predictive chi-square (filter/diagnosis/diagnosis.hpp HeldoutFigures) and
// its reference distribution (issue 33): each dwell predicted by the others and whitened by its
// predictive covariance has a chi-square of its inputs, but the dwells' predictions share their
// data, so the sum over dwells is wider than a chi-square of all inputs. Checked by drawing the
// dwells of a clean seed8 session from their own model (coefficients from the weak prior, noise
// from the whitened covariance) many times: the sum's mean, its variance against
// heldout_predictive_variance, and the rate at which it exceeds heldout_predictive_quantile.
#include <Eigen/Cholesky>
#include <boost/math/distributions/chi_squared.hpp>
#include <catch2/catch.hpp>
#include <random>

#include "diagnosis_cases.hpp"

using namespace sinscal;
using namespace sinscal::test;

namespace {

// The held-out predictive chi-square of the whitened dwells `w` for data y (per dwell), written
// out for the check: dwell i predicted from the others' normal equations with the prior p0.
struct Predictor {
  std::vector<Eigen::MatrixXd> A;
  std::vector<Eigen::LDLT<Eigen::MatrixXd>> others;  // N_-i
  std::vector<Eigen::LLT<Eigen::MatrixXd>> S;        // I + A_i N_-i^-1 A_i^T
  Predictor(const std::vector<WhitenedDwell>& w, const Eigen::VectorXd& p0) {
    Eigen::MatrixXd N = p0.cwiseInverse().cwiseAbs2().asDiagonal();
    for (const auto& d : w) N += d.A.transpose() * d.A;
    for (const auto& d : w) {
      A.push_back(d.A);
      others.emplace_back(N - d.A.transpose() * d.A);
      const auto rows = d.A.rows();
      S.emplace_back(Eigen::MatrixXd::Identity(rows, rows) +
                     d.A * others.back().solve(d.A.transpose()));
    }
  }
  double chi2(const std::vector<Eigen::VectorXd>& y) const {
    Eigen::VectorXd b = Eigen::VectorXd::Zero(A.front().cols());
    for (std::size_t i = 0; i < A.size(); ++i) b += A[i].transpose() * y[i];
    double q = 0.0;
    for (std::size_t i = 0; i < A.size(); ++i) {
      const Eigen::VectorXd z = y[i] - A[i] * others[i].solve(b - A[i].transpose() * y[i]);
      q += z.dot(S[i].solve(z));
    }
    return q;
  }
};

}  // namespace

TEST_CASE("Held-out predictive chi-square: its reference distribution on seed8's eight dwells",
          "[diagnosis][heldout_predictive]") {
  const HiddenCase c = hidden_case("heldout_predictive", "seed8.ini", "nav-fog.ini", {}, 31, 20.0);
  const Stage1Options s1 = default_stage1(&c.filter_profile);
  const TableAttitudeError table{kDefaultTableAttitudeSigma};
  const TurnModel model = turn_model_of(c.session, c.filter_profile, table.sigma);
  const ClosedFormReport cal = run_closed_form(c.session, s1, table, true, nullptr);
  Stage2Options base = cal.stage2_options;
  base.bias_wander = model.base.noise;
  DiagnosisOptions o;
  o.prior_sigma = grade_priors(model.base);
  const DwellTests dwells(cal.stage1, c.session.site, base, o);
  const std::vector<int>& p = base.parameters;
  const FitFigures f = dwells.fit(p);
  const auto w = dwells.whitened(p);
  const Eigen::VectorXd p0 = dwells.prior(p);
  const Predictor predictor(w, p0);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g;
  const int draws = 4000;
  const double q_model = heldout_predictive_quantile(f, 0.99);
  const double q_chi2 = boost::math::quantile(boost::math::chi_squared(f.heldout_inputs), 0.99);
  std::vector<double> q(draws);
  int over_model = 0, over_chi2 = 0;
  for (int k = 0; k < draws; ++k) {
    Eigen::VectorXd theta(p0.size());
    for (Eigen::Index j = 0; j < p0.size(); ++j) theta(j) = p0(j) * g(rng);
    std::vector<Eigen::VectorXd> y;
    for (const auto& d : w) {
      Eigen::VectorXd e(d.A.rows());
      for (Eigen::Index r = 0; r < e.size(); ++r) e(r) = g(rng);
      y.push_back(d.A * theta + e);
    }
    q[static_cast<std::size_t>(k)] = predictor.chi2(y);
    over_model += q[static_cast<std::size_t>(k)] > q_model ? 1 : 0;
    over_chi2 += q[static_cast<std::size_t>(k)] > q_chi2 ? 1 : 0;
  }
  double mean = 0.0;
  for (double v : q) mean += v / draws;
  double var = 0.0, m4 = 0.0;
  for (double v : q) {
    var += (v - mean) * (v - mean) / (draws - 1);
    m4 += std::pow(v - mean, 4) / draws;
  }
  const double n = f.heldout_inputs;
  INFO("inputs " << n << ", sample mean " << mean << ", variance " << var << " (predicted "
                 << f.heldout_predictive_variance << ", chi-square " << 2.0 * n
                 << "); over the 99 % quantile " << q_model << ": " << over_model << " of " << draws
                 << "; over the chi-square's " << q_chi2 << ": " << over_chi2);
  // The model's own draws: the data's chi-square is its mean; the variance is the predicted one
  // within 4 of its standard errors (from the sample's fourth moment).
  CHECK(std::abs(mean - n) < 4.0 * std::sqrt(var / draws));
  CHECK(std::abs(var - f.heldout_predictive_variance) < 4.0 * std::sqrt((m4 - var * var) / draws));
  // The quantile's tail: 1 % within 4 binomial sigmas.
  const double expected = 0.01 * draws, sd = std::sqrt(draws * 0.01 * 0.99);
  CHECK(std::abs(over_model - expected) < 4.0 * sd);
}
