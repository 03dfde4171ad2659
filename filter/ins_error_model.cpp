#include "filter/ins_error_model.hpp"

#include <cmath>

#include "models/attitude.hpp"

namespace sinscal {

InsErrorModel InsErrorModel::at(const Site& site, ErrorModelKind kind, const Earth& earth) {
  using namespace ins_state;
  InsErrorModel m;
  m.F.setZero();
  m.B.setZero();
  const double lat = site.lat_rad;
  const double RN = earth.radius_meridian(lat) + site.h_m;
  const double RE = earth.radius_transverse(lat) + site.h_m;
  const Eigen::Vector3d g_n = earth.gravity_n(lat, site.h_m);
  const Eigen::Vector3d f_n = -g_n;
  const double g = g_n.norm();
  const int a = kAttitude.index, v = kVelocity.index;
  m.B.block<3, 3>(v, ins_input::kAccel.index) = Eigen::Matrix3d::Identity();
  m.B.block<3, 3>(a, ins_input::kGyro.index) = -Eigen::Matrix3d::Identity();
  m.F(kLatitude.index, v + 0) = 1.0 / RN;
  m.F(kDown.index, v + 2) = 1.0;
  if (kind == ErrorModelKind::Uncoupled) {
    m.F(v + 0, a + 1) = g;
    m.F(v + 1, a + 0) = -g;
    m.F(a + 1, v + 0) = -1.0 / RN;
    m.F(a + 0, v + 1) = 1.0 / RE;
    return m;
  }
  const Eigen::Vector3d w_ie = earth.omega_ie_n(lat);
  m.F.block<3, 3>(a, a) = -skew(w_ie);
  // d_omega_en from dv, d_omega_ie from dlat
  m.F(a + 0, v + 1) = 1.0 / RE;
  m.F(a + 1, v + 0) = -1.0 / RN;
  m.F(a + 2, v + 1) = -std::tan(lat) / RE;
  m.F(a + 0, kLatitude.index) = -earth.rate() * std::sin(lat);
  m.F(a + 2, kLatitude.index) = -earth.rate() * std::cos(lat);
  m.F.block<3, 3>(v, a) = skew(f_n);
  m.F.block<3, 3>(v, v) = -2.0 * skew(w_ie);
  m.F(v + 2, kDown.index) = 2.0 * g / RE;
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
