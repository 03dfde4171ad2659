#include <catch2/catch.hpp>

#include "helpers.hpp"
#include "models/config.hpp"
#include "models/units.hpp"
#include "rig/plan.hpp"
#include "rig/table.hpp"

using namespace sinscal;
using Eigen::Matrix3d;
using Eigen::Vector3d;

TEST_CASE("Table: angles for every paper orientation reproduce it", "[table]") {
  const Plan plan = test::load_plan("seed8.ini");
  REQUIRE(plan.orientations.size() == 8);
  const Table table(plan.table);
  for (const auto& o : plan.orientations) {
    const Matrix3d C = C_b_n_from_euler(plan.convention, o.angles);
    const TableAngles a = table.angles_for(C);
    CHECK((table.C_b_n(a) - C).cwiseAbs().maxCoeff() < 1e-12);
  }
  // Orientation 1 (roll 45 about North) is a pure outer-axis tilt of 45 deg.
  const TableAngles a1 =
      table.angles_for(C_b_n_from_euler(plan.convention, plan.orientations[0].angles));
  CHECK(std::abs(a1.outer) == Approx(45 * units::deg));
  CHECK(a1.inner == Approx(0.0).margin(1e-12));
  // Nose up 30 deg at heading 0 tilts the inner axis (body y) towards South: unreachable.
  CHECK_THROWS_AS(table.angles_for(C_b_n_from_euler(plan.convention, {0, 30 * units::deg, 0})),
                  UnreachableOrientation);
}

TEST_CASE("Plans: seed8 and rot19 build the documented timelines", "[plan]") {
  const Plan s8 = test::load_plan("seed8.ini");
  const Motion m8 = build_motion(s8, s8.site);
  REQUIRE(m8.dwells().size() == 8);
  for (const auto& d : m8.dwells()) {
    CHECK(d.t_end - d.t_start == Approx(180.0));
    CHECK((d.C_b_n_true - d.C_b_n_known).cwiseAbs().maxCoeff() < 1e-12);
  }
  const Plan r19 = test::load_plan("rot19.ini");
  REQUIRE(r19.steps.size() == 18);
  const Motion m19 = build_motion(r19, r19.site);
  REQUIRE(m19.dwells().size() == 19);
  CHECK(m19.duration() == Approx(70.0 + 18 * 29.0));
  CHECK(m19.dwells()[0].t_end == Approx(70.0));
  // The sequence turns the body back to its start attitude.
  CHECK((m19.dwells().back().C_b_n_known - m19.dwells().front().C_b_n_known).cwiseAbs().maxCoeff() <
        1e-12);
  CHECK((m19.dwells().back().C_b_n_true - m19.dwells().back().C_b_n_known).cwiseAbs().maxCoeff() <
        1e-12);
  // Start (ned-frd, pitch 90 deg): x up, y East, z North.
  CHECK(m19.dwells()[0].C_b_n_known.col(0).z() == Approx(-1.0));
  CHECK(m19.dwells()[0].C_b_n_known.col(2).x() == Approx(1.0));
  // The first +y turn is about East: z turns from North to up, x from up to South.
  CHECK(m19.dwells()[1].C_b_n_known.col(2).z() == Approx(-1.0));
  CHECK(m19.dwells()[1].C_b_n_known.col(0).x() == Approx(-1.0));
}

TEST_CASE("Plans: table errors move the truth away from the known attitude", "[plan]") {
  const Plan s8 = test::load_plan("seed8.ini");
  TableErrors e;
  e.angle_sigma = 2.5 * units::arcsec;
  e.non_orthogonality = 5 * units::arcsec;
  e.seed = 9;
  const Motion m = build_motion(s8, s8.site, e);
  double max_err = 0;
  for (const auto& d : m.dwells())
    max_err = std::max(max_err, rotvec_from_dcm(d.C_b_n_true * d.C_b_n_known.transpose()).norm());
  CHECK(max_err > 1 * units::arcsec);
  CHECK(max_err < 30 * units::arcsec);
}

TEST_CASE("Motion: rates and angular accelerations match finite differences", "[motion]") {
  for (const char* name : {"seed8.ini", "rot19.ini"}) {
    const Plan p = test::load_plan(name);
    const Motion m = build_motion(p, p.site);
    const double h = 1e-4;
    for (const auto& seg : m.segments()) {
      if (seg.is_static()) continue;
      for (double frac : {0.05, 0.37, 0.5, 0.81}) {
        const double t = seg.t0 + frac * (seg.t1 - seg.t0);
        const KinematicState k = m.at(t), kp = m.at(t + h), km = m.at(t - h);
        const Vector3d w_fd = rotvec_from_dcm(km.C_b_n.transpose() * kp.C_b_n) / (2 * h);
        CHECK((w_fd - k.omega_nb_b).norm() < 1e-8 * (1 + k.omega_nb_b.norm()));
        const Vector3d wd_fd = (kp.imu.omega_ib_b - km.imu.omega_ib_b) / (2 * h);
        CHECK((wd_fd - k.imu.omega_dot_ib_b).norm() < 1e-6);
        // Specific force is gravity's reaction at the table centre.
        CHECK(k.imu.f_ib_b.norm() ==
              Approx(Earth::wgs84().gravity_n(p.site.lat_rad, p.site.h_m).norm()));
      }
    }
  }
}

TEST_CASE("Plans: bad plans are clear errors naming file and line", "[plan]") {
  const std::string dir = test::temp_dir("plans");
  const std::string head =
      "[plan]\ntype = orientations\nconvention = paper\nmove_rate = 15 deg/s\n"
      "move_acceleration = 15 deg/s^2\n";
  auto error_of = [&](const std::string& text) {
    test::write_file(dir + "/p.ini", text);
    try {
      Plan::load(dir + "/p.ini");
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK_THAT(
      error_of(head + "[orientation.1]\nheading = 0\npitch = 0\nroll = 0\ndwell = 180 deg\n"),
      Catch::Contains("p.ini:10") && Catch::Contains("deg"));
  CHECK_THAT(error_of(head + "[orientation.1]\nheading = 0\npitch = 0\nroll = 0\n"),
             Catch::Contains("dwell"));
  CHECK_THAT(error_of(head + "[orientation.2]\nheading = 0\npitch = 0\nroll = 0\ndwell = 1\n"),
             Catch::Contains("orientation.1"));
  CHECK_THAT(error_of(head + "[orientation.1]\nheading = 0\npitch = 30\nroll = 0\ndwell = 1\n"),
             Catch::Contains("not reachable"));
  CHECK_THAT(
      error_of(head + "[orientation.1]\nheading = 0\npitch = 0\nroll = 0\ndwell = 1\nspeed = 3\n"),
      Catch::Contains("p.ini:11") && Catch::Contains("unknown key"));
  CHECK_THAT(
      error_of(
          "[plan]\ntype = rotations\nrotation_acceleration = 1 deg/s^2\n[start]\nheading = 0\n"
          "pitch = 0\nroll = 0\ndwell = 10\n[rotations]\naxes = +y\nangle = 90\nduration = 9\n"),
      Catch::Contains("acceleration too low"));
}

TEST_CASE("Every bundled plan loads and builds", "[plan]") {
  int n = 0;
  for (const auto& f : std::filesystem::directory_iterator(test::source_path("config/plans"))) {
    CAPTURE(f.path().string());
    const Plan p = Plan::load(f.path().string());
    CHECK(p.has_site);
    CHECK(build_motion(p, p.site).dwells().size() >= 8);
    ++n;
  }
  CHECK(n >= 2);
}
