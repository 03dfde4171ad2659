// Linear error dynamics of an INS at rest on the Earth (velocity zero, position fixed), phi-angle
// form in NED, shared by the closed-form method (static dwells) and the Kalman filter (any
// specific force). State layout: named blocks, size derived.
//
//   phi'  = -[omega_ie_n x] phi + d_omega_in(dv, dp) - dw_n                    (coupled)
//   dv'   = [f_n x] phi + df_n - 2 [omega_ie_n x] dv + (2 g / R_E) dp_d e_d
//   dp'   = dv
// with d_omega_in = (dv_e/R_E, -dv_n/R_N, -tan(lat) dv_e/R_E) + Omega (-sin lat, 0, -cos lat)
// dp_n/R_N. Inputs: df_n (accelerometer error in NED) and dw_n (gyro error in NED, natural sign).
// The paper's uncoupled model keeps only dv_n' = g phi_e + df_n, phi_e' = -dv_n/R_N - dw_e, dv_e' =
// -g phi_n + df_e, phi_n' = dv_e/R_E - dw_n, dv_d' = df_d, phi_d' = -dw_d, dp' = dv.
#pragma once

#include <Eigen/Core>

#include "filter/kalman/state_layout.hpp"
#include "models/earth.hpp"

namespace sinscal {

/// The full 9-state INS error of the closed form (state_layout.hpp's default navigation blocks).
constexpr NavBlocks kInsNav{};
static_assert(kInsNav.size() == 9, "INS error state layout");

namespace ins_input {
constexpr Block kAccel{0, 3};  // df_n, m/s^2
constexpr Block kGyro{3, 3};   // dw_n, rad/s
constexpr int kSize = kGyro.index + kGyro.size;
}  // namespace ins_input

using InsState = Eigen::Matrix<double, 9, 1>;
using InsF = Eigen::Matrix<double, 9, 9>;
using InsB = Eigen::Matrix<double, 9, ins_input::kSize>;

enum class ErrorModelKind { Uncoupled, Coupled };

/// The Earth terms of the error dynamics at a fixed site, computed once.
struct InsSiteTerms {
  double lat_rad = 0.0;
  double R_N = 0.0;   // m, meridian radius plus height
  double R_E = 0.0;   // m, transverse radius plus height
  double g = 0.0;     // m/s^2, normal gravity magnitude
  double rate = 0.0;  // rad/s, Earth rate
  Eigen::Vector3d omega_ie_n = Eigen::Vector3d::Zero();
  Eigen::Vector3d f_n_static = Eigen::Vector3d::Zero();  // specific force at rest, -g_n
  static InsSiteTerms at(const Site& site, const Earth& earth = Earth::wgs84());
};

/// Continuous error-dynamics matrix for the specific force f_n (NED, m/s^2), written into F at the
/// indices of the navigation blocks `nav` (entries of absent components, e.g. the vertical
/// velocity when it is off, are skipped). F must be zero where the matrix has no entry.
void ins_error_matrix(const InsSiteTerms& site, const Eigen::Vector3d& f_n, ErrorModelKind kind,
                      const NavBlocks& nav, Eigen::Ref<Eigen::MatrixXd> F);
/// The same for the full 9-state layout.
InsF ins_error_matrix(const InsSiteTerms& site, const Eigen::Vector3d& f_n, ErrorModelKind kind);

struct InsErrorModel {
  InsF F;
  InsB B;
  /// Continuous model at rest at a site.
  static InsErrorModel at(const Site& site, ErrorModelKind kind,
                          const Earth& earth = Earth::wgs84());
  /// Discrete transition over h seconds: x(t+h) = Phi x(t) + Gamma u (u constant).
  void discretize(double h, InsF& Phi, InsB& Gamma) const;
};

}  // namespace sinscal
