#include "filter/strapdown/ins_error_model.hpp"

#include <cmath>

#include "models/attitude.hpp"

namespace sinscal {

InsSiteTerms InsSiteTerms::at(const Site& site, const Earth& earth) {
  InsSiteTerms t;
  t.lat_rad = site.lat_rad;
  t.R_N = earth.radius_meridian(site.lat_rad) + site.h_m;
  t.R_E = earth.radius_transverse(site.lat_rad) + site.h_m;
  const Eigen::Vector3d g_n = earth.gravity_n(site.lat_rad, site.h_m);
  t.g = g_n.norm();
  t.f_n_static = -g_n;
  t.rate = earth.rate();
  t.omega_ie_n = earth.omega_ie_n(site.lat_rad);
  return t;
}

void ins_error_matrix(const InsSiteTerms& s, const Eigen::Vector3d& f_n, ErrorModelKind kind,
                      const NavBlocks& nav, Eigen::Ref<Eigen::MatrixXd> F) {
  const Block &a = nav.attitude, &v = nav.velocity, &p = nav.position;
  // F(row block r component i, column block c component j) = value, when both exist.
  auto set = [&](const Block& r, int i, const Block& c, int j, double value) {
    if (i < r.size && j < c.size) F(r.index + i, c.index + j) = value;
  };
  for (int i = 0; i < 3; ++i) set(p, i, v, i, 1.0);
  set(a, 0, v, 1, 1.0 / s.R_E);
  set(a, 1, v, 0, -1.0 / s.R_N);
  if (kind == ErrorModelKind::Uncoupled) {
    // The paper's channels see gravity only: dv_n' = g phi_e, dv_e' = -g phi_n.
    set(v, 0, a, 1, s.g);
    set(v, 1, a, 0, -s.g);
    return;
  }
  const Eigen::Matrix3d W = -skew(s.omega_ie_n), Fx = skew(f_n), C = -2.0 * skew(s.omega_ie_n);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      set(a, i, a, j, W(i, j));
      set(v, i, a, j, Fx(i, j));
      set(v, i, v, j, C(i, j));
    }
  // d_omega_en from dv, d_omega_ie from the latitude error dp_n / R_N.
  set(a, 2, v, 1, -std::tan(s.lat_rad) / s.R_E);
  set(a, 0, p, 0, -s.rate * std::sin(s.lat_rad) / s.R_N);
  set(a, 2, p, 0, -s.rate * std::cos(s.lat_rad) / s.R_N);
  set(v, 2, p, 2, 2.0 * s.g / s.R_E);
}

InsF ins_error_matrix(const InsSiteTerms& s, const Eigen::Vector3d& f_n, ErrorModelKind kind) {
  InsF F = InsF::Zero();
  ins_error_matrix(s, f_n, kind, kInsNav, F);
  return F;
}

InsErrorModel InsErrorModel::at(const Site& site, ErrorModelKind kind, const Earth& earth) {
  const InsSiteTerms s = InsSiteTerms::at(site, earth);
  InsErrorModel m;
  m.F = ins_error_matrix(s, s.f_n_static, kind);
  m.B.setZero();
  m.B.block<3, 3>(kInsNav.velocity.index, ins_input::kAccel.index) = Eigen::Matrix3d::Identity();
  m.B.block<3, 3>(kInsNav.attitude.index, ins_input::kGyro.index) = -Eigen::Matrix3d::Identity();
  return m;
}

void InsErrorModel::discretize(double h, InsF& Phi, InsB& Gamma) const {
  // Series: |F h| ~ 1e-5 per sample, so terms beyond the fourth are below 1e-20.
  const InsF Fh = F * h;
  const InsF I = InsF::Identity();
  const InsF Fh2 = Fh * Fh, Fh3 = Fh2 * Fh;
  Phi = I + Fh + Fh2 / 2.0 + Fh3 / 6.0 + Fh3 * Fh / 24.0;
  Gamma = (I + Fh / 2.0 + Fh2 / 6.0 + Fh3 / 24.0) * B * h;
}

}  // namespace sinscal
