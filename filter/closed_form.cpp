#include "filter/closed_form.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>

#include "filter/dwell_navigation.hpp"
#include "models/attitude.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "rig/log_io.hpp"
#include "rig/plan.hpp"

namespace sinscal {

namespace {
// Input indices within u.
constexpr int kDfN = 0, kDfE = 1, kDfD = 2, kDwN = 3, kDwE = 4, kDwD = 5;
// Observed rows of the INS error state used by each channel.
constexpr int kRowPhiN = kInsNav.attitude.index + 0, kRowPhiE = kInsNav.attitude.index + 1,
              kRowPhiD = kInsNav.attitude.index + 2, kRowVN = kInsNav.velocity.index + 0,
              kRowVE = kInsNav.velocity.index + 1, kRowVD = kInsNav.velocity.index + 2;

InsState observed_state(const NavError& e) {
  InsState x;
  x << e.phi_n, e.dv_n, e.dp_n;
  return x;
}

/// Normal equations of one dwell's fit, per observed row (constant memory).
struct RowSums {
  double dd = 0.0;
  Vector6d gd = Vector6d::Zero();
  Matrix6d gg = Matrix6d::Zero();
};

struct DwellAccumulator {
  PlanDwell dwell;
  bool started = false;
  NavError prev;
  NavError at_point;
  double point_distance = 1e300;
  std::size_t steps = 0;
  std::map<int, RowSums> rows;
};

std::vector<int> rows_of(const ChannelSet& c) {
  std::vector<int> r;
  if (c.north) r.insert(r.end(), {kRowVN, kRowPhiE});
  if (c.east) r.insert(r.end(), {kRowVE, kRowPhiN});
  if (c.vertical) r.push_back(kRowVD);
  if (c.heading) r.push_back(kRowPhiD);
  return r;
}

bool is_velocity_row(int r) {
  return r >= kInsNav.velocity.index && r < kInsNav.velocity.index + 3;
}

}  // namespace

std::array<bool, 6> ChannelSet::inputs() const {
  std::array<bool, 6> in{};
  in[kDfN] = in[kDwE] = north;
  in[kDfE] = in[kDwN] = east;
  in[kDfD] = vertical;
  in[kDwD] = heading;
  return in;
}

std::vector<EquivalentInputs> run_stage1(SampleSource& source, const std::vector<PlanDwell>& dwells,
                                         const Site& site, const Stage1Options& o,
                                         double time_offset) {
  if (!(o.arw > 0.0) || !(o.vrw > 0.0))
    throw std::invalid_argument(
        "stage 1 needs the gyro and accelerometer white-noise densities (arw, vrw) for its weights "
        "and sigmas: give a sensor profile in the session or set them");
  for (const auto& d : dwells)
    if (d.t_end - d.t_start < o.min_dwell)
      throw std::invalid_argument("dwell " + std::to_string(d.index) + " (" + d.label + ") lasts " +
                                  std::to_string(d.t_end - d.t_start) + " s, shorter than the " +
                                  std::to_string(o.min_dwell) + " s stage 1 needs");
  const Earth& earth = Earth::wgs84();
  const double R_N = earth.radius_meridian(site.lat_rad) + site.h_m;
  const InsErrorModel model = InsErrorModel::at(site, o.model, earth);
  const Eigen::Vector3d f_n = -earth.gravity_n(site.lat_rad, site.h_m);
  const std::vector<int> rows = rows_of(o.channels);
  InsF Phi;
  InsB Gamma;
  double h_cached = -1.0;

  std::map<int, DwellAccumulator> acc;
  DwellNavOptions nav_opt;
  nav_opt.output_interval = 0.0;
  nav_opt.time_offset = time_offset;
  nav_opt.strapdown = o.strapdown;
  DwellNavigation nav(dwells, site, nav_opt);
  nav.run(source, [&](const DwellNavRow& r) {
    DwellAccumulator& a = acc[r.dwell];
    if (!a.started) {
      a.started = true;
      a.dwell = *r.info;
      a.prev = r.error;
      return;
    }
    const double h = r.error.t - a.prev.t;
    if (h <= 0.0) return;
    if (std::abs(h - h_cached) > 1e-9 * h) {
      model.discretize(h, Phi, Gamma);
      h_cached = h;
    }
    const InsState x0 = observed_state(a.prev), x1 = observed_state(r.error);
    InsState delta = x1 - Phi * x0;
    InsB Gamma_k = Gamma;
    if (o.model == ErrorModelKind::Coupled) {
      // Second-order attitude terms, exact because phi is observed: the specific force is
      // rotated by R(-phi) (not I - [phi x]), and the inputs act in the computed frame,
      // (I - [phi x]) df_n and -(I - [phi x]) dw_n. The fit stays linear in u.
      const Eigen::Vector3d phi = 0.5 * (a.prev.phi_n + r.error.phi_n);
      delta.segment<3>(kInsNav.velocity.index) -=
          h * ((dcm_from_rotvec(-phi) - Eigen::Matrix3d::Identity()) * f_n - f_n.cross(phi));
      Gamma_k.block<3, 3>(kInsNav.velocity.index, ins_input::kAccel.index) -= h * skew(phi);
      Gamma_k.block<3, 3>(kInsNav.attitude.index, ins_input::kGyro.index) += h * skew(phi);
    }
    for (int row : rows) {
      RowSums& s = a.rows[row];
      const Vector6d g = Gamma_k.row(row).transpose();
      s.dd += delta(row) * delta(row);
      s.gd += g * delta(row);
      s.gg += g * g.transpose();
    }
    ++a.steps;
    const double target = o.point_time > 0.0 ? o.point_time : a.dwell.t_end - a.dwell.t_start;
    if (std::abs(r.error.t - target) <= a.point_distance) {
      a.point_distance = std::abs(r.error.t - target);
      a.at_point = r.error;
    }
    a.prev = r.error;
  });

  const double g = earth.gravity_n(site.lat_rad, site.h_m).norm();
  const double R_E = earth.radius_transverse(site.lat_rad) + site.h_m;
  const std::array<bool, 6> sel = o.channels.inputs();
  std::vector<EquivalentInputs> out;
  for (auto& [index, a] : acc) {
    EquivalentInputs e;
    e.dwell = a.dwell;
    e.duration = a.prev.t;
    e.samples = a.steps;
    e.estimated = sel;
    const double T = e.duration;
    if (o.method == Stage1Method::Point) {
      // The paper's eq. 5 (uncoupled Schuler solutions at one time t).
      const NavError& x = a.at_point;
      const double t = x.t;
      auto channel = [&](double R, double& cot_half, double& ws) {
        ws = std::sqrt(g / R);
        cot_half = 0.5 * ws * std::sin(ws * t) / (1.0 - std::cos(ws * t));
      };
      double k_n, ws_n, k_e, ws_e;
      channel(R_N, k_n, ws_n);
      channel(R_E, k_e, ws_e);
      const double dtheta = x.phi_n.y(), dgamma = x.phi_n.x();
      // north: dfn = -g/2 dtheta + k dVn;  dwe(paper) = ws^2/(2g) dVn + k dtheta
      e.u(kDfN) = -0.5 * g * dtheta + k_n * x.dv_n.x();
      e.u(kDwE) = -(0.5 * ws_n * ws_n / g * x.dv_n.x() + k_n * dtheta);
      // east: dfe = g/2 dgamma + k dVe;  dwn(paper) = -ws^2/(2g) dVe + k dgamma
      e.u(kDfE) = 0.5 * g * dgamma + k_e * x.dv_n.y();
      e.u(kDwN) = -(-0.5 * ws_e * ws_e / g * x.dv_n.y() + k_e * dgamma);
      e.u(kDfD) = x.dv_n.z() / t;
      e.u(kDwD) = -x.phi_n.z() / t;
      // Sigma: the errors at t carry random walks of variance VRW^2 t and ARW^2 t.
      const double vv = o.vrw * o.vrw * t, va = o.arw * o.arw * t;
      e.cov(kDfN, kDfN) = 0.25 * g * g * va + k_n * k_n * vv;
      e.cov(kDwE, kDwE) = std::pow(0.5 * ws_n * ws_n / g, 2) * vv + k_n * k_n * va;
      e.cov(kDfN, kDwE) = e.cov(kDwE, kDfN) =
          -(-0.5 * g * k_n * va + k_n * 0.5 * ws_n * ws_n / g * vv);
      e.cov(kDfE, kDfE) = 0.25 * g * g * va + k_e * k_e * vv;
      e.cov(kDwN, kDwN) = std::pow(0.5 * ws_e * ws_e / g, 2) * vv + k_e * k_e * va;
      e.cov(kDfE, kDwN) = e.cov(kDwN, kDfE) =
          -(0.5 * g * k_e * va - k_e * 0.5 * ws_e * ws_e / g * vv);
      e.cov(kDfD, kDfD) = o.vrw * o.vrw / t;
      e.cov(kDwD, kDwD) = o.arw * o.arw / t;
    } else {
      Matrix6d N = Matrix6d::Zero();
      Vector6d b = Vector6d::Zero();
      const double h = T / static_cast<double>(std::max<std::size_t>(a.steps, 1));
      auto weight = [&](int row) {
        return 1.0 / ((is_velocity_row(row) ? o.vrw * o.vrw : o.arw * o.arw) * h);
      };
      for (auto& [row, s] : a.rows) {
        N += weight(row) * s.gg;
        b += weight(row) * s.gd;
      }
      std::vector<int> idx;
      for (int i = 0; i < 6; ++i)
        if (sel[i]) idx.push_back(i);
      const int m = static_cast<int>(idx.size());
      Eigen::MatrixXd Ns(m, m);
      Eigen::VectorXd bs(m);
      for (int i = 0; i < m; ++i) {
        bs(i) = b(idx[i]);
        for (int j = 0; j < m; ++j) Ns(i, j) = N(idx[i], idx[j]);
      }
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(Ns);
      const Eigen::VectorXd us = ldlt.solve(bs);
      const Eigen::MatrixXd cs = ldlt.solve(Eigen::MatrixXd::Identity(m, m));
      for (int i = 0; i < m; ++i) {
        e.u(idx[i]) = us(i);
        for (int j = 0; j < m; ++j) e.cov(idx[i], idx[j]) = cs(i, j);
      }
      double chi2 = 0.0, ssv = 0.0, ssa = 0.0;
      std::size_t nv = 0, na = 0;
      for (auto& [row, s] : a.rows) {
        const double rss = std::max(0.0, s.dd - 2.0 * e.u.dot(s.gd) + e.u.dot(s.gg * e.u));
        chi2 += weight(row) * rss;
        if (is_velocity_row(row)) {
          ssv += rss;
          nv += a.steps;
        } else {
          ssa += rss;
          na += a.steps;
        }
      }
      e.rms_velocity = nv ? std::sqrt(ssv / static_cast<double>(nv)) : 0.0;
      e.rms_attitude = na ? std::sqrt(ssa / static_cast<double>(na)) : 0.0;
      const double dof = static_cast<double>(nv + na) - m;
      e.chi2_per_dof = dof > 0 ? chi2 / dof : 0.0;
    }
    out.push_back(e);
  }
  return out;
}

Stage2Map equivalent_input_map(const Eigen::Matrix3d& C, const Site& site) {
  using namespace base_coeffs;
  const Earth& earth = Earth::wgs84();
  const Eigen::Vector3d f_b = -(C.transpose() * earth.gravity_n(site.lat_rad, site.h_m));
  const Eigen::Vector3d w_b = C.transpose() * earth.omega_ie_n(site.lat_rad);
  Stage2Map H = Stage2Map::Zero();
  auto triad = [&](int row, const Block& bias, const Block& scale, const Block& mis,
                   const Eigen::Vector3d& x) {
    H.block<3, 3>(row, bias.index) = C;
    int m = mis.index;
    for (int i = 0; i < 3; ++i) {
      H.block<3, 1>(row, scale.index + i) = C.col(i) * x(i);
      for (int j = 0; j < 3; ++j)
        if (i != j) H.block<3, 1>(row, m++) = C.col(i) * x(j);
    }
  };
  triad(ins_input::kAccel.index, kAccelBias, kAccelScale, kAccelMis, f_b);
  triad(ins_input::kGyro.index, kGyroBias, kGyroScale, kGyroMis, w_b);
  return H;
}

Eigen::VectorXd base_vector(const ImuErrorModel& model) {
  return model.vector().head(base_coeffs::kSize);
}

Stage2Result solve_stage2(const std::vector<EquivalentInputs>& inputs, const Site& site,
                          const Stage2Options& o) {
  const int n = base_coeffs::kSize;
  const Earth& earth = Earth::wgs84();
  const Eigen::Vector3d f_n = -earth.gravity_n(site.lat_rad, site.h_m);
  const Eigen::Vector3d w_ie = earth.omega_ie_n(site.lat_rad);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  for (const auto& in : inputs) {
    const Stage2Map H = equivalent_input_map(in.dwell.C_b_n_known, site);
    // A table attitude error eps (truth relative to the plan) aliases into the inputs as
    // df_n += f_n x eps, dw_n += omega_ie_n x eps.
    Eigen::Matrix<double, 6, 3> S;
    S.topRows<3>() = skew(f_n);
    S.bottomRows<3>() = skew(w_ie);
    const Eigen::Vector3d u_i = in.dwell.C_b_n_known * o.inner_axis_b.normalized();
    const Eigen::Matrix3d Sigma_eps =
        o.table_sigma * o.table_sigma *
        (o.outer_axis_n.normalized() * o.outer_axis_n.normalized().transpose() +
         u_i * u_i.transpose());
    const Matrix6d R = in.cov + S * Sigma_eps * S.transpose();
    std::vector<int> idx;
    for (int i = 0; i < 6; ++i)
      if (in.estimated[i]) idx.push_back(i);
    const int m = static_cast<int>(idx.size());
    Eigen::MatrixXd Hs(m, n), Rs(m, m);
    Eigen::VectorXd us(m);
    for (int i = 0; i < m; ++i) {
      Hs.row(i) = H.row(idx[i]);
      us(i) = in.u(idx[i]);
      for (int j = 0; j < m; ++j) Rs(i, j) = R(idx[i], idx[j]);
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(Rs);
    if (llt.info() != Eigen::Success)
      throw std::runtime_error("stage 2: the covariance of dwell " +
                               std::to_string(in.dwell.index) + " is not positive definite");
    J += Hs.transpose() * llt.solve(Hs);
    b += Hs.transpose() * llt.solve(us);
  }
  // Jacobi scaling, then the eigen-decomposition names the unobservable directions.
  Eigen::VectorXd d(n);
  for (int i = 0; i < n; ++i) d(i) = J(i, i) > 0.0 ? 1.0 / std::sqrt(J(i, i)) : 1.0;
  const Eigen::MatrixXd Js = d.asDiagonal() * J * d.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Js);
  const double lmax = es.eigenvalues().maxCoeff();
  Eigen::MatrixXd pinv = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd null_weight = Eigen::VectorXd::Zero(n);
  Stage2Result r;
  const auto& cat = coefficient_catalog();
  for (int k = 0; k < n; ++k) {
    const double l = es.eigenvalues()(k);
    const Eigen::VectorXd v = es.eigenvectors().col(k);
    if (l > o.null_tolerance * lmax) {
      pinv += v * v.transpose() / l;
      ++r.rank;
      continue;
    }
    null_weight += v.cwiseAbs2();
    Eigen::VectorXd dir = (d.asDiagonal() * v).normalized();
    int lead = 0;
    dir.cwiseAbs().maxCoeff(&lead);
    if (dir(lead) < 0.0) dir = -dir;
    std::string text;
    for (int i = 0; i < n; ++i)
      if (std::abs(dir(i)) > 0.05) {
        char buf[96];
        std::snprintf(buf, sizeof buf, "%s%+.3f %s", text.empty() ? "" : " ", dir(i),
                      cat[i].name.c_str());
        text += buf;
      }
    r.unobservable_directions.push_back(text);
    r.null_vectors.push_back(dir);
  }
  r.theta = d.asDiagonal() * pinv * d.asDiagonal() * b;
  r.cov = d.asDiagonal() * pinv * d.asDiagonal();
  r.observable.assign(n, true);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < n; ++i)
    if (null_weight(i) > 1e-6) {
      r.observable[i] = false;
      r.theta(i) = nan;
      r.cov.row(i).setConstant(nan);
      r.cov.col(i).setConstant(nan);
    }
  return r;
}

PaperClosedForms paper_closed_forms(const std::vector<EquivalentInputs>& in, const Site& site) {
  if (in.size() != 8)
    throw std::invalid_argument("the paper's closed forms need the 8 orientations");
  const Earth& earth = Earth::wgs84();
  const double Om = earth.rate(), phi = site.lat_rad;
  const double g = earth.gravity_n(site.lat_rad, site.h_m).norm();
  const double s2 = std::sqrt(2.0);
  // Paper variables, 1-based as in the paper: dwn = -(gyro error North), dfn = accel error North.
  double dwn[9], dfn[9];
  for (int i = 1; i <= 8; ++i) {
    dwn[i] = -in[i - 1].u(ins_input::kGyro.index + 0);
    dfn[i] = in[i - 1].u(ins_input::kAccel.index + 0);
  }
  const double Os = Om * std::sin(phi), Oc = Om * std::cos(phi);
  PaperClosedForms p;
  p.w0x = (dwn[3] + dwn[7] - dwn[1] - dwn[5]) / 4.0;
  p.dkgx = -(dwn[1] + dwn[3] + dwn[5] + dwn[7]) / (4.0 * Oc);
  p.nu_xy = (dwn[3] + dwn[5] - dwn[1] - dwn[7]) / (2.0 * s2 * Os);
  p.nu_xz = (dwn[1] + dwn[3] - dwn[5] - dwn[7]) / (2.0 * s2 * Os);
  p.w0z = (dwn[2] + dwn[8] - dwn[4] - dwn[6]) / 4.0;
  p.dkgz = -(dwn[2] + dwn[4] + dwn[6] + dwn[8]) / (4.0 * Oc);
  p.nu_zx = (dwn[2] - dwn[8] + dwn[4] - dwn[6]) / (2.0 * s2 * Os);
  p.nu_zy = (dwn[2] - dwn[8] - dwn[4] + dwn[6]) / (2.0 * s2 * Os);
  p.f0x = (dfn[1] - dfn[3] + dfn[5] - dfn[7]) / 4.0;
  p.mu_xy = s2 / (4.0 * g) * (dfn[1] - dfn[3] - dfn[5] + dfn[7]);
  p.mu_xz = s2 / (4.0 * g) * (-dfn[1] - dfn[3] + dfn[5] + dfn[7]);
  p.f0z = (-dfn[2] + dfn[4] + dfn[6] - dfn[8]) / 4.0;
  p.mu_zx = s2 / (4.0 * g) * (-dfn[2] - dfn[4] + dfn[6] + dfn[8]);
  p.mu_zy = s2 / (4.0 * g) * (-dfn[2] + dfn[4] - dfn[6] + dfn[8]);
  return p;
}

}  // namespace sinscal

namespace sinscal {

namespace {
const char* kInputName[6] = {"df_n", "df_e", "df_d", "dw_n", "dw_e", "dw_d"};
}  // namespace

ClosedFormReport run_closed_form(const Session& session, const Stage1Options& stage1,
                                 double table_sigma) {
  ClosedFormReport r;
  r.stage1_options = stage1;
  const PlanTimeline timeline = PlanTimeline::of(session.plan, session.site);
  LogReader reader(session.log);
  r.stage1 = run_stage1(reader, timeline.dwells, session.site, stage1, session.time_offset);
  r.stage2_options.table_sigma = table_sigma;
  r.stage2_options.outer_axis_n = session.plan.table.outer_axis_n;
  r.stage2_options.inner_axis_b = Table(session.plan.table).inner_axis_b();
  r.stage2 = solve_stage2(r.stage1, session.site, r.stage2_options);

  const auto& cat = coefficient_catalog();
  for (int i = 0; i < base_coeffs::kSize; ++i) {
    ResultCoefficient c;
    c.unit = cat[i].unit;
    c.observable = r.stage2.observable[i];
    if (c.observable) {
      c.value = r.stage2.theta(i) / cat[i].si_per_unit;
      c.sigma = std::sqrt(r.stage2.cov(i, i)) / cat[i].si_per_unit;
    }
    r.coefficients[cat[i].name] = c;
  }

  // The paper's literal closed forms, when the plan is its 8-orientation table.
  const auto& o = session.plan.orientations;
  static const double kPaper[8][3] = {{0, 0, 45},  {90, 45, 0},   {180, 0, 315}, {270, 315, 0},
                                      {0, 0, 225}, {90, 45, 180}, {180, 0, 135}, {90, 225, 0}};
  if (session.plan.type == Plan::Type::Orientations && o.size() == 8 && r.stage1.size() == 8) {
    bool same = true;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Matrix3d C = C_b_n_from_euler(
          AngleConvention::Paper,
          {kPaper[i][0] * units::deg, kPaper[i][1] * units::deg, kPaper[i][2] * units::deg});
      same = same && (C - r.stage1[i].dwell.C_b_n_known).cwiseAbs().maxCoeff() < 1e-9;
    }
    if (same) {
      r.has_paper_forms = true;
      r.paper = paper_closed_forms(r.stage1, session.site);
    }
  }

  nlohmann::ordered_json& d = r.details;
  d["method"] = {{"name", "closed-form"},
                 {"stage1", stage1.method == Stage1Method::Fit ? "fit" : "point"},
                 {"model", stage1.model == ErrorModelKind::Coupled ? "coupled" : "uncoupled"},
                 {"channels",
                  {{"north", stage1.channels.north},
                   {"east", stage1.channels.east},
                   {"vertical", stage1.channels.vertical},
                   {"heading", stage1.channels.heading}}},
                 {"arw_deg_per_sqrt_h", stage1.arw / units::deg_per_sqrt_h},
                 {"vrw_ug_per_sqrt_hz", stage1.vrw / units::ug_per_sqrt_hz},
                 {"table_sigma_arcsec", table_sigma / units::arcsec}};
  nlohmann::ordered_json dwells = nlohmann::ordered_json::array();
  for (const auto& e : r.stage1) {
    nlohmann::ordered_json x = {
        {"dwell", e.dwell.index}, {"label", e.dwell.label}, {"duration_s", e.duration}};
    nlohmann::ordered_json inputs = nlohmann::ordered_json::object();
    for (int i = 0; i < 6; ++i) {
      if (!e.estimated[i]) continue;
      const bool gyro = i >= 3;
      const double f = gyro ? units::deg_per_h : units::ug;
      inputs[kInputName[i]] = {{"value", e.u(i) / f},
                               {"sigma", std::sqrt(e.cov(i, i)) / f},
                               {"unit", gyro ? "deg/h" : "ug"}};
    }
    x["equivalent_inputs"] = inputs;
    if (stage1.method == Stage1Method::Fit)
      x["residuals"] = {{"rms_velocity_m_per_s", e.rms_velocity},
                        {"rms_attitude_arcsec", e.rms_attitude / units::arcsec},
                        {"chi2_per_dof", e.chi2_per_dof}};
    dwells.push_back(x);
  }
  d["stage1"] = dwells;
  d["identifiability"] = {{"rank", r.stage2.rank},
                          {"parameters", base_coeffs::kSize},
                          {"unobservable_directions", r.stage2.unobservable_directions}};
  return r;
}

}  // namespace sinscal
