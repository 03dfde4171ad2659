#pragma once

#include <unistd.h>

#include <array>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "filter/kalman/kalman_calibrator.hpp"
#include "models/sensor_profile.hpp"
#include "rig/handheld.hpp"
#include "rig/imu_sim.hpp"
#include "rig/plan.hpp"

namespace sinscal::test {

inline std::string source_path(const std::string& relative) {
  return std::string(SINSCAL_SOURCE_DIR) + "/" + relative;
}

/// A fresh temporary directory for one test (per process: test runs of several build trees at
/// once do not share it).
inline std::string temp_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("sinscal_test_" + std::to_string(::getpid()) + "_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

inline Plan load_plan(const std::string& name) {
  return Plan::load(source_path("config/plans/" + name));
}

/// What the estimators know of a plan (rig/timeline.hpp), at the plan's site.
inline PlanTimeline timeline(const Plan& plan) { return PlanTimeline::of(plan, plan.site); }

/// The plan's part of a simulated motion's dwells (what the estimators may see).
inline std::vector<PlanDwell> plan_dwells(const Motion& motion) {
  std::vector<PlanDwell> out;
  for (const Dwell& d : motion.dwells()) out.push_back(d);
  return out;
}

/// All samples of a motion, noise off unless a noise model is given; with `temperature`, in a
/// chamber (the samples carry the sensor's temperature).
inline std::vector<ImuSample> simulate(const Motion& motion, const ImuErrorModel& errors = {},
                                       double rate_hz = 100.0, const NoiseModel* noise = nullptr,
                                       std::uint64_t seed = 1,
                                       const SensorTemperature* temperature = nullptr) {
  SimulatorOptions o;
  o.temperature = temperature;
  o.rate_hz = rate_hz;
  o.noise = noise != nullptr;
  o.noise_seed = seed;
  ImuSimulator sim(motion, errors, noise ? *noise : NoiseModel{}, o);
  std::vector<ImuSample> out;
  out.reserve(sim.total_samples());
  ImuSample s;
  while (sim.next(s)) out.push_back(s);
  return out;
}

using sinscal::VectorSource;

/// A sensor-profile range [lo, hi] (SI) for profiles built in tests.
inline CoefficientRange range(double lo, double hi) {
  CoefficientRange r;
  r.lo = lo;
  r.hi = hi;
  return r;
}

inline void write_file(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  std::fputs(text.c_str(), f);
  std::fclose(f);
}

/// Pushes every sample through the filter, finishes, returns the estimate.
inline std::vector<CoefficientEstimate> run_filter(Calibrator& kf,
                                                   const std::vector<ImuSample>& samples) {
  for (const auto& s : samples) kf.push(s);
  kf.finish();
  return kf.estimate();
}

/// The imu_tk Xsens files: two whitespace tables `t x y z` with the same times (raw counts).
inline std::vector<ImuReading> read_xsens(const std::string& dir) {
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

}  // namespace sinscal::test
