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

TEST_CASE("Euler angles round trip in every convention", "[attitude]") {
  for (auto conv : {AngleConvention::NedFrd, AngleConvention::Paper, AngleConvention::EnuRfu}) {
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

TEST_CASE("enu-rfu (PSINS): hand-derived attitudes", "[attitude][enu-rfu]") {
  const double d = units::deg;
  const auto C = [](double yaw, double pitch, double roll) {
    // Plan angles: heading = -yaw (clockwise from North).
    return C_b_n_from_euler(AngleConvention::EnuRfu, {-yaw, pitch, roll});
  };
  const Vector3d N(1, 0, 0), E(0, 1, 0), Up(0, 0, -1);
  // Zero angles: x Right = East, y Forward = North, z Up.
  Matrix3d c = C(0, 0, 0);
  CHECK((c.col(0) - E).norm() < 1e-15);
  CHECK((c.col(1) - N).norm() < 1e-15);
  CHECK((c.col(2) - Up).norm() < 1e-15);
  CHECK((c - C_enu_ned()).norm() < 1e-15);
  // Yaw 90 deg is counter-clockwise seen from above: forward turns from North to West.
  c = C(90 * d, 0, 0);
  CHECK((c.col(1) + E).norm() < 1e-15);
  CHECK((c.col(0) - N).norm() < 1e-15);
  // Pitch 30 deg raises the nose: forward = cos30 North + sin30 Up.
  c = C(0, 30 * d, 0);
  CHECK((c.col(1) - (std::sqrt(0.75) * N + 0.5 * Up)).norm() < 1e-15);
  CHECK((c.col(0) - E).norm() < 1e-15);
  // Roll 30 deg lowers the right side: right = cos30 East + sin30 Down.
  c = C(0, 0, 30 * d);
  CHECK((c.col(0) - (std::sqrt(0.75) * E - 0.5 * Up)).norm() < 1e-15);
  CHECK((c.col(1) - N).norm() < 1e-15);
  // The PSINS order: yaw, then pitch about the turned right axis. Yaw 90, pitch 90 deg: right
  // (x) North, forward (y) up, z East.
  c = C(90 * d, 90 * d, 0);
  CHECK((c.col(1) - Up).norm() < 1e-15);
  CHECK((c.col(0) - N).norm() < 1e-15);
  CHECK((c.col(2) - E).norm() < 1e-15);
  // PSINS a2mat, written out: Cnb = [cj ck - si sj sk, -ci sk, sj ck + si cj sk; cj sk + si sj ck,
  // ci ck, sj sk - si cj ck; -ci sj, si, ci cj] (i pitch, j roll, k yaw), East-North-Up.
  const double p = 0.3, r = -1.2, y = 2.1;
  const double si = std::sin(p), ci = std::cos(p), sj = std::sin(r), cj = std::cos(r),
               sk = std::sin(y), ck = std::cos(y);
  Matrix3d Cnb;
  Cnb << cj * ck - si * sj * sk, -ci * sk, sj * ck + si * cj * sk, cj * sk + si * sj * ck, ci * ck,
      sj * sk - si * cj * ck, -ci * sj, si, ci * cj;
  CHECK((C(y, p, r) - C_enu_ned() * Cnb).cwiseAbs().maxCoeff() < 1e-15);
}

TEST_CASE("enu-rfu is ned-frd with the body axes relabelled: same angles, same attitude",
          "[attitude][enu-rfu]") {
  // Yaw-pitch-roll about Up, Right, Forward (PSINS) is heading-pitch-roll about Down, Right,
  // Forward (3-2-1) with yaw = -heading: for every angle, C_enu-rfu = C_ned-frd * P where
  // P takes RFU components to FRD ones (x_frd = y_rfu, y_frd = x_rfu, z_frd = -z_rfu).
  Matrix3d P;
  P << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  for (double h : {0.0, 10.0, 135.0, 270.0, 359.0})
    for (double p : {-90.0, -89.9999, -45.0, 0.0, 30.0, 89.9999, 90.0})
      for (double r : {-179.0, -30.0, 0.0, 75.0}) {
        const EulerAngles e{h * units::deg, p * units::deg, r * units::deg};
        CAPTURE(h, p, r);
        const Matrix3d c = C_b_n_from_euler(AngleConvention::EnuRfu, e);
        CHECK((c - C_b_n_from_euler(AngleConvention::NedFrd, e) * P).cwiseAbs().maxCoeff() < 1e-15);
        // Back to angles: the same matrix (angles themselves are ambiguous at +-90 deg pitch).
        const EulerAngles back = euler_from_C_b_n(AngleConvention::EnuRfu, c);
        CHECK((C_b_n_from_euler(AngleConvention::EnuRfu, back) - c).cwiseAbs().maxCoeff() < 1e-9);
        if (std::abs(p) < 89.0) {
          CHECK(back.pitch == Approx(e.pitch).margin(1e-12));
          CHECK(back.roll == Approx(e.roll).margin(1e-12));
          CHECK(std::remainder(back.heading - e.heading, 2 * M_PI) == Approx(0.0).margin(1e-12));
        }
      }
  // Near pitch 90 deg: pitch 89.9999 deg, yaw 30 deg, roll 20 deg. Forward is 1.7e-6 rad from Up,
  // its horizontal part points at yaw 30 deg (North towards West), and the angles come back to
  // 1e-9 rad (the condition of yaw and roll there is 1 / cos(pitch) = 5.7e5).
  const double d = units::deg;
  const EulerAngles e{-30 * d, 89.9999 * d, 20 * d};
  const Matrix3d c = C_b_n_from_euler(AngleConvention::EnuRfu, e);
  const double cp = std::cos(89.9999 * d);
  CHECK(c(2, 1) == Approx(-std::sin(89.9999 * d)).epsilon(1e-15));
  CHECK(c(0, 1) == Approx(cp * std::cos(30 * d)).epsilon(1e-9));
  CHECK(c(1, 1) == Approx(-cp * std::sin(30 * d)).epsilon(1e-9));
  const EulerAngles back = euler_from_C_b_n(AngleConvention::EnuRfu, c);
  CHECK(back.pitch == Approx(e.pitch).margin(1e-9));
  CHECK(back.roll == Approx(e.roll).margin(1e-9));
  CHECK(back.heading == Approx(e.heading + 2 * M_PI).margin(1e-9));
  CHECK(parse_angle_convention("enu-rfu") == AngleConvention::EnuRfu);
  CHECK(to_string(AngleConvention::EnuRfu) == "enu-rfu");
  CHECK_THROWS_WITH(parse_angle_convention("enu"), Catch::Contains("enu-rfu"));
}
