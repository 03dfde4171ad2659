#include "filter/diagnosis/term_library.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <cstdio>
#include <limits>

#include "filter/strapdown/ins_error_model.hpp"
#include "models/earth.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

// The most terms the forward selection takes.
constexpr int kMaxTerms = 4;
// The thresholded pass: a selected term below this many sigmas is dropped (STLSQ's threshold).
constexpr double kThresholdSigma = 3.0;

const char* const kAxis[3] = {"x", "y", "z"};

// One library column: which sensor axis, its function of the body's specific force (m/s^2) and
// of the dwell's middle time (s), per unit of `unit`.
struct Column {
  LibraryTerm term;
  bool gyro = false;
  int product_a = -1, product_b = -1;  // f_a f_b / g^2; -1: a step
  double step_t = 0.0;                 // s: 1 after this time
  double value(const Eigen::Vector3d& f_b, double t) const {
    if (product_a >= 0) return f_b(product_a) * f_b(product_b) / (units::g0 * units::g0);
    return t > step_t ? 1.0 : 0.0;
  }
};

LibraryTerm term_of(bool gyro, int axis, const std::string& formula, bool product) {
  LibraryTerm t;
  t.sensor = gyro ? "gyro" : "accel";
  t.axis = axis;
  t.formula = formula;
  t.unit = gyro ? (product ? "deg/h/g^2" : "deg/h") : (product ? "ug/g^2" : "ug");
  t.si_per_unit = gyro ? units::deg_per_h : units::ug;
  return t;
}

// The library: f_a f_b on each axis of both triads; bias steps at a quarter, half and three
// quarters of the dwells (in time).
std::vector<Column> library(const std::vector<EquivalentInputs>& inputs) {
  std::vector<double> mids;
  mids.reserve(inputs.size());
  for (const auto& in : inputs) mids.push_back(0.5 * (in.dwell.t_start + in.dwell.t_end));
  std::sort(mids.begin(), mids.end());
  std::vector<Column> out;
  for (const bool gyro : {false, true})
    for (int axis = 0; axis < 3; ++axis) {
      for (int a = 0; a < 3; ++a)
        for (int b = a; b < 3; ++b) {
          Column c;
          c.gyro = gyro;
          c.product_a = a;
          c.product_b = b;
          c.term = term_of(gyro, axis,
                           a == b ? std::string("f_") + kAxis[a] + "^2"
                                  : std::string("f_") + kAxis[a] + " f_" + kAxis[b],
                           true);
          out.push_back(c);
        }
      for (const double q : {0.25, 0.5, 0.75}) {
        const auto k = static_cast<std::size_t>(q * static_cast<double>(mids.size()));
        if (k == 0 || k >= mids.size()) continue;
        Column c;
        c.gyro = gyro;
        c.step_t = 0.5 * (mids[k - 1] + mids[k]);
        char b[64];
        std::snprintf(b, sizeof b, "step after t = %.0f s", c.step_t);
        c.term = term_of(gyro, axis, b, false);
        out.push_back(c);
      }
    }
  return out;
}

// The stacked whitened system: the model's columns A, the library's B, the data y; each dwell's
// first row.
struct Stacked {
  Eigen::MatrixXd A, B;
  Eigen::VectorXd y, prior;
  std::vector<Eigen::Index> first;  // per dwell, plus the end
};

Stacked stack(const DwellTests& dwells, const std::vector<int>& parameters,
              const std::vector<Column>& lib) {
  const auto w = dwells.whitened(parameters);
  const auto& inputs = dwells.dwell_inputs();
  const Earth& earth = Earth::wgs84();
  const Eigen::Vector3d g_n = earth.gravity_n(dwells.site().lat_rad, dwells.site().h_m);
  Stacked s;
  Eigen::Index n = 0;
  for (const auto& d : w) n += d.y.size();
  const Eigen::Index p = w.empty() ? 0 : w.front().A.cols();
  const auto m = static_cast<Eigen::Index>(lib.size());
  s.A.resize(n, p);
  s.B.resize(n, m);
  s.y.resize(n);
  s.prior = dwells.prior(parameters);
  Eigen::Index at = 0;
  for (std::size_t k = 0; k < w.size(); ++k) {
    const auto& d = w[k];
    const auto& in = inputs[k];
    const Eigen::Matrix3d& C = in.dwell.C_b_n_known;
    const Eigen::Vector3d f_b = -C.transpose() * g_n;
    const double t = 0.5 * (in.dwell.t_start + in.dwell.t_end);
    const auto rows = d.y.size();
    s.first.push_back(at);
    s.A.middleRows(at, rows) = d.A;
    s.y.segment(at, rows) = d.y;
    for (Eigen::Index j = 0; j < m; ++j) {
      const Column& c = lib[static_cast<std::size_t>(j)];
      Eigen::Matrix<double, 6, 1> v = Eigen::Matrix<double, 6, 1>::Zero();
      const Eigen::Vector3d body =
          Eigen::Vector3d::Unit(c.term.axis) * c.value(f_b, t) * c.term.si_per_unit;
      v.segment<3>(c.gyro ? ins_input::kGyro.index : ins_input::kAccel.index) = C * body;
      Eigen::VectorXd sel(rows);
      for (Eigen::Index r = 0; r < rows; ++r) sel(r) = v(d.rows[static_cast<std::size_t>(r)]);
      s.B.block(at, j, rows, 1) = d.L.triangularView<Eigen::Lower>().solve(sel);
    }
    at += rows;
  }
  s.first.push_back(at);
  return s;
}

// The model's columns projected out of y and B (the library explains what the model cannot).
void project_out_model(Stacked& s) {
  if (s.A.cols() == 0) return;
  Eigen::MatrixXd N = s.A.transpose() * s.A;
  N.diagonal() += s.prior.cwiseInverse().cwiseAbs2();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(N);
  s.y -= s.A * ldlt.solve(s.A.transpose() * s.y);
  s.B -= s.A * ldlt.solve(s.A.transpose() * s.B);
}

// Least squares of y on the columns `cols` of B, without the rows of dwell `skip` (-1: none).
Eigen::VectorXd solve_on(const Stacked& s, const std::vector<Eigen::Index>& cols, int skip) {
  const auto k = static_cast<Eigen::Index>(cols.size());
  if (k == 0) return Eigen::VectorXd();
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(k, k);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(k);
  for (std::size_t d = 0; d + 1 < s.first.size(); ++d) {
    if (static_cast<int>(d) == skip) continue;
    const Eigen::Index r0 = s.first[d], rows = s.first[d + 1] - r0;
    Eigen::MatrixXd X(rows, k);
    for (Eigen::Index j = 0; j < k; ++j)
      X.col(j) = s.B.block(r0, cols[static_cast<std::size_t>(j)], rows, 1);
    N += X.transpose() * X;
    b += X.transpose() * s.y.segment(r0, rows);
  }
  N.diagonal().array() += 1e-9 * (1.0 + N.diagonal().maxCoeff());
  return N.ldlt().solve(b);
}

double chi2_of(const Stacked& s, const std::vector<Eigen::Index>& cols, const Eigen::VectorXd& c,
               Eigen::Index r0, Eigen::Index rows) {
  Eigen::VectorXd r = s.y.segment(r0, rows);
  for (std::size_t j = 0; j < cols.size(); ++j)
    r -= s.B.block(r0, cols[j], rows, 1) * c(static_cast<Eigen::Index>(j));
  return r.squaredNorm();
}

// Leave-one-dwell-out chi-square of the fit on `cols`.
double heldout_chi2(const Stacked& s, const std::vector<Eigen::Index>& cols) {
  double sum = 0.0;
  for (std::size_t d = 0; d + 1 < s.first.size(); ++d) {
    const Eigen::VectorXd c = solve_on(s, cols, static_cast<int>(d));
    sum += chi2_of(s, cols, c, s.first[d], s.first[d + 1] - s.first[d]);
  }
  return sum;
}

// Forward selection: the term that lowers the chi-square most, while the held-out chi-square
// falls.
std::vector<Eigen::Index> forward_select(const Stacked& s, double& heldout) {
  std::vector<Eigen::Index> cols;
  heldout = heldout_chi2(s, cols);
  for (int step = 0; step < kMaxTerms; ++step) {
    Eigen::Index best = -1;
    double best_chi2 = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < s.B.cols(); ++j) {
      if (std::find(cols.begin(), cols.end(), j) != cols.end()) continue;
      if (s.B.col(j).squaredNorm() < 1e-12 * s.y.squaredNorm()) continue;  // the model holds it
      auto trial = cols;
      trial.push_back(j);
      const double c2 = chi2_of(s, trial, solve_on(s, trial, -1), 0, s.y.size());
      if (c2 < best_chi2) {
        best_chi2 = c2;
        best = j;
      }
    }
    if (best < 0) break;
    auto trial = cols;
    trial.push_back(best);
    const double h = heldout_chi2(s, trial);
    if (!(h < heldout)) break;
    cols = trial;
    heldout = h;
  }
  return cols;
}

// Covariance of the fit on `cols` (unit noise).
Eigen::MatrixXd covariance_on(const Stacked& s, const std::vector<Eigen::Index>& cols) {
  const auto k = static_cast<Eigen::Index>(cols.size());
  Eigen::MatrixXd X(s.B.rows(), k);
  for (Eigen::Index j = 0; j < k; ++j) X.col(j) = s.B.col(cols[static_cast<std::size_t>(j)]);
  const Eigen::MatrixXd N = X.transpose() * X;
  return N.ldlt().solve(Eigen::MatrixXd::Identity(k, k));
}

// The library terms whose columns are one function with column j on these dwells, each with the
// value and sigma it would have alone in j's place.
std::vector<LibraryTerm> aliases_of(const Stacked& s, const std::vector<Column>& lib,
                                    Eigen::Index j, double value, double sigma) {
  std::vector<LibraryTerm> out;
  const double nj = s.B.col(j).norm();
  for (Eigen::Index k = 0; k < s.B.cols(); ++k) {
    const double nk = s.B.col(k).norm();
    if (k == j || !(nk > 0.0) || !(nj > 0.0)) continue;
    const double r = s.B.col(j).dot(s.B.col(k)) / (nj * nk);
    if (std::abs(r) < kAliasCorrelation) continue;
    LibraryTerm t = lib[static_cast<std::size_t>(k)].term;
    t.value = value * r * nj / nk;
    t.sigma = sigma * nj / nk;
    out.push_back(t);
  }
  return out;
}

std::string how_to_add(const std::vector<LibraryTerm>& terms) {
  if (terms.empty()) return "";
  const LibraryTerm& t = terms.front();
  return "to model it, add one entry to the family table (models/coefficient_families.cpp): a "
         "family such as " +
         t.sensor + ".library_" + kAxis[t.axis] + " with the column " + t.formula + " on the " +
         t.sensor + " " + kAxis[t.axis] + " axis (unit " + t.unit +
         "), its profile key and default prior; its Jacobian in models/imu_error_model.cpp";
}

}  // namespace

std::string LibraryTerm::text() const {
  char b[200];
  std::snprintf(b, sizeof b, "%s %s: %.3g +- %.2g %s * %s", sensor.c_str(), kAxis[axis], value,
                sigma, unit.c_str(), formula.c_str());
  std::string out = b;
  for (std::size_t k = 0; k < aliases.size(); ++k)
    out += (k == 0 ? " (or, not separable on this plan: " : "; ") + aliases[k].text() +
           (k + 1 == aliases.size() ? ")" : "");
  return out;
}

LibraryFit fit_term_library(const DwellTests& dwells, const std::vector<int>& parameters,
                            double alpha) {
  LibraryFit out;
  const std::vector<Column> lib = library(dwells.dwell_inputs());
  out.candidates = static_cast<int>(lib.size());
  Stacked s = stack(dwells, parameters, lib);
  project_out_model(s);
  out.chi2_before = s.y.squaredNorm();
  std::vector<Eigen::Index> cols = forward_select(s, out.heldout_after);
  out.heldout_before = heldout_chi2(s, {});
  // The thresholded pass: terms below kThresholdSigma dropped, the rest refitted, until stable.
  for (bool changed = true; changed && !cols.empty();) {
    const Eigen::VectorXd c = solve_on(s, cols, -1);
    const Eigen::MatrixXd P = covariance_on(s, cols);
    std::vector<Eigen::Index> kept;
    for (std::size_t j = 0; j < cols.size(); ++j) {
      const auto i = static_cast<Eigen::Index>(j);
      if (std::abs(c(i)) >= kThresholdSigma * std::sqrt(P(i, i))) kept.push_back(cols[j]);
    }
    changed = kept.size() != cols.size();
    cols = kept;
  }
  out.threshold_sigma = kThresholdSigma;
  out.heldout_after = heldout_chi2(s, cols);
  const int k = static_cast<int>(cols.size());
  out.heldout_needed = boost::math::quantile(boost::math::chi_squared(std::max(1, k)), 1.0 - alpha);
  if (k == 0 || out.heldout_before - out.heldout_after < out.heldout_needed) return out;
  const Eigen::VectorXd c = solve_on(s, cols, -1);
  const Eigen::MatrixXd P = covariance_on(s, cols);
  out.chi2_after = chi2_of(s, cols, c, 0, s.y.size());
  out.dof_after = std::max(1, static_cast<int>(s.y.size()) - static_cast<int>(s.A.cols()) - k);
  const double scale = std::sqrt(std::max(1.0, out.chi2_after / out.dof_after));
  for (std::size_t j = 0; j < cols.size(); ++j) {
    LibraryTerm t = lib[static_cast<std::size_t>(cols[j])].term;
    const auto i = static_cast<Eigen::Index>(j);
    t.value = c(i);
    t.sigma = std::sqrt(P(i, i)) * scale;
    t.aliases = aliases_of(s, lib, cols[j], t.value, t.sigma);
    out.terms.push_back(t);
  }
  out.how_to_add = how_to_add(out.terms);
  return out;
}

}  // namespace sinscal
