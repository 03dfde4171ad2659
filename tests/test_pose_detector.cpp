// Static poses of hand-held sessions: simulated ones (known pose edges) in raw counts with
// unknown offsets, and the real Xsens MTi recording of imu_tk.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "filter/pose_detector.hpp"
#include "helpers.hpp"
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
  ho.poses = 20;
  for (std::uint64_t seed : {1u, 2u, 3u}) {
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

namespace {
/// The imu_tk Xsens files: two whitespace tables `t x y z` with the same times (raw counts).
std::vector<ImuReading> read_xsens(const std::string& dir) {
  auto read = [](const std::string& path) {
    std::ifstream f(path);
    REQUIRE(f.good());
    std::vector<std::array<double, 4>> rows;
    std::array<double, 4> row{};
    while (f >> row[0] >> row[1] >> row[2] >> row[3]) rows.push_back(row);
    return rows;
  };
  const auto acc = read(dir + "/xsens_acc.txt");
  const auto gyr = read(dir + "/xsens_gyro.txt");
  REQUIRE(acc.size() == gyr.size());
  std::vector<ImuReading> out(acc.size());
  for (std::size_t k = 0; k < acc.size(); ++k) {
    REQUIRE(acc[k][0] == gyr[k][0]);
    out[k].t = acc[k][0];
    out[k].accel = Eigen::Vector3d(acc[k][1], acc[k][2], acc[k][3]);
    out[k].gyro = Eigen::Vector3d(gyr[k][1], gyr[k][2], gyr[k][3]);
  }
  return out;
}
}  // namespace

TEST_CASE("Pose detector on the real Xsens MTi session finds its 38 poses", "[pose][real]") {
  const std::string dir = "/work/shared/data/xsens-mti-handheld";
  if (!std::ifstream(dir + "/xsens_acc.txt").good()) {
    WARN("Xsens recording not found at " << dir << ": skipped");
    return;
  }
  const auto r = read_xsens(dir);
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
