#include <catch2/catch.hpp>
#include <random>

#include "models/attitude.hpp"
#include "models/units.hpp"

using namespace sinscal;
using Eigen::Matrix3d;
using Eigen::Vector3d;

TEST_CASE("Rotation vector, quaternion and DCM round trips", "[attitude]") {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (double scale : {1e-12, 1e-6, 1e-3, 9.9e-3, 1.01e-2, 0.5, 3.0}) {
    for (int k = 0; k < 20; ++k) {
      Vector3d r(n(rng), n(rng), n(rng));
      r = r.normalized() * scale;
      const Matrix3d C = dcm_from_rotvec(r);
      CHECK((C * C.transpose() - Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-14);
      CHECK((rotvec_from_dcm(C) - r).norm() < 1e-15 + 1e-14 * scale);
      // Against Rodrigues with std::sin / std::cos.
      CHECK((C - rotation(r.normalized(), scale)).cwiseAbs().maxCoeff() < 1e-14);
    }
  }
}

TEST_CASE("Euler angles round trip in both conventions", "[attitude]") {
  for (auto conv : {AngleConvention::NedFrd, AngleConvention::Paper}) {
    for (double h : {10.0, 100.0, 200.0, 350.0})
      for (double p : {-80.0, -30.0, 0.0, 45.0})
        for (double r : {-170.0, -20.0, 0.0, 60.0}) {
          const EulerAngles e{h * units::deg, p * units::deg, r * units::deg};
          const EulerAngles back = euler_from_C_b_n(conv, C_b_n_from_euler(conv, e));
          CHECK(back.heading == Approx(e.heading).margin(1e-12));
          CHECK(back.pitch == Approx(e.pitch).margin(1e-12));
          CHECK(back.roll == Approx(e.roll).margin(1e-12));
        }
  }
}

TEST_CASE("Named conventions put the body axes where their definitions say", "[attitude]") {
  const double d = units::deg;
  // ned-frd: heading 90 points x East; pitch 30 raises the nose (x gets an Up = -Down part).
  Matrix3d C = C_b_n_from_euler(AngleConvention::NedFrd, {90 * d, 0, 0});
  CHECK((C.col(0) - Vector3d(0, 1, 0)).norm() < 1e-15);
  C = C_b_n_from_euler(AngleConvention::NedFrd, {0, 30 * d, 0});
  CHECK(C(2, 0) == Approx(-0.5));
  // paper: zero angles = x North, y Up, z East.
  C = C_b_n_from_euler(AngleConvention::Paper, {});
  CHECK((C.col(0) - Vector3d(1, 0, 0)).norm() < 1e-15);
  CHECK((C.col(1) - Vector3d(0, 0, -1)).norm() < 1e-15);
  CHECK((C.col(2) - Vector3d(0, 1, 0)).norm() < 1e-15);
  // paper: heading clockwise (x to East), pitch nose up, roll right wing (z) down.
  CHECK(C_b_n_from_euler(AngleConvention::Paper, {90 * d, 0, 0}).col(0).y() == Approx(1.0));
  CHECK(C_b_n_from_euler(AngleConvention::Paper, {0, 30 * d, 0}).col(0).z() == Approx(-0.5));
  CHECK(C_b_n_from_euler(AngleConvention::Paper, {0, 0, 30 * d}).col(2).z() == Approx(0.5));
}

TEST_CASE("The paper's 8 orientations: one axis North-South, two at 45 deg in East-Up",
          "[attitude]") {
  const double table[8][3] = {{0, 0, 45},  {90, 45, 0},   {180, 0, 315}, {270, 315, 0},
                              {0, 0, 225}, {90, 45, 180}, {180, 0, 135}, {90, 225, 0}};
  for (int i = 0; i < 8; ++i) {
    const EulerAngles e{table[i][0] * units::deg, table[i][1] * units::deg,
                        table[i][2] * units::deg};
    const Matrix3d C = C_b_n_from_euler(AngleConvention::Paper, e);
    const int ns_axis = i % 2 == 0 ? 0 : 2;  // x in 1,3,5,7; z in 2,4,6,8
    CAPTURE(i + 1);
    CHECK(std::abs(std::abs(C(0, ns_axis)) - 1.0) < 1e-15);
    for (int a = 0; a < 3; ++a) {
      if (a == ns_axis) continue;
      CHECK(std::abs(C(0, a)) < 1e-15);
      CHECK(std::abs(C(1, a)) == Approx(std::sqrt(0.5)).epsilon(1e-14));
      CHECK(std::abs(C(2, a)) == Approx(std::sqrt(0.5)).epsilon(1e-14));
    }
  }
}

TEST_CASE("Attitude error sign: C_computed = (I - [phi x]) C_true", "[attitude]") {
  const Matrix3d C_true = C_b_n_from_euler(AngleConvention::NedFrd, {0.3, -0.2, 1.1});
  const Vector3d phi(2e-5, -3e-5, 1e-5);
  const Matrix3d C_comp = (Matrix3d::Identity() - skew(phi)) * C_true;
  CHECK((attitude_error_n(C_comp, C_true) - phi).norm() < 1e-14);
  CHECK((attitude_error_n(dcm_from_rotvec(-phi) * C_true, C_true) - phi).norm() <
        1e-15);  // rounding of unit-size matrices
}
