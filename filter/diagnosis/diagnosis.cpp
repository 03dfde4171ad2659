#include "filter/diagnosis/diagnosis.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <tuple>

#include "filter/strapdown/ins_error_model.hpp"
#include "filter/thermal/soak_fit.hpp"
#include "models/attitude.hpp"
#include "models/coefficient_families.hpp"
#include "models/earth.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

// The noise model is trusted while the fit's chi-square stays within this quantile.
constexpr double kNoiseModelLevel = 0.99;
// Two candidates whose fits' chi-square differ by less than this explain the residual equally
// well (a likelihood ratio below e^4.5, about 90).
constexpr double kAmbiguityMargin = 9.0;

// One dwell's estimated inputs, whitened: L^-1 u = L^-1 H theta + unit noise (R = L L^T).
struct WhiteDwell {
  Eigen::MatrixXd A;  // L^-1 H (rows: the dwell's estimated inputs)
  Eigen::VectorXd y;  // L^-1 u
  Eigen::MatrixXd H;  // H (physical units)
  Eigen::VectorXd u;
  std::vector<int> rows;  // which of the 6 inputs
  Eigen::MatrixXd L;      // R = L L^T
};

class StaticDesign {
 public:
  StaticDesign(const std::vector<EquivalentInputs>& inputs, const Site& site,
               const Stage2Options& base, const std::vector<double>& priors = {})
      : inputs_(inputs),
        site_(site),
        table_(base.table),
        base_attitude_(base.base_attitude),
        reference_temperature_c_(base.reference_temperature_c),
        wander_(base.bias_wander),
        priors_(priors) {}

  std::vector<WhiteDwell> whiten(const std::vector<int>& parameters) const {
    std::vector<WhiteDwell> out;
    for (const auto& in : inputs_) {
      const auto Hc = equivalent_input_map(in, site_, parameters, reference_temperature_c_);
      // The table base's error (closed form's stage 2 with a base): three more columns.
      Eigen::Matrix<double, 6, Eigen::Dynamic> H6(6, Hc.cols() + (base_attitude_ ? 3 : 0));
      H6.leftCols(Hc.cols()) = Hc;
      if (base_attitude_) {
        const Earth& earth = Earth::wgs84();
        H6.rightCols(3).setZero();
        H6.block<3, 3>(ins_input::kAccel.index, Hc.cols()) =
            skew(-earth.gravity_n(site_.lat_rad, site_.h_m));
        H6.block<3, 3>(ins_input::kGyro.index, Hc.cols()) = skew(earth.omega_ie_n(site_.lat_rad));
      }
      // Each dwell alone: its variance with the bias wander (stage 2 correlates the dwells).
      const Matrix6d R6 =
          stage2_input_covariance(in, site_, table_) + stage2_wander_covariance(in, in, wander_);
      WhiteDwell w;
      for (int i = 0; i < 6; ++i)
        if (in.estimated[static_cast<std::size_t>(i)]) w.rows.push_back(i);
      const auto m = static_cast<Eigen::Index>(w.rows.size());
      Eigen::MatrixXd R(m, m);
      w.H.resize(m, H6.cols());
      w.u.resize(m);
      for (Eigen::Index a = 0; a < m; ++a) {
        w.H.row(a) = H6.row(w.rows[static_cast<std::size_t>(a)]);
        w.u(a) = in.u(w.rows[static_cast<std::size_t>(a)]);
        for (Eigen::Index b = 0; b < m; ++b)
          R(a, b) = R6(w.rows[static_cast<std::size_t>(a)], w.rows[static_cast<std::size_t>(b)]);
      }
      const Eigen::LLT<Eigen::MatrixXd> llt(R);
      if (llt.info() != Eigen::Success)
        throw std::invalid_argument("diagnosis: the covariance of dwell " +
                                    std::to_string(in.dwell.index) + " is not positive definite");
      w.A = llt.matrixL().solve(w.H);
      w.y = llt.matrixL().solve(w.u);
      w.L = llt.matrixL();
      out.push_back(std::move(w));
    }
    return out;
  }

  const std::vector<EquivalentInputs>& inputs() const { return inputs_; }
  const Site& site() const { return site_; }
  const TableAttitudeError& table() const { return table_; }
  bool base_attitude() const { return base_attitude_; }
  const NoiseModel& wander() const { return wander_; }
  const std::vector<double>& priors() const { return priors_; }
  /// The prior 1-sigma (SI) of catalog coefficient k: the session's grade, else the default.
  double prior(int k) const {
    const auto i = static_cast<std::size_t>(k);
    if (i < priors_.size() && priors_[i] > 0.0) return priors_[i];
    return coefficient_family_info(coefficient_catalog()[i].family).default_prior;
  }

 private:
  const std::vector<EquivalentInputs>& inputs_;
  const Site& site_;
  const TableAttitudeError& table_;
  bool base_attitude_ = false;
  double reference_temperature_c_ = 25.0;
  NoiseModel wander_;
  std::vector<double> priors_;
};

// The priors (SI) of the parameters, the session's grade (else the families' defaults): a weak
// prior that makes every fit determinate (a direction no dwell sees is predicted as zero) without
// pulling observed ones.
Eigen::VectorXd prior_sigmas(const StaticDesign& design, const std::vector<int>& parameters) {
  const bool base_attitude = design.base_attitude();
  Eigen::VectorXd s(static_cast<Eigen::Index>(parameters.size()) + (base_attitude ? 3 : 0));
  // The base's three angles: a weak prior of a table set up on its site (1 deg).
  if (base_attitude) s.tail<3>().setConstant(units::deg);
  for (std::size_t k = 0; k < parameters.size(); ++k)
    s(static_cast<Eigen::Index>(k)) = design.prior(parameters[k]);
  return s;
}

// Regularized least squares over the dwells except `skip` (-1: none).
Eigen::VectorXd solve_with_prior(const std::vector<WhiteDwell>& dwells, const Eigen::VectorXd& p0,
                                 int skip) {
  const Eigen::Index n = p0.size();
  Eigen::MatrixXd N = p0.cwiseInverse().cwiseAbs2().asDiagonal();
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  for (std::size_t i = 0; i < dwells.size(); ++i) {
    if (static_cast<int>(i) == skip) continue;
    N += dwells[i].A.transpose() * dwells[i].A;
    b += dwells[i].A.transpose() * dwells[i].y;
  }
  return N.ldlt().solve(b);
}

// z^T S^-1 z for the whitened prediction error z of dwell i from the others: S = I + A_i N_-i^-1
// A_i^T, N_-i the other dwells' normal matrix with the prior.
double predictive_chi2(const std::vector<WhiteDwell>& dwells, const Eigen::VectorXd& p0,
                       std::size_t i, const Eigen::VectorXd& z) {
  Eigen::MatrixXd N = p0.cwiseInverse().cwiseAbs2().asDiagonal();
  for (std::size_t k = 0; k < dwells.size(); ++k)
    if (k != i) N += dwells[k].A.transpose() * dwells[k].A;
  const Eigen::MatrixXd& A = dwells[i].A;
  const Eigen::MatrixXd S =
      Eigen::MatrixXd::Identity(A.rows(), A.rows()) + A * N.ldlt().solve(A.transpose());
  return z.dot(S.ldlt().solve(z));
}

// The variance and third cumulant of the held-out predictive chi-square when the model holds (the
// data noise and the coefficients drawn from the weak prior): 2 tr(M^2) and 8 tr(M^3), M the
// covariance of every dwell's whitened prediction error together. Dwell i's error is z_i = y_i -
// A_i N_-i^-1 sum_k!=i A_k^T y_k = (rows of T) y + L_i^-1 A_i N_-i^-1 P0^-1 theta, so M = T T^T + W
// W^T with W_i = L_i^-1 A_i N_-i^-1 P0^-1/2 (S_i = L_i L_i^T: each diagonal block of M is the
// identity).
std::pair<double, double> predictive_cumulants(const std::vector<WhiteDwell>& dwells,
                                               const Eigen::VectorXd& p0) {
  const Eigen::Index p = p0.size();
  Eigen::Index n = 0;
  std::vector<Eigen::Index> first;
  for (const auto& w : dwells) {
    first.push_back(n);
    n += w.A.rows();
  }
  Eigen::MatrixXd A(n, p);
  for (std::size_t i = 0; i < dwells.size(); ++i)
    A.middleRows(first[i], dwells[i].A.rows()) = dwells[i].A;
  Eigen::MatrixXd N = p0.cwiseInverse().cwiseAbs2().asDiagonal();
  N += A.transpose() * A;
  Eigen::MatrixXd big(n, n + p);
  for (std::size_t i = 0; i < dwells.size(); ++i) {
    const Eigen::MatrixXd& Ai = dwells[i].A;
    const Eigen::Index r0 = first[i], rows = Ai.rows();
    const Eigen::LDLT<Eigen::MatrixXd> Ni(N - Ai.transpose() * Ai);
    Eigen::MatrixXd K = Ni.solve(A.transpose());  // p x n
    K.middleCols(r0, rows).setZero();
    Eigen::MatrixXd X(rows, n + p);
    X.leftCols(n) = -Ai * K;
    X.block(0, r0, rows, rows) += Eigen::MatrixXd::Identity(rows, rows);
    X.rightCols(p) = Ai * Ni.solve(Eigen::MatrixXd(p0.cwiseInverse().asDiagonal()));
    const Eigen::MatrixXd S = Eigen::MatrixXd::Identity(rows, rows) + Ai * Ni.solve(Ai.transpose());
    const Eigen::LLT<Eigen::MatrixXd> llt(S);
    big.middleRows(r0, rows) = llt.matrixL().solve(X);
  }
  const Eigen::MatrixXd M = big * big.transpose();
  return {2.0 * M.squaredNorm(), 8.0 * (M * M).cwiseProduct(M).sum()};
}

// Fit, residuals and leave-one-dwell-out prediction of one parameter set.
FitFigures figures(const StaticDesign& design, const std::vector<int>& parameters,
                   bool heldout = true) {
  FitFigures f;
  Stage2Options o;
  o.table = design.table();
  o.base_attitude = design.base_attitude();
  o.bias_wander = design.wander();
  o.parameters = parameters;
  f.fit = solve_stage2(design.inputs(), design.site(), o);
  f.chi2 = f.fit.chi2_per_dof * f.fit.dof;
  const auto dwells = design.whiten(parameters);
  const Eigen::VectorXd p0 = prior_sigmas(design, parameters);
  const Eigen::VectorXd theta = solve_with_prior(dwells, p0, -1);
  double sa = 0.0, sg = 0.0, ha = 0.0, hg = 0.0, hz = 0.0;
  int na = 0, ng = 0, nha = 0, nhg = 0, nz = 0, inputs = 0;
  for (std::size_t i = 0; i < dwells.size(); ++i) {
    const WhiteDwell& w = dwells[i];
    const Eigen::VectorXd r = w.u - w.H * theta;
    const Eigen::VectorXd th = heldout ? solve_with_prior(dwells, p0, static_cast<int>(i)) : theta;
    const Eigen::VectorXd e = w.u - w.H * th, z = w.y - w.A * th;
    for (std::size_t a = 0; a < w.rows.size(); ++a) {
      const bool gyro = w.rows[a] >= ins_input::kGyro.index;
      const auto k = static_cast<Eigen::Index>(a);
      (gyro ? sg : sa) += r(k) * r(k);
      (gyro ? ng : na) += 1;
      (gyro ? hg : ha) += e(k) * e(k);
      (gyro ? nhg : nha) += 1;
    }
    hz += z.squaredNorm();
    if (heldout) f.heldout_predictive_chi2 += predictive_chi2(dwells, p0, i, z);
    nz += static_cast<int>(z.size());
    inputs += static_cast<int>(w.rows.size());
  }
  f.accel_rms = na ? std::sqrt(sa / na) : 0.0;
  f.gyro_rms = ng ? std::sqrt(sg / ng) : 0.0;
  f.heldout_accel = nha ? std::sqrt(ha / nha) : 0.0;
  f.heldout_gyro = nhg ? std::sqrt(hg / nhg) : 0.0;
  f.heldout = nz ? std::sqrt(hz / nz) : 0.0;
  f.heldout_chi2 = hz;
  f.heldout_inputs = heldout ? nz : 0;
  if (heldout)
    std::tie(f.heldout_predictive_variance, f.heldout_predictive_cumulant3) =
        predictive_cumulants(dwells, p0);
  f.heldout_dwells = static_cast<int>(dwells.size());
  f.log_likelihood = -0.5 * f.chi2;
  f.bic = f.chi2 + f.fit.rank * std::log(std::max(1, inputs));
  return f;
}

// One component as a candidate: separable when, added alone to the current parameters, it is
// observable with a sigma below its prior (the session's grade) / ratio.
CandidateTest separability(const StaticDesign& design, const std::vector<int>& current,
                           int component, const DiagnosisOptions& o) {
  const auto& cat = coefficient_catalog();
  CandidateTest c;
  c.family = cat[static_cast<std::size_t>(component)].family;
  const CoefficientFamily& info = coefficient_family_info(c.family);
  c.separated_by = info.separated_by;
  Stage2Options so;
  so.table = design.table();
  so.base_attitude = design.base_attitude();
  so.bias_wander = design.wander();
  so.parameters = current;
  so.parameters.push_back(component);
  const Stage2Result r = solve_stage2(design.inputs(), design.site(), so);
  const auto j = static_cast<Eigen::Index>(current.size());
  const double sigma = std::sqrt(r.cov(j, j));
  const bool ok = r.observable.back() && std::isfinite(sigma) &&
                  sigma < design.prior(component) / o.separable_ratio;
  (ok ? c.separable : c.aliased).push_back(component);
  const std::string& name = cat[static_cast<std::size_t>(component)].name;
  for (const auto& d : r.unobservable_directions)
    if (d.find(name) != std::string::npos) c.aliased_with = d;
  return c;
}

}  // namespace

std::string DeterminedCombination::text() const {
  std::string out;
  const auto& cat = coefficient_catalog();
  for (const auto& [k, w] : weights) {
    if (std::abs(w) < 5e-4) continue;
    char b[32];
    std::snprintf(b, sizeof b, "%s%+.3f ", out.empty() ? "" : " ", w);
    out += b + cat[static_cast<std::size_t>(k)].name;
  }
  return out.empty() ? out : out.substr(out[0] == ' ' ? 1 : 0);
}

std::vector<DeterminedCombination> determined_combinations(const Stage2Result& fit,
                                                           const std::vector<int>& components) {
  std::vector<Eigen::Index> at;  // positions of the components not observable one by one
  for (int k : components) {
    const auto it = std::find(fit.parameters.begin(), fit.parameters.end(), k);
    if (it == fit.parameters.end()) continue;
    const auto i = it - fit.parameters.begin();
    if (!fit.observable[static_cast<std::size_t>(i)]) at.push_back(i);
  }
  if (at.empty() || fit.null_vectors.empty() || fit.theta_min_norm.size() == 0) return {};
  const auto a = static_cast<Eigen::Index>(at.size());
  // Z: the null vectors restricted to these components; a determined combination c has Z c = 0.
  Eigen::MatrixXd Z(static_cast<Eigen::Index>(fit.null_vectors.size()), a);
  for (std::size_t r = 0; r < fit.null_vectors.size(); ++r)
    for (Eigen::Index j = 0; j < a; ++j)
      Z(static_cast<Eigen::Index>(r), j) = fit.null_vectors[r](at[static_cast<std::size_t>(j)]);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Z, Eigen::ComputeFullV);
  const double smax = svd.singularValues().size() ? svd.singularValues()(0) : 0.0;
  Eigen::Index rank = 0;
  for (Eigen::Index k = 0; k < svd.singularValues().size(); ++k)
    if (svd.singularValues()(k) > 1e-8 * std::max(1.0, smax)) ++rank;
  std::vector<DeterminedCombination> out;
  for (Eigen::Index k = rank; k < a; ++k) {
    Eigen::VectorXd c = svd.matrixV().col(k);
    Eigen::Index lead = 0;
    c.cwiseAbs().maxCoeff(&lead);
    if (c(lead) < 0.0) c = -c;
    DeterminedCombination d;
    Eigen::VectorXd full = Eigen::VectorXd::Zero(fit.theta_min_norm.size());
    for (Eigen::Index j = 0; j < a; ++j) {
      const auto i = at[static_cast<std::size_t>(j)];
      full(i) = c(j);
      d.weights.emplace_back(fit.parameters[static_cast<std::size_t>(i)], c(j));
    }
    d.value = full.dot(fit.theta_min_norm);
    d.sigma = std::sqrt(std::max(0.0, full.dot(fit.cov_min_norm * full)));
    out.push_back(std::move(d));
  }
  return out;
}

namespace {

bool is_family(const std::string& name) {
  const auto& all = coefficient_families();
  return std::any_of(all.begin(), all.end(), [&](const auto& f) { return f.name == name; });
}

// The family a default candidate waits for on a session whose temperature varies (empty: none):
// a polynomial in T - T0 grows degree by degree (degree d once degree d - 1 of the same
// coefficient is in the model), and a bias drift in time waits for the same bias's degree-1
// temperature term. On a ramp time and temperature rise together: with every thermal family
// hidden, a line in time (accel.bias_drift) or a cube in temperature fitted the bias's hidden
// linear and quadratic temperature terms better than the line in temperature and was the first
// candidate with a zero truth (3 of 4 all-hidden ramps, issue 33); the chambers' soaks test
// degree by degree for the same reason (thermal_diagnosis.cpp).
std::string waits_for(const std::string& family) {
  const std::string drift = "_drift";
  if (family.size() > drift.size() &&
      family.compare(family.size() - drift.size(), drift.size(), drift) == 0) {
    const std::string lower = family.substr(0, family.size() - drift.size()) + "_temp1";
    return is_family(lower) ? lower : "";
  }
  if (!coefficient_family_info(family).thermal()) return "";
  const auto [base, degree] = thermal_family_parts(family);
  if (degree < 2) return "";
  const std::string lower = base + "_temp" + std::to_string(degree - 1);
  return is_family(lower) ? lower : "";
}

bool has_family(const std::vector<int>& current, const std::string& family) {
  const auto& cat = coefficient_catalog();
  return std::any_of(current.begin(), current.end(),
                     [&](int c) { return cat[static_cast<std::size_t>(c)].family == family; });
}

}  // namespace

namespace diagnosis_detail {

std::vector<int> candidate_components(const std::vector<std::string>& candidates,
                                      const std::vector<int>& current, bool thermal) {
  std::vector<std::string> families = candidates;
  if (families.empty())
    for (const auto& f : coefficient_families()) {
      if (f.base || !(thermal || !f.thermal())) continue;
      const std::string lower = thermal ? waits_for(f.name) : "";
      if (lower.empty() || has_family(current, lower)) families.push_back(f.name);
    }
  const auto& cat = coefficient_catalog();
  std::vector<int> out;
  for (std::size_t k = 0; k < cat.size(); ++k) {
    const int c = static_cast<int>(k);
    if (std::find(families.begin(), families.end(), cat[k].family) != families.end() &&
        std::find(current.begin(), current.end(), c) == current.end())
      out.push_back(c);
  }
  return out;
}

double largest_shift(const FitFigures& before, const FitFigures& after,
                     const std::vector<int>& base) {
  double worst = 0.0;
  for (std::size_t k = 0; k < base.size(); ++k) {
    const auto i = static_cast<Eigen::Index>(k);
    const double s = std::sqrt(before.fit.cov(i, i));
    if (!before.fit.observable[k] || !after.fit.observable[k] || !(s > 0.0)) continue;
    worst = std::max(worst, std::abs(after.fit.theta(i) - before.fit.theta(i)) / s);
  }
  return worst;
}

// Tests one separable candidate against the current fit.
// The test of a nested extension: the chi-square test of the likelihood ratio while the noise
// model holds (the extended fit's chi-square within its 99 % quantile), else the F test, which
// scales the noise by the fit's own residual.
void test_statistic(const FitFigures& now, CandidateTest& c) {
  const double lr = std::max(0.0, now.chi2 - c.with.chi2);
  const int dof1 = c.with.fit.dof;
  c.likelihood_ratio = lr;
  if (c.with.chi2 <= boost::math::quantile(boost::math::chi_squared(dof1), kNoiseModelLevel))
    chi2_verdict(c, "chi2", lr);
  else
    f_verdict(c, lr, c.with.fit.chi2_per_dof, dof1);
}

bool test_extension(const std::vector<int>& current, const FitFigures& now, CandidateTest& c,
                    const std::function<FitFigures(const std::vector<int>&)>& fit) {
  std::vector<int> with = current;
  with.insert(with.end(), c.separable.begin(), c.separable.end());
  c.with = fit(with);
  c.dof = c.with.fit.rank - now.fit.rank;
  if (c.dof <= 0 || c.with.fit.dof <= 0) return false;
  test_statistic(now, c);
  c.base_shift_sigma = largest_shift(now, c.with, current);
  return true;
}

// Marks the round's significant candidates and returns the most significant one, or nullptr.
CandidateTest* best_of(std::vector<CandidateTest>& round, double alpha) {
  const auto tested =
      std::count_if(round.begin(), round.end(), [](const CandidateTest& c) { return c.dof > 0; });
  return most_significant_of(round,
                             alpha / static_cast<double>(std::max<std::ptrdiff_t>(1, tested)),
                             [](const CandidateTest& a, const CandidateTest& b) {
                               return a.likelihood_ratio > b.likelihood_ratio;
                             });
}

// The round's most significant candidate, with the candidates that explain the residual as well
// (their fits' chi-square within kAmbiguityMargin): the plan cannot tell them apart. Another
// family's: name neither; the same family's: the family is named, its axis is ambiguous.
CandidateTest* choose(std::vector<CandidateTest>& round, double alpha) {
  CandidateTest* best = best_of(round, alpha);
  if (!best) return nullptr;
  for (auto& c : round)
    if (&c != best && c.significant && c.with.chi2 - best->with.chi2 < kAmbiguityMargin)
      best->ambiguous_with.push_back(c);
  best->named = std::none_of(best->ambiguous_with.begin(), best->ambiguous_with.end(),
                             [&](const CandidateTest& c) { return c.family != best->family; });
  return best;
}

// What the plan could not separate (against the final model), one entry per family.
std::vector<CandidateTest> not_separable(const std::vector<CandidateTest>& last_round) {
  std::vector<CandidateTest> out;
  for (const auto& c : last_round) {
    if (c.aliased.empty()) continue;
    auto it = std::find_if(out.begin(), out.end(),
                           [&](const CandidateTest& n) { return n.family == c.family; });
    if (it == out.end()) {
      out.push_back(c);
    } else {
      it->aliased.insert(it->aliased.end(), c.aliased.begin(), c.aliased.end());
      if (it->aliased_with.empty()) it->aliased_with = c.aliased_with;
    }
  }
  return out;
}

std::string heldout_refusal(const FitFigures& before, const FitFigures& after, int dof,
                            double alpha) {
  if (before.heldout_dwells == 0 || after.heldout_dwells == 0 || !(after.heldout_chi2 > 0.0))
    return "";
  const double scale = std::max(1.0, after.heldout * after.heldout);
  const double gain = (before.heldout_chi2 - after.heldout_chi2) / scale;
  const double q = boost::math::quantile(boost::math::chi_squared(std::max(1, dof)), 1.0 - alpha);
  if (gain >= q) return "";
  char b[200];
  std::snprintf(b, sizeof b, "the held-out chi-square gains %.3g%s (%.3g needed)", gain,
                scale > 1.0 ? " in its residual's scale" : "", q);
  return b;
}

void run_rounds(DiagnosisReport& rep, int max_findings, const RoundRunner& run_round,
                const BestCompleter& complete) {
  std::vector<int> current = rep.initial_parameters;
  FitFigures now = rep.initial;
  while (static_cast<int>(rep.findings.size()) < max_findings) {
    std::vector<CandidateTest> round = run_round(current, now);
    CandidateTest* best = choose(round, rep.alpha);
    if (best && complete) {
      std::vector<int> with = current;
      with.insert(with.end(), best->separable.begin(), best->separable.end());
      complete(with, *best);
    }
    rep.rounds.push_back(round);
    if (!best) break;
    if (!best->named) {
      rep.ambiguous.push_back(*best);
      break;
    }
    const std::string refused = heldout_refusal(now, best->with, best->dof, rep.alpha);
    if (!refused.empty()) {
      for (auto& c : rep.rounds.back()) c.named = false;
      rep.rejected.push_back(*best);
      rep.stops.push_back(best->family + ", the most significant candidate, is not named: " +
                          refused + "; the search stops, its residual unexplained");
      break;
    }
    rep.findings.push_back(*best);
    current.insert(current.end(), best->separable.begin(), best->separable.end());
    now = best->with;
  }
  if (!rep.rounds.empty()) rep.not_separable = not_separable(rep.rounds.back());
  rep.final_parameters = current;
  rep.final_fit = now;
}

}  // namespace diagnosis_detail

double heldout_predictive_quantile(const HeldoutFigures& f, double level) {
  const double m = f.heldout_inputs;
  if (!(m > 0.0)) return 0.0;
  const double c2 = 0.5 * f.heldout_predictive_variance, c3 = f.heldout_predictive_cumulant3 / 8.0;
  if (!(c2 > 0.0) || !(c3 > 0.0)) return boost::math::quantile(boost::math::chi_squared(m), level);
  // A chi-square of l dof has the quadratic form's skewness; shifted and scaled to its mean and
  // variance.
  const double l = c2 * c2 * c2 / (c3 * c3);
  return m + std::sqrt(c2 / l) * (boost::math::quantile(boost::math::chi_squared(l), level) - l);
}

using namespace diagnosis_detail;

namespace {

void test_candidate(const StaticDesign& design, const std::vector<int>& current,
                    const FitFigures& now, CandidateTest& c) {
  const auto fit = [&](const std::vector<int>& with) { return figures(design, with); };
  if (!test_extension(current, now, c, fit)) return;
  const auto& p = c.with.fit.parameters;
  for (int k : c.separable) {
    const auto at = std::find(p.begin(), p.end(), k) - p.begin();
    if (c.with.fit.observable[static_cast<std::size_t>(at)]) c.determined.push_back(k);
  }
  c.combinations = determined_combinations(c.with.fit, c.separable);
}

DwellResidual residual_of(const EquivalentInputs& in, const Site& site, const Stage2Options& base) {
  DwellResidual d;
  d.dwell = in.dwell.index;
  d.label = in.dwell.label;
  const Matrix6d R = stage2_input_covariance(in, site, base.table) +
                     stage2_wander_covariance(in, in, base.bias_wander);
  for (int i = 0; i < 6; ++i) d.sigma(i) = std::sqrt(R(i, i));
  return d;
}

// Residuals of every dwell under the regularized fit of `parameters`; `after` or `before`.
void fill_residuals(const StaticDesign& design, const std::vector<int>& parameters,
                    std::vector<DwellResidual>& out, bool after) {
  const auto dwells = design.whiten(parameters);
  const Eigen::VectorXd theta = solve_with_prior(dwells, prior_sigmas(design, parameters), -1);
  for (std::size_t i = 0; i < dwells.size(); ++i) {
    const Eigen::VectorXd r = dwells[i].u - dwells[i].H * theta;
    auto& target = after ? out[i].after : out[i].before;
    target.setConstant(std::numeric_limits<double>::quiet_NaN());
    for (std::size_t a = 0; a < dwells[i].rows.size(); ++a)
      target(dwells[i].rows[a]) = r(static_cast<Eigen::Index>(a));
  }
}

}  // namespace

namespace {

// One round: every candidate component against the current model, then each family's separable
// components together (an effect on every axis at once shows only partly in each one alone).
std::vector<CandidateTest> run_round(const StaticDesign& design, const std::vector<int>& current,
                                     const FitFigures& now, const DiagnosisOptions& o) {
  std::vector<CandidateTest> round;
  for (int component : diagnosis_detail::candidate_components(o.candidates, current, o.thermal)) {
    CandidateTest c = separability(design, current, component, o);
    if (!c.separable.empty()) test_candidate(design, current, now, c);
    round.push_back(std::move(c));
  }
  add_family_candidates<CandidateTest>(
      round, {}, [&](CandidateTest& all) { test_candidate(design, current, now, all); });
  return round;
}

}  // namespace

DwellTests::DwellTests(std::vector<EquivalentInputs> inputs, const Site& site,
                       const Stage2Options& base, const DiagnosisOptions& o)
    : inputs_(std::move(inputs)), site_(site), base_(base), options_(o) {
  if (!(o.alpha > 0.0 && o.alpha < 1.0) || !(o.separable_ratio >= 1.0))
    throw std::invalid_argument("diagnosis: alpha must be in (0, 1), separable_ratio >= 1");
  for (const auto& in : inputs_)
    for (bool e : in.estimated) inputs_count_ += e ? 1 : 0;
  if (inputs_count_ <= static_cast<int>(base.parameters.size()))
    throw std::invalid_argument(
        "diagnosis: " + std::to_string(inputs_.size()) + " dwells give " +
        std::to_string(inputs_count_) + " equivalent inputs, not more than the model's " +
        std::to_string(base.parameters.size()) + " coefficients: too few dwells to test anything");
}

FitFigures DwellTests::fit(const std::vector<int>& parameters) const {
  return figures(StaticDesign(inputs_, site_, base_, options_.prior_sigma), parameters);
}

std::vector<CandidateTest> DwellTests::round(const std::vector<int>& current,
                                             const FitFigures& now) const {
  return run_round(StaticDesign(inputs_, site_, base_, options_.prior_sigma), current, now,
                   options_);
}

std::vector<WhitenedDwell> DwellTests::whitened(const std::vector<int>& parameters) const {
  std::vector<WhitenedDwell> out;
  for (auto& w : StaticDesign(inputs_, site_, base_, options_.prior_sigma).whiten(parameters))
    out.push_back({std::move(w.A), std::move(w.L), std::move(w.y), std::move(w.rows)});
  return out;
}

Eigen::VectorXd DwellTests::prior(const std::vector<int>& parameters) const {
  return prior_sigmas(StaticDesign(inputs_, site_, base_, options_.prior_sigma), parameters);
}

std::vector<DwellResidual> DwellTests::residuals(const std::vector<int>& initial,
                                                 const std::vector<int>& final) const {
  const StaticDesign design(inputs_, site_, base_, options_.prior_sigma);
  std::vector<DwellResidual> out;
  for (const auto& in : inputs_) out.push_back(residual_of(in, site_, base_));
  fill_residuals(design, initial, out, false);
  fill_residuals(design, final, out, true);
  return out;
}

}  // namespace sinscal
