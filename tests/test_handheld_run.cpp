// Hand-held sessions end to end (filter/table_free/handheld_run.hpp, report/table_free_result.hpp):
// a simulated session written as a plan-less session.ini with a two-file log in raw counts, read,
// calibrated from its nominal conversion, validated and written as a result file; Allan of a pose.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "filter/table_free/handheld_run.hpp"
#include "helpers.hpp"
#include "models/config.hpp"
#include "models/units.hpp"
#include "report/table_free_result.hpp"
#include "rig/handheld.hpp"

using namespace sinscal;

namespace {

SensorProfile mems() {
  SensorProfile p;
  p.name = "test-mems";
  p.ranges["gyro.bias"] = test::range(0.5 * units::deg_per_s, 1.0 * units::deg_per_s);
  p.ranges["gyro.scale"] = test::range(0.01, 0.03);
  p.ranges["gyro.misalignment"] = test::range(300 * units::arcsec, 3000 * units::arcsec);
  p.ranges["accel.bias"] = test::range(5 * units::mg, 40 * units::mg);
  p.ranges["accel.scale"] = test::range(0.01, 0.03);
  p.ranges["accel.misalignment"] = test::range(300 * units::arcsec, 3000 * units::arcsec);
  p.noise.gyro.white = 0.3 * units::deg_per_sqrt_h;
  p.noise.accel.white = 150 * units::ug_per_sqrt_hz;
  return p;
}

// The nominal conversion of the simulated ADC (Xsens-like: 16-bit, zero at 32768).
RawScaling nominal() {
  RawScaling c;
  c.accel_sensitivity.setConstant(400.0);
  c.gyro_sensitivity.setConstant(4800.0);
  c.accel_offset.setConstant(32768.0);
  c.gyro_offset.setConstant(32768.0);
  return c;
}

// Writes a simulated hand-held session (two files of counts, t x y z) and its session.ini.
std::string write_session(const std::string& dir, const ImuErrorModel& truth, std::uint64_t seed,
                          int poses) {
  Site site;
  site.lat_rad = 45.0 * units::deg;
  site.h_m = 100.0;
  HandheldOptions ho;
  ho.poses = poses;
  const Motion m = handheld_motion(site, ho, derive_seed(seed, 0));
  const SensorProfile prof = mems();
  const auto counts = counts_from_readings(
      readings_from_samples(test::simulate(m, truth, 100.0, &prof.noise, derive_seed(seed, 2))),
      nominal(), true);
  std::FILE* a = std::fopen((dir + "/acc.txt").c_str(), "w");
  std::FILE* g = std::fopen((dir + "/gyro.txt").c_str(), "w");
  for (const auto& r : counts) {
    std::fprintf(a, "%.5f %.0f %.0f %.0f\n", r.t, r.accel(0), r.accel(1), r.accel(2));
    std::fprintf(g, "%.5f %.0f %.0f %.0f\n", r.t, r.gyro(0), r.gyro(1), r.gyro(2));
  }
  std::fclose(a);
  std::fclose(g);
  test::write_file(dir + "/session.ini",
                   "[session]\nname = handheld\nrate = 100 Hz\n\n[site]\nlatitude = 45 deg\n"
                   "height = 100 m\n\n[log]\nformat = custom\naccel_file = acc.txt\n"
                   "gyro_file = gyro.txt\ndelimiter = whitespace\naccel = rate\n"
                   "accel_scale = 0.0025\naccel_offset = 32768\ngyro = rate\n"
                   "gyro_scale = 0.00020833333333333335\ngyro_offset = 32768\n");
  return dir + "/session.ini";
}

}  // namespace

TEST_CASE("Sessions without a plan load for the hand-held methods only", "[handheld][session]") {
  const std::string dir = test::temp_dir("handheld_session");
  test::write_file(dir + "/imu.csv", "1\n");
  test::write_file(dir + "/session.ini",
                   "[session]\nrate = 100 Hz\n[site]\ngravity = 9.81 m/s^2\n[log]\nfile = imu.csv\n"
                   "format = custom\ncolumns = ax ay az gx gy gz\n");
  const Session s = Session::load(dir + "/session.ini", Session::PlanNeed::Optional);
  CHECK_FALSE(s.has_plan);
  CHECK_FALSE(s.has_site);
  CHECK(s.gravity == Approx(9.81));
  try {
    Session::load(dir + "/session.ini");
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK(std::string(e.what()).find("session.ini:5: 'site.gravity'") == std::string::npos);
    CHECK(std::string(e.what()).find("has no 'plan'") != std::string::npos);
    CHECK(std::string(e.what()).find("table-free") != std::string::npos);
  }
  test::write_file(dir + "/bad.ini",
                   "[session]\nrate = 100 Hz\n[site]\ngravity = 98.1 m/s^2\n[log]\nfile = imu.csv\n"
                   "format = custom\ncolumns = ax ay az gx gy gz\n");
  CHECK_THROWS_WITH(
      Session::load(dir + "/bad.ini", Session::PlanNeed::Optional),
      Catch::Contains("bad.ini:4: 'site.gravity'") && Catch::Contains("within 9.7 and 9.9"));
}

TEST_CASE("Table-free run of a simulated hand-held session in raw counts",
          "[handheld][table_free]") {
  const std::string dir = test::temp_dir("handheld_run");
  const ImuErrorModel truth = mems().draw(11);
  const std::string path = write_session(dir, truth, 5, 36);
  const Session session = Session::load(path, Session::PlanNeed::Optional);
  TableFreeRunOptions o;
  const TableFreeRun run = run_table_free(session, o);
  REQUIRE(run.result.converged);
  CHECK(run.poses.size() == 37);
  CHECK(run.gravity_from == "normal gravity at the site");
  CHECK(run.accel_counts);
  CHECK(run.gyro_counts);
  // Every coefficient within 4 sigma of the truth (accelerometer-triad frame, relative to the
  // nominal conversion the counts were made with): 21 estimates, chance of a miss about 0.1 %.
  const auto t = in_accel_triad_frame(truth).coefficients();
  const ResultCoefficients c = result_coefficients(run);
  REQUIRE(c.size() == 24);
  for (const auto& [name, e] : c) {
    if (e.fixed_by_convention) continue;
    CAPTURE(name, e.value, *e.sigma, t.at(name));
    CHECK(std::abs(e.value - t.at(name)) < 4.0 * *e.sigma);
  }
  // The pose statistics are in SI: at rest the mean specific force is g within the sensor's
  // errors (scale factors up to 3 %, biases up to 40 mg on each axis).
  for (const auto& p : run.poses) CHECK(p.accel_mean.norm() == Approx(9.806).epsilon(0.1));

  // The raw view by the sensors' axes, against the counts' truth.
  const auto raw = raw_entries(run);
  REQUIRE(raw.size() == 18);
  for (const auto& e : raw) {
    if (!e.has_sigma) continue;
    const bool accel = e.name[0] == 'a';
    const int i = e.name.back() - 'x';
    const std::string triad = accel ? "accel" : "gyro";
    const auto& info_k = coefficient_info(triad + ".scale." + e.name.substr(e.name.size() - 1));
    const auto& info_b = coefficient_info(triad + ".bias." + e.name.substr(e.name.size() - 1));
    const double s0 = accel ? 400.0 : 4800.0;
    const double k = t.at(info_k.name) * info_k.si_per_unit;
    const double b = t.at(info_b.name) * info_b.si_per_unit;
    const bool sensitivity = e.name.find(".sensitivity.") != std::string::npos;
    const double want = sensitivity ? s0 * (1.0 + k) : 32768.0 + s0 * b;
    CAPTURE(e.name, e.value, e.sigma, want, i);
    CHECK(std::abs(e.value - want) < 4.0 * e.sigma);
    CHECK(e.unit == (sensitivity ? (accel ? "counts/(m/s^2)" : "counts/(rad/s)") : "counts"));
  }

  // Validation on another session of the same unit: corrected beats nominal.
  const std::string vdir = test::temp_dir("handheld_validation");
  const Session v = Session::load(write_session(vdir, truth, 6, 12), Session::PlanNeed::Optional);
  TableFreeRun with = run;
  with.validations.push_back(validate_table_free(v, run, o.detector));
  const HandheldValidation& val = with.validations.front();
  CHECK(val.poses.size() == 13);
  CHECK(val.turns.size() == 12);
  CHECK(val.gravity_rms_calibrated < 0.2 * val.gravity_rms_nominal);
  CHECK(val.rate_rms_calibrated < 0.2 * val.rate_rms_nominal);
  CHECK(val.turn_rms_calibrated < 0.5 * val.turn_rms_nominal);

  // The result file: the common coefficient schema and the table-free sections.
  write_result_json(dir + "/result.json", c, result_sections(with));
  std::ifstream in(dir + "/result.json");
  const auto j = nlohmann::json::parse(in);
  CHECK(j.at("method").at("name") == "table-free");
  CHECK(j.at("method").at("dof").get<int>() == run.result.dof);
  CHECK(j.at("pose_detection").at("poses_found") == 37);
  CHECK(j.at("poses").size() == 37);
  CHECK(j.at("poses")[3].contains("fit"));
  CHECK(j.at("raw").at("gyro.sensitivity.y").at("unit") == "counts/(rad/s)");
  CHECK(j.at("raw").at("accel.offset.z").contains("sigma"));
  CHECK(j.at("validation")[0].at("poses") == 13);
  CHECK(j.at("coefficients").at("accel.misalignment.xy").at("fixed_by_convention") == true);
  // Read back as a result file (compare, summaries).
  CHECK(read_result_json(dir + "/result.json").size() == 24);

  // Allan deviation of the longest pose (the 50 s at the start): the white noise the session
  // was made with, within the estimate's spread.
  AllanRunOptions ao;
  ao.selection = AllanSelection::LongestPose;
  const AllanRun an = run_allan(session, ao);
  CHECK(an.pose == 1);
  CHECK(an.t_end - an.t_start > 45.0);
  for (int i = 0; i < 3; ++i) {
    CHECK(an.analysis.gyro_fit[static_cast<std::size_t>(i)].white ==
          Approx(mems().noise.gyro.white).epsilon(0.2));
    CHECK(an.analysis.accel_fit[static_cast<std::size_t>(i)].white ==
          Approx(mems().noise.accel.white).epsilon(0.2));
  }
  ao.selection = AllanSelection::All;
  ao.require_static = true;
  CHECK_THROWS_WITH(run_allan(session, ao), Catch::Contains("the record is not static"));
  ao.selection = AllanSelection::Pose;
  ao.pose = 38;
  CHECK_THROWS_WITH(run_allan(session, ao), Catch::Contains("found 37 poses"));
}
