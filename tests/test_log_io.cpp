#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "helpers.hpp"
#include "models/config.hpp"
#include "models/units.hpp"
#include "rig/io/log_io.hpp"

using namespace sinscal;
using Eigen::Vector3d;

namespace {
std::vector<ImuSample> some_samples(int n) {
  std::vector<ImuSample> v;
  for (int k = 1; k <= n; ++k) {
    ImuSample s;
    s.t = k * 0.01;
    s.dt = 0.01;
    s.dtheta_b = Vector3d(1e-7 * k, -3.3e-6 / k, 0.1 / 3.0);
    s.dv_b = Vector3d(0.0981 / 7.0, -1e-5, 0.0980665 + 1e-12 * k);
    v.push_back(s);
  }
  return v;
}

std::string native_text(int n) {
  const std::string dir = test::temp_dir("native_text");
  LogWriter w(dir + "/imu.csv", 100.0);
  for (const auto& s : some_samples(n)) w.write(s);
  w.close();
  std::ifstream in(dir + "/imu.csv");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Reads a whole native log; returns the error message ("" if none).
std::string read_error(const std::string& path) {
  try {
    LogReader r(LogFormat::native_format(path, 100.0));
    ImuSample s;
    while (r.next(s)) {
    }
  } catch (const LogError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST_CASE("Log: native CSV round trip is exact", "[log]") {
  const std::string dir = test::temp_dir("log_roundtrip");
  const auto in = some_samples(1000);
  LogWriter w(dir + "/imu.csv", 100.0);
  for (const auto& s : in) w.write(s);
  w.close();
  LogReader r(LogFormat::native_format(dir + "/imu.csv", 100.0));
  ImuSample s;
  std::size_t k = 0;
  while (r.next(s)) {
    REQUIRE(k < in.size());
    CHECK(s.t == in[k].t);
    CHECK(s.dtheta_b == in[k].dtheta_b);
    CHECK(s.dv_b == in[k].dv_b);
    ++k;
  }
  CHECK(k == in.size());
}

TEST_CASE("Log: each kind of bad line is an error naming file, line and cause", "[log]") {
  const std::string dir = test::temp_dir("log_bad");
  const std::string good = native_text(20);  // 3 header lines, then data lines 4..23
  std::vector<std::string> lines;
  {
    std::istringstream in(good);
    for (std::string l; std::getline(in, l);) lines.push_back(l);
  }
  auto with = [&](int line, const std::string& replacement, bool drop_rest = false) {
    std::string out;
    for (int i = 0; i < static_cast<int>(lines.size()); ++i) {
      if (i + 1 == line) {
        out += replacement;
        if (drop_rest) return out;  // no newline at the end: the file stops mid-line
        out += "\n";
      } else {
        out += lines[i] + "\n";
      }
    }
    return out;
  };
  struct Case {
    std::string name, text, expect;
  };
  const std::string l10 = lines[9];
  const std::vector<Case> cases = {
      {"truncated", with(10, l10.substr(0, l10.size() / 2), true), "imu.csv:10: truncated line"},
      {"nonnumeric", with(10, "0.1,abc,0,0,0,0,0"), "imu.csv:10: field 2 'abc' is not a number"},
      {"nan", with(10, "0.1,nan,0,0,0,0,0"), "imu.csv:10: field 2 is NaN"},
      {"backwards", with(10, "0.05,0,0,0,0,0,0"), "imu.csv:10: time goes backwards"},
      // A time ahead at the end of the log is a gap; followed by the times before it, it is one
      // sample out of order: time goes backwards on the next line.
      {"gap", with(10, "0.5,0,0,0,0,0,0\n", true), "imu.csv:10: gap in the data"},
      {"ahead", with(10, "0.5,0,0,0,0,0,0"), "imu.csv:11: time goes backwards"},
      {"columns", with(10, l10 + ",7"), "imu.csv:10: expected 7 fields, found 8"},
      {"header", with(3, "t,a,b"), "imu.csv:3: not a sinscal log"},
  };
  for (const auto& c : cases) {
    const std::string path = dir + "/" + c.name + "_imu.csv";
    test::write_file(path, c.text);
    CAPTURE(c.name);
    CHECK_THAT(read_error(path), Catch::Contains(c.expect.substr(c.expect.find(':'))) &&
                                     Catch::Contains(c.name + "_imu.csv:"));
  }
  CHECK_THAT(read_error(dir + "/missing.csv"), Catch::Contains("missing.csv:0: cannot open"));
  test::write_file(dir + "/good.csv", good);
  CHECK(read_error(dir + "/good.csv").empty());
}

TEST_CASE("Log: table-angle columns, native and foreign", "[log][table]") {
  const std::string dir = test::temp_dir("log_table");
  auto in = some_samples(50);
  for (auto& s : in) {
    s.has_table = true;
    s.table_outer = 0.37 * s.t;
    s.table_inner = -1.1 + s.t;
  }
  LogWriter w(dir + "/imu.csv", 100.0, true);
  for (const auto& s : in) w.write(s);
  w.close();
  LogReader r(LogFormat::native_format(dir + "/imu.csv", 100.0));
  std::size_t k = 0;
  for (ImuSample s; r.next(s); ++k) {
    REQUIRE(s.has_table);
    // Written in degrees, shortest round trip: back to the radian value within rounding.
    CHECK(s.table_outer == Approx(in[k].table_outer).epsilon(1e-15));
    CHECK(s.table_inner == Approx(in[k].table_inner).epsilon(1e-15));
  }
  CHECK(k == in.size());
  // A writer that declares the columns refuses a sample without them (no silent zeros).
  LogWriter w2(dir + "/imu2.csv", 100.0, true);
  CHECK_THROWS_AS(w2.write(some_samples(1).front()), std::invalid_argument);
  // Foreign: angles in arcsec, in any column order; one of the pair alone is an error.
  test::write_file(dir + "/f.txt", "0.01,3600,0,0,0,0,0,0,-7200\n");
  test::write_file(dir + "/s.ini",
                   "[log]\nfile = f.txt\nformat = custom\ncolumns = t outer gx gy gz ax ay az "
                   "inner\ntable_unit = arcsec\n");
  LogReader f(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0));
  ImuSample s;
  REQUIRE(f.next(s));
  CHECK(s.has_table);
  CHECK(s.table_outer == Approx(1.0 * units::deg));
  CHECK(s.table_inner == Approx(-2.0 * units::deg));
  test::write_file(dir + "/one.ini",
                   "[log]\nfile = f.txt\nformat = custom\ncolumns = t outer gx gy gz ax ay az\n");
  CHECK_THROWS_WITH(LogFormat::from_ini(IniFile(dir + "/one.ini"), dir, 100.0),
                    Catch::Contains("both table-angle columns"));
}

TEST_CASE("Log: foreign formats (counts, rates, delimiters, axis mapping)", "[log]") {
  const std::string dir = test::temp_dir("log_foreign");
  // Whitespace separated, time in ms, gyro rates in raw counts about an offset, accelerometer
  // increments in mm/s; body x = -log y, body y = log x, body z = log z.
  test::write_file(dir + "/f.txt",
                   "some header\nmore header\n"
                   "10  100 200 300  1000 2000 3000\n"
                   "20  100 200 300  1000 2000 3000\n");
  test::write_file(
      dir + "/s.ini",
      "[log]\nfile = f.txt\nformat = custom\ndelimiter = whitespace\nheader_lines = 2\n"
      "columns = t gx gy gz ax ay az\ntime_unit = ms\n"
      "gyro = rate\ngyro_unit = deg/s\ngyro_scale = 0.5\ngyro_offset = 100\n"
      "gyro_axes = -y x z\naccel = increment\naccel_unit = mm/s\naccel_axes = -y x z\n");
  const IniFile ini(dir + "/s.ini");
  LogReader r(LogFormat::from_ini(ini, dir, 100.0));
  ImuSample s;
  REQUIRE(r.next(s));
  REQUIRE(r.next(s));
  CHECK(s.t == Approx(0.02));
  CHECK(s.dt == Approx(0.01));
  CHECK(s.dtheta_b.x() == Approx(-(200 - 100) * 0.5 * units::deg * 0.01));
  CHECK(s.dtheta_b.y() == Approx(0.0).margin(1e-15));
  CHECK(s.dtheta_b.z() == Approx((300 - 100) * 0.5 * units::deg * 0.01));
  CHECK(s.dv_b.x() == Approx(-2.0));
  CHECK(s.dv_b.y() == Approx(1.0));
  CHECK(s.dv_b.z() == Approx(3.0));
  CHECK_FALSE(r.next(s));
  // A bad key value is a configuration error naming the line.
  test::write_file(dir + "/bad.ini",
                   "[log]\nfile = f.txt\nformat = custom\ncolumns = t gx\ngyro_axes = x x z\n");
  CHECK_THROWS_WITH(LogFormat::from_ini(IniFile(dir + "/bad.ini"), dir, 100.0),
                    Catch::Contains("bad.ini:5"));
}

TEST_CASE("Log: the real MPU-6050 recording reads with its documented format", "[log][data]") {
  const std::string file = test::source_path("data/mpu6050-handheld/imu_static_test.csv");
  REQUIRE(std::filesystem::exists(file));
  const std::string dir = test::temp_dir("log_mpu");
  test::write_file(dir + "/s.ini",
                   "[log]\nfile = " + file +
                       "\nformat = custom\nheader_lines = 5\n"
                       "columns = ax ay az gx gy gz\ngyro = rate\ngyro_unit = deg/s\n"
                       "gyro_scale = 0.0076335877862595417\naccel = rate\naccel_unit = g\n"
                       "accel_scale = 0.00006103515625\n");
  LogReader r(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0));
  ImuSample s;
  Vector3d sum_v = Vector3d::Zero();
  std::size_t n = 0;
  while (r.next(s)) {
    sum_v += s.dv_b;
    ++n;
  }
  CHECK(n == 9991 - 5);
  // Static: the mean specific force is gravity within the part's uncalibrated tolerances
  // (MPU-6050 datasheet: zero-g offset up to 80 mg on Z, sensitivity 3 %): 0.11 g in all.
  // This recording reads 0.912 g: an offset the calibration has to find.
  const double f = (sum_v / (static_cast<double>(n) * 0.01)).norm();
  CHECK(std::abs(f - 9.81) < 0.11 * units::g0);
}
