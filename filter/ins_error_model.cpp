#include "filter/ins_error_model.hpp"

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

InsF ins_error_matrix(const InsSiteTerms& s, const Eigen::Vector3d& f_n, ErrorModelKind kind) {
  using namespace ins_state;
  InsF F = InsF::Zero();
  const int a = kAttitude.index, v = kVelocity.index, p = kPosition.index;
  for (int i = 0; i < 3; ++i) F(p + i, v + i) = 1.0;
  F(a + 0, v + 1) = 1.0 / s.R_E;
  F(a + 1, v + 0) = -1.0 / s.R_N;
  if (kind == ErrorModelKind::Uncoupled) {
    (void)f_n;  // the paper's channels see gravity only: dv_n' = g phi_e, dv_e' = -g phi_n
    F(v + 0, a + 1) = s.g;
    F(v + 1, a + 0) = -s.g;
    return F;
  }
  F.block<3, 3>(a, a) = -skew(s.omega_ie_n);
  // d_omega_en from dv, d_omega_ie from the latitude error dp_n / R_N
  F(a + 2, v + 1) = -std::tan(s.lat_rad) / s.R_E;
  F(a + 0, p + 0) = -s.rate * std::sin(s.lat_rad) / s.R_N;
  F(a + 2, p + 0) = -s.rate * std::cos(s.lat_rad) / s.R_N;
  F.block<3, 3>(v, a) = skew(f_n);
  F.block<3, 3>(v, v) = -2.0 * skew(s.omega_ie_n);
  F(v + 2, p + 2) = 2.0 * s.g / s.R_E;
  return F;
}

InsErrorModel InsErrorModel::at(const Site& site, ErrorModelKind kind, const Earth& earth) {
  const InsSiteTerms s = InsSiteTerms::at(site, earth);
  InsErrorModel m;
  m.F = ins_error_matrix(s, s.f_n_static, kind);
  m.B.setZero();
  m.B.block<3, 3>(ins_state::kVelocity.index, ins_input::kAccel.index) =
      Eigen::Matrix3d::Identity();
  m.B.block<3, 3>(ins_state::kAttitude.index, ins_input::kGyro.index) =
      -Eigen::Matrix3d::Identity();
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
