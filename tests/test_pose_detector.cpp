// Static poses of hand-held sessions: simulated ones (known pose edges) in raw counts with
// unknown offsets, and the real Xsens MTi recording of imu_tk.
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "filter/table_free/pose_detector.hpp"
#include "helpers.hpp"
#include "models/attitude.hpp"
#include "models/units.hpp"
#include "rig/handheld.hpp"

using namespace sinscal;

namespace {

/// MPU-6050-like raw scaling: 16384 counts/g, 131 counts/(deg/s), offsets of a few hundred counts
/// (the gyro's 3.5 deg/s as in the real unit).
RawScaling mpu6050_like() {
  RawScaling c;
  c.accel_sensitivity.setConstant(16384.0 / units::g0);
  c.gyro_sensitivity.setConstant(131.0 / units::deg_per_s);
  c.accel_offset = Eigen::Vector3d(-250.0, 400.0, 120.0);
  c.gyro_offset = Eigen::Vector3d(3.5, -2.0, 1.0) * 131.0;
  return c;
}

/// Time from a pose's edge at `t_edge` into the neighbouring turn (direction +1 after, -1
/// before) until the body rate reaches 3 deg/s.
double slow_edge(const Motion& m, double t_edge, double direction) {
  for (double dt = 0.0; dt < 1.0; dt += 1e-4)
    if (m.at(t_edge + direction * dt).omega_nb_b.norm() > 3.0 * units::deg_per_s) return dt;
  return 1.0;
}

}  // namespace

TEST_CASE("Pose detector finds the simulated hand-held poses at their edges", "[pose]") {
  const SensorProfile mems = SensorProfile::load(test::source_path("config/sensors/mems.ini"));
  Site site;
  site.lat_rad = 45.0 * units::deg;
  HandheldOptions ho;
  ho.first_rest = 20.0;
  ho.poses = 15;
  for (std::uint64_t seed : {1u, 2u}) {
    const Motion m = handheld_motion(site, ho, seed);
    const auto samples = test::simulate(m, mems.draw(seed), 100.0, &mems.noise, seed + 10);
    const auto counts = counts_from_readings(readings_from_samples(samples), mpu6050_like());
    const PoseDetection found = detect_poses(counts);
    CAPTURE(seed, found.threshold, found.gyro_noise_variance.transpose());
    REQUIRE(found.poses.size() == m.dwells().size());
    for (std::size_t k = 0; k < found.poses.size(); ++k) {
      const Dwell& d = m.dwells()[k];
      const Pose& p = found.poses[k];
      CAPTURE(k, d.t_start, d.t_end, p.t_start, p.t_end);
      // A reading at t covers (t - 0.01, t]: the first reading of a pose ends 0.01 s after the
      // rest begins. The detector sees a turn once its rate is about 30 per-sample gyro sigmas
      // (sqrt(w (threshold - 3)) for one moving reading in a window of w = 101), 1.5 deg/s for
      // this MEMS gyro. How soon a turn reaches that depends on how its two rotations add up;
      // the tolerance is the time the turn takes to reach 3 deg/s, plus two samples.
      const double tol_start = k == 0 ? 0.0 : slow_edge(m, d.t_start, -1.0) + 0.02;
      const double tol_end = k + 1 == m.dwells().size() ? 0.0 : slow_edge(m, d.t_end, 1.0) + 0.02;
      CHECK(std::abs(p.t_start - (d.t_start + 0.01)) <= tol_start + 1e-9);
      if (k + 1 < found.poses.size()) CHECK(std::abs(p.t_end - d.t_end) <= tol_end + 1e-9);
      // The mean rate is the gyro offset plus bias (Earth rate below a count): within 5 sigma of
      // the mean of the per-reading noise.
      const Eigen::Vector3d w_true =
          mpu6050_like().gyro_sensitivity.cwiseProduct(
              mems.draw(seed).gyro_output(m.at(0.5 * (d.t_start + d.t_end)).imu)) +
          mpu6050_like().gyro_offset;
      const double n = static_cast<double>(p.count);
      for (int i = 0; i < 3; ++i)
        CHECK(std::abs(p.gyro_mean(i) - w_true(i)) < 5.0 * p.gyro_std(i) / std::sqrt(n) + 0.5);
    }
  }
}

TEST_CASE("Pose detector: a record that never rests is an error", "[pose]") {
  std::vector<ImuReading> r(1000);
  for (std::size_t k = 0; k < r.size(); ++k) {
    const double t = 0.01 * static_cast<double>(k);
    r[k].t = t;
    r[k].gyro = Eigen::Vector3d(std::sin(t), 0.0, 0.0);
    r[k].accel = Eigen::Vector3d(std::cos(3.0 * t), 1.0, 2.0);
  }
  CHECK_THROWS_AS(detect_poses(r), PoseDetectorError);
  std::vector<ImuReading> tiny(r.begin(), r.begin() + 10);
  CHECK_THROWS_AS(detect_poses(tiny), PoseDetectorError);
}

TEST_CASE("Pose detector on the real Xsens MTi session finds its 38 poses", "[pose][real]") {
  const std::string dir = test::source_path("data/xsens-mti-handheld");
  const auto r = test::read_xsens(dir);
  REQUIRE(r.size() == 51175);
  const PoseDetection found = detect_poses(r);
  for (const auto& p : found.poses)
    UNSCOPED_INFO("pose " << p.index << ": " << p.t_start << " - " << p.t_end << " s");
  REQUIRE(found.poses.size() == 38);
  // About 50 s at the start, then 37 poses of 3-12 s.
  CHECK(found.poses[0].t_start < 1.0);
  CHECK(found.poses[0].duration() > 45.0);
  CHECK(found.poses[0].duration() < 55.0);
  for (std::size_t k = 1; k < found.poses.size(); ++k) {
    CAPTURE(k, found.poses[k].t_start, found.poses[k].t_end);
    CHECK(found.poses[k].duration() > 2.5);
    CHECK(found.poses[k].duration() < 13.0);
  }
  // Every pose is at rest: its gyro readings scatter like the record's static noise. (Not the
  // accelerometers': in some poses they creep slowly, e.g. pose 11's z by 17 counts, 0.04 m/s^2,
  // over its 8 s, which no window of 1 s tells from noise.)
  for (const auto& p : found.poses)
    for (int i = 0; i < 3; ++i) {
      CAPTURE(p.index, i, p.gyro_std(i));
      CHECK(p.gyro_std(i) < 1.2 * std::sqrt(found.gyro_noise_variance(i)));
    }
}

TEST_CASE("Hand-held motion: seeded random poses joined by hand-like turns", "[pose][handheld]") {
  Site site;
  site.lat_rad = 45.0 * units::deg;
  HandheldOptions ho;
  ho.poses = 30;
  const Motion a = handheld_motion(site, ho, 42), b = handheld_motion(site, ho, 42);
  const Motion c = handheld_motion(site, ho, 43);
  REQUIRE(a.dwells().size() == 31);
  CHECK(a.duration() == b.duration());  // same seed, same motion
  CHECK(a.duration() != c.duration());
  CHECK(a.dwells()[0].t_end == Approx(ho.first_rest));
  double peak = 0.0;
  for (std::size_t k = 0; k < a.segments().size(); ++k) {
    const MotionSegment& s = a.segments()[k];
    // Continuous attitude from one piece to the next.
    if (k > 0) CHECK((a.segments()[k - 1].C_b_n_end() - s.C_b_n_start).norm() < 1e-12);
    if (s.is_static()) {
      CHECK(s.t1 - s.t0 >= (k == 0 ? ho.first_rest : ho.rest_min) - 1e-12);
      CHECK(s.t1 - s.t0 <= (k == 0 ? ho.first_rest : ho.rest_max) + 1e-12);
      continue;
    }
    // Each turn: at least min_turn, at most the peak rate (sampled every 5 ms).
    CHECK(rotvec_from_dcm(s.C_b_n_end() * s.C_b_n_start.transpose()).norm() >= ho.min_turn - 1e-9);
    for (double t = s.t0; t <= s.t1; t += 0.005) peak = std::max(peak, a.at(t).omega_nb_b.norm());
  }
  CHECK(peak <= ho.peak_rate_max * (1.0 + 1e-9));
  CHECK(peak > ho.peak_rate_min);
  // The poses point gravity every way: the mean of the up directions is near zero and every
  // body axis is within 30 deg of vertical in some pose.
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), best = Eigen::Vector3d::Zero();
  for (const auto& d : a.dwells()) {
    const Eigen::Vector3d up_b = -d.C_b_n_true.row(2).transpose();
    mean += up_b / static_cast<double>(a.dwells().size());
    best = best.cwiseMax(up_b.cwiseAbs());
  }
  CHECK(mean.norm() < 0.5);
  CHECK(best.minCoeff() > std::cos(30.0 * units::deg));
  // The simulator's increments through a turn reproduce the turn (the motion is consistent with
  // its own rates): integrate one turn with small steps.
  const MotionSegment& turn = a.segments()[1];
  Eigen::Matrix3d C = turn.C_b_n_start;
  const int steps = 5000;
  const double h = (turn.t1 - turn.t0) / steps;
  for (int i = 0; i < steps; ++i) {
    const double t = turn.t0 + (i + 0.5) * h;
    const KinematicState k = a.at(t);
    // C_b_n' = C_b_n [omega_nb_b x] (navigation frame fixed at the site).
    C = C * dcm_from_rotvec(k.omega_nb_b * h);
  }
  CHECK(rotvec_from_dcm(C * turn.C_b_n_end().transpose()).norm() < 1e-6);
}

TEST_CASE("Pose detector on the real MPU-6050 session", "[pose][real]") {
  const std::string path = test::source_path("data/mpu6050-handheld/example_data_calibration.csv");
  std::ifstream f(path);
  REQUIRE(f.good());
  // 4 header lines (Fs, logging type, initialization time, waiting time), the column names,
  // then ax,ay,az,gx,gy,gz in counts at 100 Hz.
  std::string line;
  double init_time = 0.0, wait_time = 0.0;
  for (int i = 0; i < 5 && std::getline(f, line); ++i) {
    if (line.rfind("Initialization time,", 0) == 0) init_time = std::stod(line.substr(20));
    if (line.rfind("Waiting time,", 0) == 0) wait_time = std::stod(line.substr(13));
  }
  REQUIRE(init_time == 36.5);
  REQUIRE(wait_time == 3.0);
  std::vector<ImuReading> r;
  while (std::getline(f, line)) {
    ImuReading x;
    x.t = 0.01 * static_cast<double>(r.size() + 1);
    char comma;
    std::istringstream s(line);
    s >> x.accel(0) >> comma >> x.accel(1) >> comma >> x.accel(2) >> comma >> x.gyro(0) >> comma >>
        x.gyro(1) >> comma >> x.gyro(2);
    r.push_back(x);
  }
  // This unit is held in the hand during its poses: after the initialization the gyros see
  // 0.4-2 deg/s of tremor and drift (30-150 times their noise) in every stop but the last
  // three. With the gyro test only the truly motionless stretches are poses; with the
  // accelerometers alone (imu_tk's detector), the initialization and the 9 stops the
  // accelerometers show (each verified in the record: gyro RMS per 0.5 s falls from thousands
  // of counts to below 300 for 2.3-7 s).
  PoseDetectorOptions accel_only;
  accel_only.use_gyro = false;
  const PoseDetection still = detect_poses(r);
  const PoseDetection held = detect_poses(r, accel_only);
  std::ostringstream s;
  for (const auto& p : held.poses)
    s << "pose " << p.index << ": " << p.t_start << " - " << p.t_end << " s, gyro mean "
      << p.gyro_mean.transpose() / 131.0 << " deg/s, std " << p.gyro_std.transpose() / 131.0
      << "\n";
  INFO(s.str());
  REQUIRE(held.poses.size() == 10);
  CHECK(held.poses[0].t_start < 0.5);
  CHECK(held.poses[0].duration() > init_time - 1.0);
  for (std::size_t k = 1; k < held.poses.size(); ++k) CHECK(held.poses[k].duration() > 2.0);
  REQUIRE(still.poses.size() == 4);
  CHECK(still.poses[0].duration() > init_time - 1.0);
  // Every motionless pose lies within one of the held ones (the last three stops).
  for (std::size_t k = 1; k < still.poses.size(); ++k) {
    const Pose& p = still.poses[k];
    const Pose& q = held.poses[held.poses.size() - still.poses.size() + k];
    CHECK(p.t_start >= q.t_start - 0.01);
    CHECK(p.t_end <= q.t_end + 0.01);
  }
}

TEST_CASE("Pose detector keeps poses whose accelerometer noise rises 2.5-3x in some orientations",
          "[pose]") {
  // The OpenAXES ADXL355's noise rises 2-3x in some orientations (on the axis near gravity, or
  // on all three): such a pose is still at rest, and the gyros see no motion.
  const SensorProfile mems = SensorProfile::load(test::source_path("config/sensors/mems.ini"));
  Site site;
  site.lat_rad = 45.0 * units::deg;
  HandheldOptions ho;
  ho.first_rest = 20.0;
  ho.poses = 15;
  const Motion m = handheld_motion(site, ho, 3);
  const auto samples = test::simulate(m, mems.draw(3), 100.0, &mems.noise, 13);
  const auto clean = counts_from_readings(readings_from_samples(samples), mpu6050_like());
  const PoseDetection reference = detect_poses(clean);
  REQUIRE(reference.poses.size() == m.dwells().size());
  // Poses 1, 4, 7, ...: one axis 3x; poses 2, 5, 8, ...: all three 2.5x (extra white noise).
  auto raised = [&](bool all_axes) {
    std::vector<ImuReading> counts = clean;
    std::mt19937_64 rng(derive_seed(3, 7));
    std::normal_distribution<double> unit(0.0, 1.0);
    for (std::size_t k = 1; k < reference.poses.size(); ++k) {
      const Pose& p = reference.poses[k];
      const bool one = k % 3 == 1, every = all_axes && k % 3 == 2;
      if (!one && !every) continue;
      for (std::size_t i = p.first; i <= p.last; ++i)
        for (int c = 0; c < 3; ++c) {
          const double rise = one ? (c == static_cast<int>((k / 3) % 3) ? 3.0 : 1.0) : 2.5;
          const double extra = std::sqrt((rise * rise - 1.0) * reference.accel_noise_variance(c));
          counts[i].accel(c) += extra * unit(rng);
        }
    }
    return counts;
  };
  const PoseDetection found = detect_poses(raised(true));
  CAPTURE(found.threshold);
  CHECK(found.poses.size() == m.dwells().size());
  // The accelerometers alone: one axis's rise is still a pose.
  PoseDetectorOptions alone;
  alone.use_gyro = false;
  CHECK(detect_poses(raised(false), alone).poses.size() == detect_poses(clean, alone).poses.size());
}
