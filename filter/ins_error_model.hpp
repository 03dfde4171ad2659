// Linear error dynamics of an INS at rest (velocity zero, position fixed), phi-angle form in NED,
// as used by the closed-form method. State layout: named blocks, size derived.
//
//   phi'  = -[omega_ie_n x] phi + d_omega_in(dv, dlat) - dw_n        (coupled)
//   dv'   = [f_n x] phi + df_n - 2 [omega_ie_n x] dv + (2 g / R) dp_d e_d
//   dlat' = dv_n / R_N,   dp_d' = dv_d
// with f_n = -g_n, d_omega_in = (dv_e/R_E, -dv_n/R_N, -tan(lat) dv_e/R_E) + Omega (-sin lat, 0,
// -cos lat) dlat. Inputs: df_n (accelerometer error in NED) and dw_n (gyro error in NED, natural
// sign). The paper's uncoupled model keeps only dv_n' = g phi_e + df_n, phi_e' = -dv_n/R_N - dw_e,
// dv_e' = -g phi_n + df_e, phi_n' = dv_e/R_E - dw_n, dv_d' = df_d, phi_d' = -dw_d.
#pragma once

#include <Eigen/Core>

#include "models/earth.hpp"

namespace sinscal {

/// A block of a state or input vector.
struct Block {
  int index;
  int size;
};

namespace ins_state {
constexpr Block kAttitude{0, 3};  // phi_n, rad
constexpr Block kVelocity{3, 3};  // dv_n, m/s
constexpr Block kLatitude{6, 1};  // dlat, rad
constexpr Block kDown{7, 1};      // dp_d, m
constexpr int kSize = kDown.index + kDown.size;
static_assert(kSize == 8, "INS error state layout");
}  // namespace ins_state

namespace ins_input {
constexpr Block kAccel{0, 3};  // df_n, m/s^2
constexpr Block kGyro{3, 3};   // dw_n, rad/s
constexpr int kSize = kGyro.index + kGyro.size;
}  // namespace ins_input

using InsState = Eigen::Matrix<double, ins_state::kSize, 1>;
using InsF = Eigen::Matrix<double, ins_state::kSize, ins_state::kSize>;
using InsB = Eigen::Matrix<double, ins_state::kSize, ins_input::kSize>;

enum class ErrorModelKind { Uncoupled, Coupled };

struct InsErrorModel {
  InsF F;
  InsB B;
  /// Continuous model at a site.
  static InsErrorModel at(const Site& site, ErrorModelKind kind,
                          const Earth& earth = Earth::wgs84());
  /// Discrete transition over h seconds: x(t+h) = Phi x(t) + Gamma u (u constant).
  void discretize(double h, InsF& Phi, InsB& Gamma) const;
};

}  // namespace sinscal
