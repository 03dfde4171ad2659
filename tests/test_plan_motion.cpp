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

TEST_CASE("Motion: a move with a correction about a third axis matches finite differences",
          "[motion]") {
  // All three profiles at once and large, so that a wrong term of the kinematics shows.
  MotionSegment s;
  s.t0 = 0.0;
  s.t1 = 10.0;
  s.C_b_n_start = dcm_from_rotvec(Vector3d(0.3, -0.2, 0.5));
  s.axis_n = Vector3d(0.2, 0.1, 1.0);
  s.alpha = TrapezoidProfile::by_duration(1.2, 10.0, 0.5);
  s.axis_b = Vector3d(1.0, -0.3, 0.2);
  s.beta = TrapezoidProfile::by_duration(-0.8, 10.0, 0.4);
  s.axis_c_n = Vector3d(-0.4, 1.0, 0.3);
  s.gamma = TrapezoidProfile::by_duration(0.6, 10.0, 0.3);
  MotionSegment rest;
  rest.t0 = 10.0;
  rest.t1 = 20.0;
  rest.C_b_n_start = s.C_b_n_end();
  const Motion m(Site{}, {s, rest}, {});
  const double h = 1e-4;
  for (double t : {0.3, 2.9, 5.0, 7.7, 9.6}) {
    const KinematicState k = m.at(t), kp = m.at(t + h), km = m.at(t - h);
    const Vector3d w_fd = rotvec_from_dcm(km.C_b_n.transpose() * kp.C_b_n) / (2 * h);
    CHECK((w_fd - k.omega_nb_b).norm() < 1e-8 * (1 + k.omega_nb_b.norm()));
    const Vector3d wd_fd = (kp.imu.omega_ib_b - km.imu.omega_ib_b) / (2 * h);
    CHECK((wd_fd - k.imu.omega_dot_ib_b).norm() < 1e-6);
  }
  CHECK(rotvec_from_dcm(m.at(10.0).C_b_n * s.C_b_n_end().transpose()).norm() < 1e-12);
}

TEST_CASE(
    "Plans: the table sets each orientation's dwell to its accuracy by a correction the "
    "gyros see",
    "[plan]") {
  // TableErrors::attitude_sigma on an orientation plan: each dwell's attitude is the known one
  // turned by an independent error, reached during the move (no jump the gyros miss).
  const Plan s8 = test::load_plan("seed8.ini");
  TableErrors e;
  e.attitude_sigma = 2.5 * units::arcsec;
  e.seed = 4;
  const Motion m = build_motion(s8, s8.site, e);
  double sum2 = 0.0;
  int n = 0;
  for (const auto& d : m.dwells()) {
    const Vector3d w = rotvec_from_dcm(d.C_b_n_true * d.C_b_n_known.transpose());
    sum2 += w.squaredNorm() / (units::arcsec * units::arcsec);
    n += 3;
  }
  CHECK(std::sqrt(sum2 / n) > 1.0);  // 24 components of sigma 2.5 arcsec
  CHECK(std::sqrt(sum2 / n) < 4.0);
  // Continuity: each segment starts where the one before ends, and every dwell's attitude is
  // the motion's there.
  const auto& segs = m.segments();
  for (std::size_t i = 1; i < segs.size(); ++i)
    CHECK(rotvec_from_dcm(segs[i].C_b_n_start * segs[i - 1].C_b_n_end().transpose()).norm() <
          1e-12);
  for (const auto& d : m.dwells())
    CHECK(
        rotvec_from_dcm(m.at(0.5 * (d.t_start + d.t_end)).C_b_n * d.C_b_n_true.transpose()).norm() <
        1e-12);
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

TEST_CASE("Plans in enu-rfu (PSINS): rot19 written with RFU axes is rot19's motion",
          "[plan][enu-rfu]") {
  const Plan frd = test::load_plan("rot19.ini");
  const Plan rfu = Plan::load(test::source_path("tests/data/rot19-enu-rfu.ini"));
  CHECK(rfu.convention == AngleConvention::EnuRfu);
  const Motion a = build_motion(frd, frd.site), b = build_motion(rfu, rfu.site);
  REQUIRE(a.dwells().size() == b.dwells().size());
  CHECK(b.duration() == Approx(a.duration()));
  // The same physical attitudes, the body axes relabelled: C_rfu = C_frd * P (v_frd = P v_rfu).
  Matrix3d P;
  P << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  for (std::size_t i = 0; i < a.dwells().size(); ++i) {
    CAPTURE(i);
    CHECK(b.dwells()[i].t_start == Approx(a.dwells()[i].t_start));
    CHECK((b.dwells()[i].C_b_n_known - a.dwells()[i].C_b_n_known * P).cwiseAbs().maxCoeff() <
          1e-12);
  }
  // The start, pitch 90 deg: forward (y) up, right (x) East, z (up) North... as rot19's body
  // x up, y East, z North.
  CHECK(b.dwells()[0].C_b_n_known.col(1).z() == Approx(-1.0));
  CHECK(b.dwells()[0].C_b_n_known.col(0).y() == Approx(1.0));
  // Along the motion too (the turns' rates are about the relabelled axes).
  for (double t : {75.0, 110.0, 300.0}) {
    CHECK((b.at(t).C_b_n - a.at(t).C_b_n * P).cwiseAbs().maxCoeff() < 1e-12);
    CHECK((b.at(t).imu.omega_ib_b - P.transpose() * a.at(t).imu.omega_ib_b).norm() < 1e-12);
  }
}

TEST_CASE("Plans in enu-rfu: yaw or heading (not both), yaw only in enu-rfu", "[plan][enu-rfu]") {
  const std::string dir = test::temp_dir("h2_plans_enu");
  auto load = [&](const std::string& convention, const std::string& angles) {
    test::write_file(dir + "/p.ini", "[plan]\ntype = orientations\nconvention = " + convention +
                                         "\nmove_rate = 15 deg/s\nmove_acceleration = 15 deg/s^2\n"
                                         "[orientation.1]\n" +
                                         angles + "pitch = 0\nroll = 0\ndwell = 10\n");
    return Plan::load(dir + "/p.ini");
  };
  const Plan y = load("enu-rfu", "yaw = 30 deg\n");
  const Plan h = load("enu-rfu", "heading = -30 deg\n");
  CHECK(y.orientations[0].angles.heading == Approx(-30 * units::deg));
  CHECK((C_b_n_from_euler(y.convention, y.orientations[0].angles) -
         C_b_n_from_euler(h.convention, h.orientations[0].angles))
            .cwiseAbs()
            .maxCoeff() < 1e-15);
  // Yaw 30 deg counter-clockwise: forward (y) 30 deg West of North.
  const Matrix3d C = C_b_n_from_euler(y.convention, y.orientations[0].angles);
  CHECK(C(1, 1) == Approx(-0.5));
  CHECK_THROWS_WITH(load("enu-rfu", "yaw = 30\nheading = -30\n"),
                    Catch::Contains("p.ini:7") && Catch::Contains("not both"));
  CHECK_THROWS_WITH(load("ned-frd", "yaw = 30\n"),
                    Catch::Contains("p.ini:7") && Catch::Contains("enu-rfu convention"));
  CHECK_THROWS_WITH(load("enu-rfu", ""), Catch::Contains("missing 'yaw'"));
}

TEST_CASE("Rotation plans: per-turn angles, durations or rates, and pauses", "[plan]") {
  const std::string dir = test::temp_dir("h2_plans_lists");
  const std::string head =
      "[plan]\ntype = rotations\nrotation_acceleration = 10 deg/s^2\n[start]\nheading = 0\n"
      "pitch = 0\nroll = 0\ndwell = 30 s\n[rotations]\naxes = +x -y +z\n";
  auto load = [&](const std::string& rotations) {
    test::write_file(dir + "/p.ini", head + rotations);
    return Plan::load(dir + "/p.ini");
  };
  auto error_of = [&](const std::string& rotations) {
    try {
      load(rotations);
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const Plan p = load("angles = 90 180 45 deg\ndurations = 9 12 6 s\npauses = 20 10 30 s\n");
  REQUIRE(p.steps.size() == 3);
  CHECK(p.steps[1].angle == Approx(180 * units::deg));
  CHECK(p.steps[1].duration == 12.0);
  CHECK(p.steps[2].pause == 30.0);
  const Motion m = build_motion(p, Site{});
  REQUIRE(m.dwells().size() == 4);
  CHECK(m.dwells()[1].t_end - m.dwells()[1].t_start == Approx(20.0));
  CHECK(m.dwells()[2].t_end - m.dwells()[2].t_start == Approx(10.0));
  CHECK(m.dwells()[3].t_start == Approx(30 + 9 + 20 + 12 + 10 + 6));
  // One value for all, and rates per turn.
  const Plan q = load("angle = 90\nrates = 10 20 30 deg/s\npause = 5 s\n");
  CHECK(q.steps[2].rate == Approx(30 * units::deg));
  CHECK(q.steps[0].pause == 5.0);
  // A pause of 0 is no dwell.
  CHECK(build_motion(load("angle = 90\nduration = 9\npauses = 5 0 5\n"), Site{}).dwells().size() ==
        3);
  // Counts that do not match the axes, both forms, bad timing.
  CHECK_THAT(error_of("angle = 90\nduration = 9\npauses = 20 10 s\n"),
             Catch::Contains("p.ini:13") && Catch::Contains("expected 3 values, one per turn") &&
                 Catch::Contains("got 2"));
  CHECK_THAT(error_of("angle = 90\ndurations = 9 9 9 9\n"), Catch::Contains("p.ini:12"));
  CHECK_THAT(error_of("angle = 90\nduration = 9\npause = 5\npauses = 5 5 5\n"),
             Catch::Contains("not both"));
  CHECK_THAT(error_of("angle = 90\nduration = 9\npause = 5 6 7\n"),
             Catch::Contains("p.ini:13") && Catch::Contains("'pauses = ...'"));
  CHECK_THAT(error_of("angle = 90\nduration = 9\nrate = 10\n"), Catch::Contains("exactly one"));
  CHECK_THAT(error_of("angle = 90\n"), Catch::Contains("exactly one"));
  CHECK_THAT(error_of("duration = 9\n"), Catch::Contains("missing 'angle'"));
  // Negative or zero durations, rates, angles; negative pauses.
  CHECK_THAT(error_of("angle = 90\nduration = -9\n"),
             Catch::Contains("p.ini:12") && Catch::Contains("turn 1 (+x)") &&
                 Catch::Contains("duration must be positive"));
  CHECK_THAT(error_of("angle = 90\ndurations = 9 0 9\n"),
             Catch::Contains("turn 2 (-y)") && Catch::Contains("positive"));
  CHECK_THAT(error_of("angle = 90\nrate = -10 deg/s\n"), Catch::Contains("rate must be positive"));
  CHECK_THAT(error_of("angles = 90 0 90\nduration = 9\n"),
             Catch::Contains("p.ini:11") && Catch::Contains("turn 2") &&
                 Catch::Contains("angle must be positive"));
  CHECK_THAT(error_of("angle = 90\nduration = 9\npauses = 1 -1 1\n"),
             Catch::Contains("turn 2") && Catch::Contains("not be negative"));
  // [step.N] sections: the same checks.
  const std::string steps =
      "[plan]\ntype = rotations\nrotation_acceleration = 10 deg/s^2\n[start]\nheading = 0\n"
      "pitch = 0\nroll = 0\ndwell = 30 s\n[step.1]\naxis = +x\nangle = 90\n";
  test::write_file(dir + "/s.ini", steps + "duration = -9\nrate = 10\n");
  CHECK_THROWS_WITH(Plan::load(dir + "/s.ini"), Catch::Contains("exactly one"));
  test::write_file(dir + "/s.ini", steps + "duration = -9\n");
  CHECK_THROWS_WITH(Plan::load(dir + "/s.ini"),
                    Catch::Contains("s.ini:12") && Catch::Contains("must be positive"));
  test::write_file(dir + "/s.ini",
                   steps + "rate = 10\n[step.3]\naxis = +y\nangle = 90\nrate = 10\n");
  CHECK_THROWS_WITH(Plan::load(dir + "/s.ini"), Catch::Contains("missing [step.2]"));
  test::write_file(dir + "/s.ini", steps + "rate = 0\n");
  CHECK_THROWS_WITH(Plan::load(dir + "/s.ini"),
                    Catch::Contains("s.ini:12") && Catch::Contains("must be positive"));
}

TEST_CASE(
    "Plans: negative, huge, NaN or infinite times and angles, and plans beyond the size "
    "limits are refused",
    "[plan][limits]") {
  const std::string dir = test::temp_dir("h2_plans_limits");
  auto error_of = [&](const std::string& text) {
    test::write_file(dir + "/p.ini", text);
    try {
      Plan::load(dir + "/p.ini");
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  auto rotations = [](const std::string& start_dwell, const std::string& rest = "",
                      const std::string& plan_extra = "") {
    return "[plan]\ntype = rotations\nrotation_acceleration = 10 deg/s^2\n" + plan_extra +
           "[start]\nheading = 0\npitch = 0\nroll = 0\ndwell = " + start_dwell +
           "\n[rotations]\naxes = +x\nangle = 90\nduration = 9\n" + rest;
  };
  CHECK(error_of(rotations("70 s")) == "no error");
  CHECK_THAT(error_of(rotations("-10 s")),
             Catch::Contains("p.ini:8") && Catch::Contains("must be positive"));
  CHECK_THAT(error_of(rotations("0")), Catch::Contains("p.ini:8"));
  CHECK_THAT(error_of(rotations("1e12 s")), Catch::Contains("p.ini:8") &&
                                                Catch::Contains("plan limit of 7") &&
                                                Catch::Contains("allow_large"));
  // (A lone "nan" or "inf" reads as an unknown unit, with a number before it as not finite.)
  for (const char* bad : {"nan", "inf", "-inf", "1e999", "NaN s", "inf s", "1e999 s"}) {
    CAPTURE(bad);
    const std::string e = error_of(rotations(bad));
    CHECK_THAT(e, Catch::Contains("p.ini:8"));
    CHECK((e.find("not a finite number") != e.npos || e.find("is not a unit") != e.npos));
  }
  CHECK_THAT(error_of(rotations("NaN s")), Catch::Contains("not a finite number"));
  CHECK_THAT(error_of(rotations("10", "pause = inf s\n")), Catch::Contains("not a finite number"));
  // Angles: finite and within a turn (orientations), at most 100 turns (rotations).
  const std::string orient =
      "[plan]\ntype = orientations\nmove_rate = 15 deg/s\nmove_acceleration = 15 deg/s^2\n"
      "[orientation.1]\npitch = 0\nroll = 0\ndwell = 10\nheading = ";
  CHECK_THAT(error_of(orient + "nan\n"), Catch::Contains("p.ini:9"));
  CHECK_THAT(error_of(orient + "1e300 deg\n"),
             Catch::Contains("p.ini:9") && Catch::Contains("within -360 and 360"));
  CHECK_THAT(error_of(orient + "0\n[orientation.2]\nheading = 0\npitch = 0\nroll = 0\n"
                               "dwell = 1e12 s\n"),
             Catch::Contains("p.ini:14") && Catch::Contains("plan limit"));
  CHECK_THAT(
      error_of(rotations("10").replace(rotations("10").find("angle = 90"), 10, "angle = 1e6 deg")),
      Catch::Contains("at most 100 turns"));
  // The whole plan: 100 h of start dwell and 100 h of pause are 8.3 days, beyond the 7-day limit,
  // unless allow_large raises it.
  const std::string eight_days = rotations("100 h", "pause = 100 h\n");
  CHECK_THAT(error_of(eight_days), Catch::Contains("the plan lasts 8.") &&
                                       Catch::Contains("longer than the plan limit of 7"));
  CHECK(error_of(rotations("100 h", "pause = 100 h\n", "allow_large = true\n")) == "no error");
  CHECK_THAT(error_of(rotations("6 h", "pause = 9000 h\n", "allow_large = true\n")),
             Catch::Contains("366"));
  // A slow move rate makes the moves long: counted in the plan's duration.
  CHECK_THAT(error_of("[plan]\ntype = orientations\nmove_rate = 1e-6 deg/s\n"
                      "move_acceleration = 15 deg/s^2\n[orientation.1]\nheading = 0\npitch = 0\n"
                      "roll = 0\ndwell = 10\n[orientation.2]\nheading = 90\npitch = 0\nroll = 0\n"
                      "dwell = 10\n"),
             Catch::Contains("the plan lasts"));
  // More than 100,000 turns; allowed with allow_large.
  std::string axes = "axes =";
  for (int i = 0; i < 100001; ++i) axes += i % 2 ? " -x" : " +x";
  const std::string many =
      "[plan]\ntype = rotations\nrotation_acceleration = 100 deg/s^2\n"
      "[start]\nheading = 0\npitch = 0\nroll = 0\ndwell = 1\n[rotations]\n" +
      axes + "\nangle = 1\nduration = 0.5\n";
  CHECK_THAT(error_of(many), Catch::Contains("100001 turns, more than the plan limit of 100000") &&
                                 Catch::Contains("allow_large"));
  const std::string many_large =
      "[plan]\ntype = rotations\nrotation_acceleration = 100 deg/s^2\nallow_large = yes\n"
      "[start]\nheading = 0\npitch = 0\nroll = 0\ndwell = 1\n[rotations]\n" +
      axes + "\nangle = 1\nduration = 0.5\n";
  CHECK(error_of(many_large) == "no error");
  CHECK_THAT(error_of(rotations("10", "", "allow_large = maybe\n")), Catch::Contains("p.ini:4"));
}
