// Every value checked where it is read: sites, plan section numbers, session keys and sections,
// sensor noise and ranges, log values beyond any sensor, logs without samples. Each error names
// the file, the line and the key or cause.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "helpers.hpp"
#include "models/config.hpp"
#include "models/earth.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "rig/io/log_io.hpp"
#include "rig/plan.hpp"
#include "rig/session.hpp"

using namespace sinscal;
using Catch::Contains;

namespace {

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The message of a ConfigError thrown by `f` ("no error" if none; another exception type fails).
template <class F>
std::string config_error(F f) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

const std::string kOrientationPlan =
    "[plan]\ntype = orientations\nmove_rate = 15\nmove_acceleration = 15\n"
    "[orientation.1]\nheading = 0\npitch = 0\nroll = 0\ndwell = 10\n";

std::string plan_error(const std::string& text) {
  return config_error([&] { Plan::parse("p.ini", text); });
}

// All samples of a log; the error message if reading throws.
std::string read_error(const LogFormat& f, std::size_t* samples = nullptr,
                       std::size_t* skipped = nullptr) {
  try {
    LogReader r(f);
    if (skipped) r.skip_bad_samples([&](const BadSampleError&) { ++*skipped; });
    std::size_t n = 0;
    for (ImuSample s; r.next(s);) ++n;
    if (samples) *samples = n;
  } catch (const LogError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST_CASE("Site bounds: latitude, longitude, height", "[input][earth]") {
  CHECK(latitude_problem(55.75 * units::deg).empty());
  CHECK(latitude_problem(89.0 * units::deg).empty());
  CHECK(latitude_problem(-89.0 * units::deg).empty());
  CHECK_THAT(latitude_problem(89.001 * units::deg), Contains("within -89 and 89 deg"));
  CHECK_THAT(latitude_problem(90.0 * units::deg), Contains("got 90 deg"));
  CHECK_FALSE(latitude_problem(55.75).empty());  // 55.75 rad
  CHECK_FALSE(latitude_problem(std::nan("")).empty());
  CHECK(longitude_problem(-360.0 * units::deg).empty());
  CHECK_FALSE(longitude_problem(361.0 * units::deg).empty());
  CHECK(height_problem(-12000.0).empty());
  CHECK(height_problem(100000.0).empty());
  CHECK_FALSE(height_problem(-12001.0).empty());
  CHECK_THAT(height_problem(1e9), Contains("got 1e+09 m"));
}

TEST_CASE("Plan: the site within bounds, named by line and key", "[input][plan]") {
  CHECK(plan_error(kOrientationPlan + "[site]\nlatitude = 89 deg\n") == "no error");
  for (const char* lat : {"90 deg", "1000 deg", "55.75 rad", "-89.5"}) {
    CAPTURE(lat);
    CHECK_THAT(plan_error(kOrientationPlan + "[site]\nlatitude = " + lat + "\n"),
               Contains("p.ini:11: 'site.latitude'") && Contains("within -89 and 89 deg"));
  }
  CHECK_THAT(plan_error(kOrientationPlan + "[site]\nlatitude = 45\nheight = 1e9 m\n"),
             Contains("p.ini:12: 'site.height'") && Contains("-12000 and 100000 m"));
  CHECK_THAT(plan_error(kOrientationPlan + "[site]\nlatitude = 45\nlongitude = 400 deg\n"),
             Contains("p.ini:12: 'site.longitude'"));
  CHECK_THAT(plan_error(kOrientationPlan + "[site]\nheight = 150 m\n"),
             Contains("p.ini:11") && Contains("without 'latitude'"));
}

TEST_CASE("Plan: section numbers are digits only, checked before any conversion", "[input][plan]") {
  for (const char* n : {"+1", "01", "99999999999", "1e3", "-1", "0", "1 2", "x"}) {
    CAPTURE(n);
    const std::string text =
        kOrientationPlan + "[orientation." + n + "]\nheading = 0\npitch = 0\nroll = 0\ndwell = 5\n";
    CHECK_THAT(plan_error(text),
               Contains("p.ini:11: section [orientation.") && Contains("expected [orientation.N]"));
  }
  const std::string rot =
      "[plan]\ntype = rotations\nrotation_acceleration = 10\n"
      "[start]\nheading = 0\npitch = 0\nroll = 0\ndwell = 10\n"
      "[step.+1]\naxis = +x\nangle = 90\nduration = 9\n";
  CHECK_THAT(plan_error(rot), Contains("p.ini:10: section [step.+1]"));
  // An empty section has no line to name; the file and section still are.
  CHECK_THAT(plan_error(kOrientationPlan + "[orientation.+2]\n"),
             Contains("p.ini: section [orientation.+2]"));
  CHECK_THAT(plan_error("[plan]\ntype = rotations\nrotation_acceleration = 10\n"
                        "[start]\nheading = 0\npitch = 0\nroll = 0\ndwell = -10 s\n"
                        "[rotations]\naxes = +x\nangle = 90\nduration = 9\n"),
             Contains("p.ini:8: 'start.dwell'") && Contains("must be positive"));
}

TEST_CASE("Plan::load: an empty name or a directory is refused by name", "[input][plan]") {
  CHECK_THAT(config_error([] { Plan::load(""); }), Contains("no file name given"));
  const std::string dir = test::temp_dir("input_plan_dir");
  CHECK_THAT(config_error([&] { Plan::load(dir); }), Contains("is a directory"));
}

TEST_CASE("Session: keys, sections, files and the site checked with file and line",
          "[input][session]") {
  const std::string dir = test::temp_dir("input_session");
  std::filesystem::copy_file(test::source_path("config/plans/seed8.ini"), dir + "/plan.ini");
  test::write_file(dir + "/imu.csv", "");
  const std::string path = dir + "/session.ini";
  auto error_of = [&](const std::string& session, const std::string& rest) {
    test::write_file(
        path, "[session]\nrate = 100 Hz\n" + session + "\n" + rest + "[log]\nfile = imu.csv\n");
    return config_error([&] { Session::load(path); });
  };
  CHECK(error_of("plan = plan.ini", "") == "no error");
  CHECK(error_of("plan = plan.ini", "[site]\nlatitude = -89 deg\nheight = -11000 m\n") ==
        "no error");
  for (const char* lat : {"90", "1000 deg", "55.75 rad"}) {
    CAPTURE(lat);
    CHECK_THAT(error_of("plan = plan.ini", std::string("[site]\nlatitude = ") + lat + "\n"),
               Contains("session.ini:5: 'site.latitude'") && Contains("within -89 and 89 deg"));
  }
  CHECK_THAT(error_of("plan = plan.ini", "[site]\nlatitude = 45\nheight = 1e9 m\n"),
             Contains("session.ini:6: 'site.height'"));
  // Height without latitude would silently take the plan's whole site.
  CHECK_THAT(error_of("plan = plan.ini", "[site]\nheight = 1e3 m\n"),
             Contains("session.ini:5") && Contains("without 'latitude'"));
  // The empty plan key of the fuzzing run: session.ini, its line and the key.
  CHECK_THAT(error_of("plan =", ""),
             Contains("session.ini:3: 'session.plan'") && Contains("no file name given"));
  CHECK_THAT(error_of("plan = nope.ini", ""),
             Contains("session.ini:3: 'session.plan'") && Contains("'nope.ini': no such file"));
  // A file name the system refuses (longer than NAME_MAX; found by fuzzing): a ConfigError
  // naming the key, not a std::filesystem error.
  const std::string too_long(5000, 'n');
  CHECK_THAT(error_of("plan = " + too_long, ""),
             Contains("session.ini:3: 'session.plan'") && Contains("no such file"));
  CHECK_THAT(error_of("plan = plan.ini\ntruth = " + too_long, ""),
             Contains("session.ini:4: 'session.truth'") && Contains("no such file"));
  CHECK_THAT(error_of("plan = plan.ini\ntruth = truth.json", ""),
             Contains("session.ini:4: 'session.truth'") && Contains("no such file"));
  CHECK_THAT(error_of("plan = plan.ini\nsensor =", ""),
             Contains("session.ini:4: 'session.sensor'") && Contains("no file name given"));
  CHECK_THAT(error_of("", ""), Contains("session.ini") && Contains("no 'plan'"));
  CHECK_THAT(error_of("plan = plan.ini", "[sites]\nlatitude = 45\n"),
             Contains("session.ini:5") && Contains("unknown section [sites]"));
  CHECK_THAT(error_of("plan = plan.ini", "[extra]\n"), Contains("unknown section [extra]"));
  CHECK_THAT(error_of("plan = plan.ini\ntime_offset = 1e300 s", ""),
             Contains("session.ini:4: 'session.time_offset'"));
  test::write_file(path, "[session]\nrate = 1e9 Hz\nplan = plan.ini\n[log]\nfile = imu.csv\n");
  CHECK_THAT(config_error([&] { Session::load(path); }),
             Contains("session.ini:2: 'session.rate'") && Contains("100 kHz"));
}

TEST_CASE("Session: the fuzzing run's reproducers name session.ini, the line and the key",
          "[input][session][fuzz]") {
  const std::string dir = test::temp_dir("input_fuzz_session");
  std::filesystem::copy_file(test::source_path("config/plans/seed8.ini"), dir + "/plan.ini");
  const std::string crashes = test::source_path("tests/fuzz/crashes/fuzz_session/");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"log-time-unit-error-without-file.ini", ":9: 'log.time_unit'"},
      {"log-table-unit-error-without-file.ini", ":9: 'log.table_unit'"},
      {"empty-plan-key-error-without-file.ini", ":3: 'session.plan'"}};
  for (const auto& [file, expected] : cases) {
    CAPTURE(file);
    test::write_file(dir + "/session.ini", file_text(crashes + file));
    const std::string message = config_error([&] { Session::load(dir + "/session.ini"); });
    CHECK(message.rfind(dir + "/session.ini", 0) == 0);  // starts with the file
    CHECK_THAT(message, Contains(expected));
  }
}

TEST_CASE("Sensor profile: noise, quanta and ranges not negative, correlation time positive",
          "[input][sensor]") {
  const std::string dir = test::temp_dir("input_sensor");
  auto error_of = [&](const std::string& text) {
    test::write_file(dir + "/s.ini", "[sensor]\nname = x\n" + text);
    return config_error([&] { SensorProfile::load(dir + "/s.ini"); });
  };
  CHECK(error_of("[gyro]\narw = 0.001\nrange = 400\n") == "no error");
  for (const char* key : {"arw", "bias_instability", "rate_random_walk", "quantum", "range"}) {
    CAPTURE(key);
    CHECK_THAT(
        error_of(std::string("[gyro]\n") + key + " = -1\n"),
        Contains("s.ini:4: 'gyro." + std::string(key) + "'") && Contains("must not be negative"));
  }
  for (const char* key : {"vrw", "bias_instability", "random_walk", "quantum", "range"}) {
    CAPTURE(key);
    CHECK_THAT(error_of(std::string("[accel]\n") + key + " = -0.5\n"),
               Contains("s.ini:4: 'accel." + std::string(key) + "'"));
  }
  CHECK_THAT(error_of("[accel]\ncorrelation_time = 0 s\n"),
             Contains("s.ini:4: 'accel.correlation_time'") && Contains("must be positive"));
}

TEST_CASE("Log: values beyond any sensor are bad samples naming file, line and cause",
          "[input][log]") {
  const std::string dir = test::temp_dir("input_log_values");
  const std::string path = dir + "/imu.csv";
  const std::string header =
      "# sinscal IMU log, format 1: increments over (t - dt, t], body axes\n# rate_hz = 100\n"
      "t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],dv_y [m/s],dv_z [m/s]\n";
  const std::string good = "0.01,0,0,0,0,0,0.098\n0.02,0,0,0,0,0,0.098\n";
  const LogFormat native = LogFormat::native_format(path, 100.0);

  test::write_file(path, header + good);
  CHECK(read_error(native) == "no error");
  // A rate of 1e4 rad/s (increment 100 rad at 100 Hz) is within the bound; 1e300 is not.
  test::write_file(path, header + good + "0.03,100,0,0,0,0,0.098\n");
  CHECK(read_error(native) == "no error");
  test::write_file(path, header + good + "0.03,0,1e300,0,0,0,0.098\n");
  CHECK_THAT(read_error(native),
             Contains("imu.csv:6: gyro log axis y reads 1e+300") && Contains("beyond any sensor"));
  test::write_file(path, header + good + "0.03,0,0,0,0,0,-1e300\n");
  CHECK_THAT(read_error(native), Contains("imu.csv:6: accel log axis z") && Contains("m/s^2"));
  // Just beyond 1e6 m/s^2 over a 0.01 s interval.
  test::write_file(path, header + good + "0.03,0,0,0,10001,0,0\n");
  CHECK_THAT(read_error(native), Contains("imu.csv:6: accel log axis x"));
  test::write_file(path, header + good + "1e300,0,0,0,0,0,0.098\n");
  CHECK_THAT(read_error(native), Contains("imu.csv:6: time t = 1e+300 s is beyond 1e10 s"));
  // The first sample's time is checked too (no difference to catch it).
  test::write_file(path, header + "1e300,0,0,0,0,0,0.098\n");
  CHECK_THAT(read_error(native), Contains("imu.csv:4: time t = 1e+300 s"));

  // Bad samples can be skipped; the reading goes on.
  test::write_file(path, header + good + "0.03,0,1e300,0,0,0,0.098\n0.04,0,0,0,0,0,0.098\n");
  std::size_t n = 0, skipped = 0;
  CHECK(read_error(native, &n, &skipped) == "no error");
  CHECK(n == 3);
  CHECK(skipped == 1);

  // Table angles.
  const std::string table_header =
      header.substr(0, header.size() - 1) + ",outer [deg],inner [deg]\n";
  test::write_file(path, table_header + "0.01,0,0,0,0,0,0.098,0,0\n0.02,0,0,0,0,0,0.098,1e300,0\n");
  CHECK_THAT(read_error(native), Contains("imu.csv:5: table angle"));
}

TEST_CASE("Log: a time column reaching infinity through its unit is a bad sample", "[input][log]") {
  const std::string dir = test::temp_dir("input_log_time");
  test::write_file(dir + "/s.ini",
                   "[log]\nfile = f.txt\nformat = custom\ncolumns = t gx gy gz ax ay az\n"
                   "time_unit = h\n");
  test::write_file(dir + "/f.txt", "1e-6,0,0,0,0,0,0.098\n1.7e308,0,0,0,0,0,0.098\n");
  const LogFormat f = LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0);
  CHECK_THAT(read_error(f), Contains("f.txt:2: time t = inf s"));
}

TEST_CASE("Log: a log without samples says so, naming the file", "[input][log]") {
  const std::string dir = test::temp_dir("input_log_empty");
  const std::string path = dir + "/imu.csv";
  test::write_file(path,
                   "# sinscal IMU log, format 1: increments over (t - dt, t], body axes\n"
                   "t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],dv_y "
                   "[m/s],dv_z [m/s]\n# nothing\n\n");
  const LogFormat native = LogFormat::native_format(path, 100.0);
  const std::string message = read_error(native);
  CHECK_THAT(message, Contains("imu.csv:4: no samples"));
  CHECK_THAT(message, !Contains("1e+300"));
  // Every sample bad and skipped.
  test::write_file(path,
                   "t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],dv_y "
                   "[m/s],dv_z [m/s]\n0.01,nan,0,0,0,0,0\n0.02,x,0,0,0,0,0\n");
  std::size_t skipped = 0;
  CHECK_THAT(read_error(native, nullptr, &skipped),
             Contains("imu.csv:3: no good samples: all 2 samples were bad"));
  CHECK(skipped == 2);
  // From a stream.
  std::istringstream in(
      "t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],dv_y [m/s],dv_z [m/s]\n");
  LogFormat f = native;
  f.file = "<stdin>";
  LogReader r(in, f);
  ImuSample s;
  CHECK_THROWS_WITH(r.next(s), Contains("<stdin>:1: no samples"));
}

TEST_CASE("Log configuration: a scale or max_gap no sensor or log has is refused at its line",
          "[input][log]") {
  const std::string dir = test::temp_dir("input_log_config");
  const std::string head = "[log]\nfile = f.txt\nformat = custom\ncolumns = t gx gy gz ax ay az\n";
  auto error_of = [&](const std::string& extra) {
    test::write_file(dir + "/s.ini", head + extra);
    return config_error([&] { LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0); });
  };
  CHECK(error_of("gyro = rate\ngyro_unit = deg/s\ngyro_scale = 0.0076335877862595417\n") ==
        "no error");
  CHECK_THAT(error_of("gyro = rate\ngyro_scale = 1e300\n"),
             Contains("s.ini:6: 'log.gyro_scale'") && Contains("beyond any sensor"));
  // Increments: one count of 1e5 rad over 0.01 s is 1e7 rad/s.
  CHECK_THAT(error_of("gyro_scale = 1e5\n"), Contains("s.ini:5: 'log.gyro_scale'"));
  CHECK(error_of("gyro_scale = 1e3\n") == "no error");
  CHECK_THAT(error_of("accel = rate\naccel_unit = g\naccel_scale = 1e6\n"),
             Contains("s.ini:7: 'log.accel_scale'") && Contains("m/s^2"));
  CHECK_THAT(error_of("max_gap = 1e300\n"),
             Contains("s.ini:5: 'log.max_gap'") && Contains("1 to 1000"));
  CHECK(error_of("max_gap = 1000\n") == "no error");
  CHECK_THAT(error_of("header_lines = -1\n"), Contains("s.ini:5: 'log.header_lines'"));
}

TEST_CASE("Log: a native log's last line without a line end was cut", "[input][log]") {
  const std::string dir = test::temp_dir("input_log_cut");
  const std::string path = dir + "/imu.csv";
  const std::string header =
      "t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],dv_y [m/s],dv_z [m/s]\n";
  // The last number cut short still reads as a number: only the missing line end tells.
  test::write_file(path, header + "0.01,0,0,0,0,0,0.0980665\n0.02,0,0,0,0,0,0.098");
  CHECK_THAT(read_error(LogFormat::native_format(path, 100.0)),
             Contains("imu.csv:3: truncated line"));
  test::write_file(path, header + "0.01,0,0,0,0,0,0.0980665\n0.02,0,0,0,0,0,0.098\n");
  CHECK(read_error(LogFormat::native_format(path, 100.0)) == "no error");
  // A complete last line without its line end (a logger that does not end it) is a line.
  test::write_file(path, header + "0.01,0,0,0,0,0,0.0980665\n0.02,0,0,0,0,0,0.0980671");
  CHECK(read_error(LogFormat::native_format(path, 100.0)) == "no error");
  // Round-trip numbers vary in length line to line: a shorter one past 12 digits is complete.
  test::write_file(
      path, header + "0.01,0,0,0,0,0,0.09806650000000012\n0.02,0,0,0,0,0,0.0980665000000001");
  CHECK(read_error(LogFormat::native_format(path, 100.0)) == "no error");
  // A foreign log may lack the last line end (hand-written files often do).
  test::write_file(dir + "/s.ini",
                   "[log]\nfile = f.txt\nformat = custom\ncolumns = t gx gy gz ax ay az\n");
  test::write_file(dir + "/f.txt", "0.01,0,0,0,0,0,0.098\n0.02,0,0,0,0,0,0.098");
  CHECK(read_error(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0)) == "no error");
}

TEST_CASE("Plan: a bad rotation axis is named as written", "[input][plan]") {
  const std::string rot =
      "[plan]\ntype = rotations\nrotation_acceleration = 10\n"
      "[start]\nheading = 0\npitch = 0\nroll = 0\ndwell = 10\n"
      "[rotations]\nangle = 90\nduration = 9\naxes = +y ";
  for (const char* axis : {"+w", "y", "+outer2", "-", "+"}) {
    CAPTURE(axis);
    CHECK_THAT(plan_error(rot + axis + "\n"),
               Contains("p.ini:12: 'rotations.axes': axis '" + std::string(axis) + "'"));
  }
  CHECK(plan_error(rot + "-inner\n") == "no error");
}
