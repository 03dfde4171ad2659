#include "filter/thermal/soak_fit.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <cmath>
#include <map>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"

namespace sinscal {

SoakTemperature measure_soak_temperature(const LogFormat& log) {
  LogReader reader(log);
  SoakTemperature out;
  ImuSample s;
  double sum_a = 0.0, sum_g = 0.0;
  while (reader.next(s)) {
    if (!s.has_temperature)
      throw LogError(log.file, reader.line(),
                     "no temperature column: a soak's temperature comes from the log "
                     "(docs/formats.md \"Temperature columns\")");
    const double lo = std::min(s.accel_temperature_c, s.gyro_temperature_c);
    const double hi = std::max(s.accel_temperature_c, s.gyro_temperature_c);
    if (out.samples == 0 || lo < out.min_c) {
      out.min_c = lo;
      out.t_min = s.t;
      out.line_min = reader.line();
    }
    if (out.samples == 0 || hi > out.max_c) {
      out.max_c = hi;
      out.t_max = s.t;
      out.line_max = reader.line();
    }
    sum_a += s.accel_temperature_c;
    sum_g += s.gyro_temperature_c;
    ++out.samples;
  }
  if (out.samples == 0) throw LogError(log.file, 0, "no samples");
  out.file_min = out.file_max = log.file;
  out.accel_mean_c = sum_a / static_cast<double>(out.samples);
  out.gyro_mean_c = sum_g / static_cast<double>(out.samples);
  return out;
}

namespace {

bool family_exists(const std::string& name) {
  const auto& all = coefficient_families();
  return std::any_of(all.begin(), all.end(), [&](const auto& f) { return f.name == name; });
}

// One family's coefficients among the fitted ones.
struct FamilyColumns {
  std::string name;
  bool gyro_temperature = true;  // which triad's temperature it follows
  std::vector<int> positions;    // in the common coefficient list
  int max_degree = 0;
};

// The soaks on their common coefficients, scaled: each coefficient by its mean per-soak sigma,
// the temperature by the largest |T - T0|, so the normal equations are well conditioned.
struct Scaled {
  std::vector<int> catalog;             // common coefficients
  Eigen::VectorXd scale;                // SI per scaled unit
  std::vector<Eigen::VectorXd> x;       // per soak
  std::vector<Eigen::MatrixXd> cov;     // per soak
  std::vector<double> u_gyro, u_accel;  // (T - T0) / t_scale per soak
  double t_scale = 1.0;                 // deg C
};

Scaled scale_soaks(const std::vector<SoakEstimate>& soaks, double t0) {
  Scaled s;
  for (int c : soaks.front().catalog) {
    const bool everywhere = std::all_of(soaks.begin(), soaks.end(), [&](const SoakEstimate& e) {
      return std::find(e.catalog.begin(), e.catalog.end(), c) != e.catalog.end();
    });
    if (everywhere) s.catalog.push_back(c);
  }
  const auto n = static_cast<Eigen::Index>(s.catalog.size());
  if (n == 0) throw std::invalid_argument("the soaks share no estimated coefficient");
  s.scale = Eigen::VectorXd::Zero(n);
  for (const auto& e : soaks) {
    Eigen::VectorXd x(n);
    Eigen::MatrixXd P(n, n);
    std::vector<Eigen::Index> at(static_cast<std::size_t>(n));
    for (Eigen::Index i = 0; i < n; ++i)
      at[static_cast<std::size_t>(i)] = static_cast<Eigen::Index>(
          std::find(e.catalog.begin(), e.catalog.end(), s.catalog[static_cast<std::size_t>(i)]) -
          e.catalog.begin());
    for (Eigen::Index i = 0; i < n; ++i) {
      x(i) = e.value(at[static_cast<std::size_t>(i)]);
      for (Eigen::Index j = 0; j < n; ++j)
        P(i, j) = e.covariance(at[static_cast<std::size_t>(i)], at[static_cast<std::size_t>(j)]);
    }
    s.scale += P.diagonal().cwiseSqrt();
    s.x.push_back(x);
    s.cov.push_back(P);
    s.t_scale = std::max(
        {s.t_scale, std::abs(e.gyro_temperature_c - t0), std::abs(e.accel_temperature_c - t0)});
  }
  s.scale /= static_cast<double>(soaks.size());
  for (Eigen::Index i = 0; i < n; ++i)
    if (!(s.scale(i) > 0.0))
      throw std::invalid_argument(
          "coefficient " +
          coefficient_catalog()[static_cast<std::size_t>(s.catalog[static_cast<std::size_t>(i)])]
              .name +
          " has a zero sigma in the soaks");
  const Eigen::VectorXd inv = s.scale.cwiseInverse();
  for (std::size_t k = 0; k < soaks.size(); ++k) {
    s.x[k] = s.x[k].cwiseProduct(inv);
    s.cov[k] = inv.asDiagonal() * s.cov[k] * inv.asDiagonal();
    s.u_gyro.push_back((soaks[k].gyro_temperature_c - t0) / s.t_scale);
    s.u_accel.push_back((soaks[k].accel_temperature_c - t0) / s.t_scale);
  }
  return s;
}

// A parameter of the fit: coefficient `position` (common list), power `degree` of u.
struct Parameter {
  int position = 0;
  int degree = 0;
  bool gyro_temperature = true;
};

struct Solution {
  Eigen::VectorXd theta;
  Eigen::MatrixXd covariance;
  double chi2 = 0.0;
};

// Generalized least squares over the soaks for the parameters, on the coefficients `rows`
// (positions in the common list; the soaks' covariance restricted to them).
Solution solve(const Scaled& s, const std::vector<int>& rows,
               const std::vector<Parameter>& params) {
  const auto m = static_cast<Eigen::Index>(rows.size());
  const auto p = static_cast<Eigen::Index>(params.size());
  Eigen::MatrixXd N = Eigen::MatrixXd::Zero(p, p);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(p);
  std::vector<Eigen::MatrixXd> A(s.x.size()), W(s.x.size());
  std::vector<Eigen::VectorXd> x(s.x.size());
  for (std::size_t k = 0; k < s.x.size(); ++k) {
    Eigen::MatrixXd P(m, m);
    x[k].resize(m);
    for (Eigen::Index i = 0; i < m; ++i) {
      x[k](i) = s.x[k](rows[static_cast<std::size_t>(i)]);
      for (Eigen::Index j = 0; j < m; ++j)
        P(i, j) = s.cov[k](rows[static_cast<std::size_t>(i)], rows[static_cast<std::size_t>(j)]);
    }
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(P);
    if (ldlt.info() != Eigen::Success || ldlt.vectorD().minCoeff() <= 0.0)
      throw std::invalid_argument("a soak's covariance is not positive definite");
    W[k] = ldlt.solve(Eigen::MatrixXd::Identity(m, m));
    A[k] = Eigen::MatrixXd::Zero(m, p);
    for (Eigen::Index j = 0; j < p; ++j) {
      const Parameter& q = params[static_cast<std::size_t>(j)];
      const auto row = std::find(rows.begin(), rows.end(), q.position) - rows.begin();
      const double u = q.gyro_temperature ? s.u_gyro[k] : s.u_accel[k];
      A[k](row, j) = std::pow(u, q.degree);
    }
    N += A[k].transpose() * W[k] * A[k];
    b += A[k].transpose() * W[k] * x[k];
  }
  const Eigen::LDLT<Eigen::MatrixXd> normal(N);
  Solution out;
  out.covariance = normal.solve(Eigen::MatrixXd::Identity(p, p));
  out.theta = out.covariance * b;
  if (!out.theta.allFinite() || normal.vectorD().minCoeff() <= 0.0)
    throw std::invalid_argument(
        "the soaks' temperatures do not determine the fit (too few distinct temperatures)");
  for (std::size_t k = 0; k < s.x.size(); ++k) {
    const Eigen::VectorXd r = x[k] - A[k] * out.theta;
    out.chi2 += r.dot(W[k] * r);
  }
  return out;
}

std::vector<Parameter> parameters(const FamilyColumns& f, int degree) {
  std::vector<Parameter> out;
  for (int d = 0; d <= degree; ++d)
    for (int pos : f.positions) out.push_back({pos, d, f.gyro_temperature});
  return out;
}

std::vector<FamilyColumns> group(const Scaled& s, std::size_t soaks, const ThermalFitOptions& o) {
  const auto& cat = coefficient_catalog();
  std::vector<FamilyColumns> out;
  for (std::size_t i = 0; i < s.catalog.size(); ++i) {
    const std::string& family = cat[static_cast<std::size_t>(s.catalog[i])].family;
    if (coefficient_family_info(family).thermal()) continue;  // fitted, not fitted against
    if (out.empty() || out.back().name != family) {
      FamilyColumns f;
      f.name = family;
      f.gyro_temperature = coefficient_family_info(family).output != FamilyOutput::Accel;
      while (f.max_degree < o.max_degree &&
             family_exists(thermal_family_name(family, f.max_degree + 1)))
        ++f.max_degree;
      f.max_degree = std::min(f.max_degree, static_cast<int>(soaks) - 2);
      out.push_back(f);
    }
    out.back().positions.push_back(static_cast<int>(i));
  }
  return out;
}

// The joint fit of `params` on the coefficients `rows`, unscaled into `fit`.
void joint_fit(const Scaled& s, const std::vector<int>& rows, const std::vector<Parameter>& params,
               std::size_t soaks, ThermalFit& fit) {
  const Solution joint = solve(s, rows, params);
  const auto& cat = coefficient_catalog();
  const auto np = static_cast<Eigen::Index>(params.size());
  Eigen::VectorXd unscale(np);
  fit.catalog.clear();
  for (Eigen::Index j = 0; j < np; ++j) {
    const Parameter& q = params[static_cast<std::size_t>(j)];
    const CoefficientInfo& base =
        cat[static_cast<std::size_t>(s.catalog[static_cast<std::size_t>(q.position)])];
    const std::string component = base.name.substr(base.family.size());
    const std::string name =
        q.degree == 0 ? base.name : thermal_family_name(base.family, q.degree) + component;
    fit.catalog.push_back(static_cast<int>(&coefficient_info(name) - cat.data()));
    unscale(j) = s.scale(q.position) / std::pow(s.t_scale, q.degree);
  }
  fit.value = joint.theta.cwiseProduct(unscale);
  fit.covariance = unscale.asDiagonal() * joint.covariance * unscale.asDiagonal();
  fit.chi2 = joint.chi2;
  fit.dof = static_cast<int>(rows.size() * soaks) - static_cast<int>(np);
  fit.p_value = fit.dof > 0 ? boost::math::cdf(boost::math::complement(
                                  boost::math::chi_squared_distribution<double>(fit.dof), fit.chi2))
                            : 1.0;
}

}  // namespace

std::pair<std::string, int> thermal_family_parts(const std::string& name) {
  const auto at = name.rfind("_temp");
  if (at == std::string::npos || at + 6 != name.size()) return {"", 0};
  const char d = name.back();
  if (d < '1' || d > '9') return {"", 0};
  return {name.substr(0, at), d - '0'};
}

std::string thermal_family_name(const std::string& family, int degree) {
  return family + "_temp" + std::to_string(degree);
}

bool thermal_family_exists(const std::string& family, int degree) {
  return family_exists(thermal_family_name(family, degree));
}

int ThermalFit::degree(const std::string& family) const {
  for (const auto& d : degrees)
    if (d.family == family) return d.degree;
  return -1;
}

namespace {

// The row of the fit's parameters that gives coefficient `catalog_index` at dT from T0.
Eigen::VectorXd at_row(const ThermalFit& fit, int catalog_index, double dT) {
  const auto& info = coefficient_catalog().at(static_cast<std::size_t>(catalog_index));
  const std::string component = info.name.substr(info.family.size());  // ".x" or ""
  Eigen::VectorXd g = Eigen::VectorXd::Zero(fit.value.size());
  bool found = false;
  for (int k = 0; k <= 3; ++k) {  // the family table allows degrees 1 to 3
    if (k > 0 && !thermal_family_exists(info.family, k)) continue;
    const std::string name =
        (k == 0 ? info.family : thermal_family_name(info.family, k)) + component;
    const int c = static_cast<int>(&coefficient_info(name) - coefficient_catalog().data());
    const auto it = std::find(fit.catalog.begin(), fit.catalog.end(), c);
    if (it == fit.catalog.end()) continue;
    g(it - fit.catalog.begin()) = std::pow(dT, k);
    found = found || k == 0;
  }
  if (!found) throw std::invalid_argument(info.name + " is not in the thermal fit");
  return g;
}

}  // namespace

std::pair<double, double> ThermalFit::at(int catalog_index, double temperature_c) const {
  const Eigen::VectorXd g =
      at_row(*this, catalog_index, temperature_c - options.reference_temperature_c);
  return {g.dot(value), std::sqrt(std::max(0.0, g.dot(covariance * g)))};
}

std::pair<Eigen::VectorXd, Eigen::MatrixXd> ThermalFit::predict(
    const SoakEstimate& soak, const std::vector<int>& coefficients) const {
  const auto n = static_cast<Eigen::Index>(coefficients.size());
  Eigen::MatrixXd G(n, value.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const int c = coefficients[static_cast<std::size_t>(i)];
    const auto& family =
        coefficient_family_info(coefficient_catalog()[static_cast<std::size_t>(c)].family);
    const double T =
        family.output == FamilyOutput::Accel ? soak.accel_temperature_c : soak.gyro_temperature_c;
    G.row(i) = at_row(*this, c, T - options.reference_temperature_c).transpose();
  }
  return {G * value, G * covariance * G.transpose()};
}

ThermalFit fit_soaks(const std::vector<SoakEstimate>& soaks, const ThermalFitOptions& options) {
  if (soaks.size() < 2) throw std::invalid_argument("a thermal fit needs at least 2 soaks");
  ThermalFit fit;
  fit.options = options;
  const Scaled s = scale_soaks(soaks, options.reference_temperature_c);
  const auto families = group(s, soaks.size(), options);
  // Each family's degree: raised while the drop in its own chi-square beats the quantile.
  std::vector<Parameter> all;
  for (const auto& f : families) {
    ThermalDegreeTest t;
    t.family = f.name;
    t.max_degree = f.max_degree;
    t.dof_step = static_cast<int>(f.positions.size());
    t.threshold = boost::math::quantile(
        boost::math::complement(boost::math::chi_squared_distribution<double>(t.dof_step),
                                options.significance / static_cast<double>(families.size())));
    t.chi2.push_back(solve(s, f.positions, parameters(f, 0)).chi2);
    while (t.degree < f.max_degree) {
      const double next = solve(s, f.positions, parameters(f, t.degree + 1)).chi2;
      t.chi2.push_back(next);
      if (t.chi2[static_cast<std::size_t>(t.degree)] - next <= t.threshold) break;
      ++t.degree;
    }
    const auto p = parameters(f, t.degree);
    all.insert(all.end(), p.begin(), p.end());
    fit.degrees.push_back(t);
  }
  // The joint fit with the chosen degrees and the soaks' full covariance.
  std::vector<int> rows;
  for (const auto& f : families) rows.insert(rows.end(), f.positions.begin(), f.positions.end());
  joint_fit(s, rows, all, soaks.size(), fit);
  return fit;
}

ThermalFit fit_soaks_with(const std::vector<SoakEstimate>& soaks,
                          const std::vector<std::string>& thermal_families,
                          double reference_temperature_c) {
  if (soaks.size() < 2) throw std::invalid_argument("a thermal fit needs at least 2 soaks");
  ThermalFit fit;
  fit.options.reference_temperature_c = reference_temperature_c;
  const Scaled s = scale_soaks(soaks, reference_temperature_c);
  ThermalFitOptions o;
  o.max_degree = 0;
  const auto families = group(s, soaks.size(), o);
  std::vector<Parameter> params;
  std::vector<int> rows;
  for (const auto& f : families) {
    rows.insert(rows.end(), f.positions.begin(), f.positions.end());
    for (int pos : f.positions) params.push_back({pos, 0, f.gyro_temperature});
  }
  for (const auto& name : thermal_families) {
    const auto [base, degree] = thermal_family_parts(name);
    if (degree == 0 || !family_exists(name))
      throw std::invalid_argument(name + " is not a polynomial thermal family");
    for (const auto& f : families)
      if (f.name == base)
        for (int pos : f.positions) params.push_back({pos, degree, f.gyro_temperature});
  }
  joint_fit(s, rows, params, soaks.size(), fit);
  return fit;
}

}  // namespace sinscal
