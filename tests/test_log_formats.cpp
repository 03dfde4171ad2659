// Log formats labs and tools produce: a log split over one file per triad (imu_tk), one file per
// dwell of the plan, NovAtel RAWIMUSA / RAWIMUSXA ASCII logs; limits of the line reader;
// temperature columns in every format that has them, and their checks.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

#include "filter/closed_form/closed_form.hpp"
#include "filter/kalman/kalman_calibrator.hpp"
#include "helpers.hpp"
#include "models/config.hpp"
#include "models/units.hpp"
#include "report/result.hpp"
#include "rig/io/log_io.hpp"
#include "rig/session.hpp"

using namespace sinscal;
using Eigen::Vector3d;

namespace {

std::string data_path(const std::string& relative) {
  return test::source_path("tests/data/" + relative);
}

std::vector<ImuSample> read_all(LogReader& r) {
  std::vector<ImuSample> out;
  for (ImuSample s; r.next(s);) out.push_back(s);
  return out;
}

// The message of the error reading a whole log throws ("" if none).
template <class Make>
std::string read_error(Make make) {
  try {
    LogReader r = make();
    read_all(r);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

std::string config_error(const std::string& ini_path, const std::string& dir) {
  try {
    LogFormat::from_ini(IniFile(ini_path), dir, 100.0);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

std::string file_text(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

const char* kSplitKeys =
    "format = custom\ndelimiter = whitespace\n"
    "gyro = rate\ngyro_unit = rad/s\ngyro_scale = 0.00020833333333333335\ngyro_offset = 32768\n"
    "accel = rate\naccel_unit = m/s^2\naccel_scale = 0.0025\naccel_offset = 32768\n";

}  // namespace

TEST_CASE("Split log: one file per triad, rows paired by time", "[log][split]") {
  const std::string dir = test::temp_dir("h2_split");
  // Paths relative to the session file's directory.
  const std::string rel = std::filesystem::relative(data_path("split"), dir).string();
  test::write_file(dir + "/s.ini", "[log]\naccel_file = " + rel + "/acc.txt\ngyro_file = " + rel +
                                       "/gyro.txt\n" + kSplitKeys);
  const LogFormat f = LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0);
  CHECK(f.split());
  LogReader r(f);
  const auto s = read_all(r);
  REQUIRE(s.size() == 20);
  // acc.txt row k: x = 32768 + 400 + k, y = 32768 - 800, z = 32768 + 3924 counts; gyro.txt row
  // k: x = 32768 + 48 (k odd), y = 32768 - 96, z = 32768 + 4800.
  for (std::size_t k = 1; k < s.size(); ++k) {
    CAPTURE(k);
    CHECK(s[k].t == Approx(0.02984 + 0.01 * static_cast<double>(k) + (k % 3 == 1 ? 2e-5 : 0.0)));
    const double dt = s[k].dt;
    CHECK(s[k].dv_b.x() == Approx((400.0 + static_cast<double>(k)) * 0.0025 * dt));
    CHECK(s[k].dv_b.y() == Approx(-800 * 0.0025 * dt));
    CHECK(s[k].dv_b.z() == Approx(3924 * 0.0025 * dt));
    CHECK(s[k].dtheta_b.x() == Approx((k % 2 ? 48.0 : 0.0) / 4800.0 * dt).margin(1e-15));
    CHECK(s[k].dtheta_b.y() == Approx(-96.0 / 4800.0 * dt));
    CHECK(s[k].dtheta_b.z() == Approx(1.0 * dt));
  }
  // The same with explicit per-file columns (time only in the gyro file, a skipped column).
  const std::string acc_no_t = dir + "/acc_no_t.txt";
  {
    std::ifstream in(data_path("split/acc.txt"));
    std::ofstream out(acc_no_t);
    for (std::string l; std::getline(in, l);) {
      std::istringstream w(l);
      double t, x, y, z;
      w >> t >> x >> y >> z;
      out << x << " 7 " << y << " " << z << "\n";
    }
  }
  test::write_file(dir + "/cols.ini",
                   "[log]\naccel_file = acc_no_t.txt\ngyro_file = " + data_path("split/gyro.txt") +
                       "\naccel_columns = x - y z\ngyro_columns = t x y z\n" + kSplitKeys);
  LogReader r2(LogFormat::from_ini(IniFile(dir + "/cols.ini"), dir, 100.0));
  const auto s2 = read_all(r2);
  REQUIRE(s2.size() == s.size());
  for (std::size_t k = 0; k < s.size(); ++k) {
    CHECK(s2[k].t == s[k].t);
    CHECK((s2[k].dv_b - s[k].dv_b).norm() < 1e-15);
    CHECK((s2[k].dtheta_b - s[k].dtheta_b).norm() < 1e-15);
  }
}

TEST_CASE(
    "Split log: times that disagree or files of different lengths are errors naming both "
    "files and the line",
    "[log][split]") {
  const std::string dir = test::temp_dir("h2_split_bad");
  const std::string acc = file_text(data_path("split/acc.txt"));
  const std::string gyro = file_text(data_path("split/gyro.txt"));
  auto write_pair = [&](const std::string& a, const std::string& g, const std::string& extra) {
    test::write_file(dir + "/a.txt", a);
    test::write_file(dir + "/g.txt", g);
    test::write_file(dir + "/s.ini",
                     "[log]\naccel_file = a.txt\ngyro_file = g.txt\n" + extra + kSplitKeys);
    return [&] { return LogReader(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0)); };
  };
  // Row 5 of the gyro file 0.5 ms late.
  std::string g5 = gyro;
  const std::size_t at = g5.find("8.9840000e-02");
  REQUIRE(at != std::string::npos);
  g5.replace(at, 13, "9.0340000e-02");
  CHECK_THAT(read_error(write_pair(acc, g5, "")),
             Catch::Contains("a.txt:7: t = 0.08984 s here but 0.09034 s in") &&
                 Catch::Contains("g.txt:7") && Catch::Contains("0.0001 s (time_tolerance)"));
  // A stated tolerance accepts it.
  CHECK(read_error(write_pair(acc, g5, "time_tolerance = 1 ms\n")).empty());
  // The gyro file one row short.
  const std::string g_short = gyro.substr(0, gyro.rfind('\n', gyro.size() - 2) + 1);
  CHECK_THAT(read_error(write_pair(acc, g_short, "")),
             Catch::Contains("a.txt:20: the files of a split log have different lengths") &&
                 Catch::Contains("g.txt ends at line 19"));
  // A bad value in one file is a bad sample of that file (the pair is skipped together).
  std::string a_nan = acc;
  a_nan.replace(a_nan.find("3.1968000e+04"), 13, "nan");
  CHECK_THAT(read_error(write_pair(a_nan, gyro, "")), Catch::Contains("a.txt:1: field 3 is NaN"));
  {
    LogReader r = write_pair(a_nan, gyro, "")();
    int skipped = 0;
    r.skip_bad_samples([&](const BadSampleError&) { ++skipped; });
    CHECK(read_all(r).size() == 19);
    CHECK(skipped == 1);
  }
  // Configuration errors.
  test::write_file(dir + "/c1.ini",
                   "[log]\naccel_file = a.txt\ngyro_file = g.txt\n"
                   "accel_columns = t x y\n" +
                       std::string(kSplitKeys));
  CHECK_THAT(config_error(dir + "/c1.ini", dir),
             Catch::Contains("c1.ini:4") && Catch::Contains("column 'z' missing"));
  test::write_file(dir + "/c2.ini", "[log]\nfile = a.txt\naccel_file = a.txt\ngyro_file = g.txt\n" +
                                        std::string(kSplitKeys));
  CHECK_THAT(config_error(dir + "/c2.ini", dir),
             Catch::Contains("c2.ini:2") && Catch::Contains("accel_file and gyro_file"));
  // Missing files: an error naming the file.
  test::write_file(dir + "/c3.ini",
                   "[log]\naccel_file = a.txt\ngyro_file = nope.txt\n" + std::string(kSplitKeys));
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/c3.ini"), dir, 100.0));
             }),
             Catch::Contains("nope.txt:0: cannot open log file"));
}

TEST_CASE("Split log: the real Xsens MTi recording reads in place through a session",
          "[log][split][data]") {
  const std::string data = test::source_path("data/xsens-mti-handheld");
  REQUIRE(std::filesystem::exists(data + "/xsens_acc.txt"));
  const std::string dir = test::temp_dir("h2_xsens");
  test::write_file(dir + "/plan.ini",
                   "[plan]\ntype = rotations\nrotation_acceleration = 10 deg/s^2\n[site]\n"
                   "latitude = 45.4 deg\n[start]\nheading = 0\npitch = 0\nroll = 0\ndwell = 50 s\n"
                   "[rotations]\naxes = +x\nangle = 90\nduration = 9\npause = 10\n");
  test::write_file(dir + "/session.ini",
                   "[session]\nname = xsens\nrate = 100 Hz\nplan = "
                   "plan.ini\n[log]\naccel_file = " +
                       data + "/xsens_acc.txt\ngyro_file = " + data + "/xsens_gyro.txt\n" +
                       kSplitKeys);
  const Session session = Session::load(dir + "/session.ini");
  LogReader r(session.log);
  std::size_t n = 0;
  Vector3d sum_v = Vector3d::Zero();
  double t0 = 0.0, t_last = 0.0;
  for (ImuSample s; r.next(s); ++n) {
    if (n == 0) t0 = s.t;
    t_last = s.t;
    if (s.t < 40.0) sum_v += s.dv_b;  // static for about the first 50 s
  }
  CHECK(n == 51175);
  CHECK(t_last - t0 == Approx(511.7).margin(0.1));
  // Static: gravity at the nominal scale ("of order 400 counts per m/s^2"), within 10 %.
  const double f = (sum_v / (40.0 - t0)).norm();
  CHECK(std::abs(f - 9.81) < 1.0);
}

TEST_CASE("One file per dwell: each file placed at its dwell's start, in dwell order",
          "[log][segments]") {
  const Session session = Session::load(data_path("segments/session.ini"));
  REQUIRE(session.log.segments.size() == 3);
  const Motion motion = build_motion(session.plan, session.site);
  const auto& dwells = motion.dwells();
  LogReader r(session.log);
  const auto s = read_all(r);
  REQUIRE(s.size() == 8 + 10 + 6);
  CHECK(r.count() == s.size());
  std::size_t k = 0;
  for (int d = 1; d <= 3; ++d) {
    const int n = d == 1 ? 8 : d == 2 ? 10 : 6;
    for (int i = 0; i < n; ++i, ++k) {
      CAPTURE(d, i);
      // pos<d>.csv carries gyro x = d deg/s: the files come in dwell order.
      CHECK(s[k].dtheta_b.x() == Approx(d * units::deg * 0.01));
      // The first sample's interval starts at the dwell's start.
      CHECK(s[k].t == Approx(dwells[static_cast<std::size_t>(d - 1)].t_start + 0.01 * (i + 1)));
      CHECK(s[k].t <= dwells[static_cast<std::size_t>(d - 1)].t_end + 1e-9);
    }
  }
  // The closed form's dwell navigation reads them (the dwell 2 file covers the whole dwell).
  CHECK(s[8].t - s[8].dt == Approx(dwells[1].t_start));
}

TEST_CASE("One file per dwell: missing file, unknown dwell, overlap, too long are clear errors",
          "[log][segments]") {
  const std::string dir = test::temp_dir("h2_segments_bad");
  for (const char* f : {"plan.ini", "pos1.csv", "pos2.csv", "pos3.csv"})
    std::filesystem::copy_file(data_path(std::string("segments/") + f), dir + "/" + f);
  const std::string head =
      "[session]\nrate = 100 Hz\nplan = plan.ini\n[log]\nformat = custom\n"
      "columns = t gx gy gz ax ay az\ngyro = rate\ngyro_unit = deg/s\naccel = rate\n"
      "accel_unit = g\n";
  auto session_error = [&](const std::string& log_keys) {
    test::write_file(dir + "/session.ini", head + log_keys);
    try {
      const Session s = Session::load(dir + "/session.ini");
      LogReader r(s.log);
      read_all(r);
    } catch (const std::exception& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(session_error("files = pos1.csv pos2.csv pos3.csv\n") == "no error");
  CHECK_THAT(session_error("files = pos1.csv pos9.csv\n"),
             Catch::Contains("session.ini:11") && Catch::Contains("'pos9.csv': no such file"));
  CHECK_THAT(session_error("files = pos1.csv pos2.csv\ndwells = 1 4\n"),
             Catch::Contains("session.ini:12") &&
                 Catch::Contains("'pos2.csv' is assigned to dwell 4 but the plan") &&
                 Catch::Contains("has 3 dwells"));
  CHECK_THAT(session_error("files = pos1.csv pos2.csv\ndwells = 2 2\n"),
             Catch::Contains("both assigned to dwell 2"));
  CHECK_THAT(session_error("files = pos1.csv pos2.csv\ndwells = 1\n"),
             Catch::Contains("1 dwells for 2 files"));
  CHECK_THAT(session_error("files = pos1.csv\nfile = pos1.csv\n"),
             Catch::Contains("either 'file'") && Catch::Contains("or 'files'"));
  // A file longer than its dwell (11 samples in a 0.1 s dwell) runs into the next dwell's time.
  std::string longer = file_text(dir + "/pos2.csv") + "5.11,2,0,0,0,-1,0\n";
  test::write_file(dir + "/pos2.csv", longer);
  CHECK_THAT(session_error("files = pos1.csv pos2.csv pos3.csv\n"),
             Catch::Contains("pos2.csv:11: this file's data reach") &&
                 Catch::Contains("past the end of dwell 2"));
  // An empty file.
  test::write_file(dir + "/pos2.csv", "");
  CHECK_THAT(session_error("files = pos1.csv pos2.csv pos3.csv\n"),
             Catch::Contains("pos2.csv:0: no samples in the file for dwell 2"));
  // Without a plan the dwells' times are unknown.
  test::write_file(dir + "/noplan.ini", "[log]\nfiles = pos1.csv\n");
  CHECK_THAT(config_error(dir + "/noplan.ini", dir), Catch::Contains("needs the session's plan"));
  // Several files cannot come from a stream.
  std::istringstream in("");
  const Session ok = [&] {
    test::write_file(dir + "/session.ini", head + "files = pos1.csv\n");
    return Session::load(dir + "/session.ini");
  }();
  CHECK_THROWS_WITH(LogReader(in, ok.log), Catch::Contains("cannot be read from a stream"));
}

TEST_CASE(
    "One file per dwell: seed8 cut into its dwells, each on its own clock, calibrates as "
    "the whole log does",
    "[long][log][segments][closed-form]") {
  const std::string a = test::temp_dir("h2_seed8_whole"), b = test::temp_dir("h2_seed8_cut");
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/seed8.ini");
  spec.data_sensor_path = test::source_path("config/sensors/nav-fog.ini");
  spec.seed = 5;
  const SimulatedSession sim = simulate_session(a, spec);
  const Session whole = Session::load(sim.session_path);
  const Motion motion = build_motion(whole.plan, whole.site);
  // Each dwell's samples to pos<d>.csv, times on a clock of its own (1000 s * d + time since the
  // dwell's start); the samples of the moves are dropped.
  std::vector<std::ofstream> out;
  std::string files;
  for (const auto& d : motion.dwells()) {
    const std::string name = "pos" + std::to_string(d.index) + ".csv";
    out.emplace_back(b + "/" + name);
    files += " " + name;
  }
  LogReader r(whole.log);
  for (ImuSample s; r.next(s);) {
    for (const auto& d : motion.dwells()) {
      if (s.t - s.dt < d.t_start - 1e-9 || s.t > d.t_end + 1e-9) continue;
      char line[300];
      std::snprintf(line, sizeof line, "%.17g,%.17g,%.17g,%.17g,%.17g,%.17g,%.17g\n",
                    1000.0 * d.index + (s.t - d.t_start), s.dtheta_b.x(), s.dtheta_b.y(),
                    s.dtheta_b.z(), s.dv_b.x(), s.dv_b.y(), s.dv_b.z());
      out[static_cast<std::size_t>(d.index - 1)] << line;
    }
  }
  for (auto& o : out) o.close();
  std::filesystem::copy_file(a + "/plan.ini", b + "/plan.ini");
  // Listed out of order: the reader yields them in dwell order.
  test::write_file(b + "/session.ini",
                   "[session]\nname = seed8-cut\nrate = 100 Hz\nplan = plan.ini\n[log]\n"
                   "format = custom\nfiles = pos8.csv" +
                       files.substr(0, files.rfind(" pos8.csv")) +
                       "\ndwells = 8 1 2 3 4 5 6 7\ncolumns = t gx gy gz ax ay az\n");
  const Session cut = Session::load(b + "/session.ini");
  REQUIRE(cut.log.segments.size() == 8);
  Stage1Options o;
  o.arw = sim.profile.noise.gyro.white;
  o.vrw = sim.profile.noise.accel.white;
  const ResultCoefficients ra =
      result_coefficients(run_closed_form(whole, o, TableAttitudeError{2.5 * units::arcsec}));
  const ResultCoefficients rb =
      result_coefficients(run_closed_form(cut, o, TableAttitudeError{2.5 * units::arcsec}));
  REQUIRE(ra.size() == rb.size());
  int compared = 0;
  for (const auto& [name, ca] : ra) {
    const ResultCoefficient& cb = rb.at(name);
    CAPTURE(name);
    REQUIRE(ca.observable == cb.observable);
    if (!ca.observable) continue;
    CHECK(std::abs(ca.value - cb.value) <= 1e-6 * *ca.sigma);
    CHECK(*cb.sigma == Approx(*ca.sigma).epsilon(1e-9));
    ++compared;
  }
  CHECK(compared >= 20);
}

TEST_CASE("Kalman filter: data that jump over the time between dwells stop the run",
          "[log][segments][kalman]") {
  // A log in one file per dwell has no data for the moves between dwells: the filter, which
  // integrates through them, must say so rather than integrate a wrong attitude.
  const Session session = Session::load(data_path("segments/session.ini"));
  const Motion motion = build_motion(session.plan, session.site);
  Calibrator kf(PlanTimeline::of(session.plan, session.site), session.site, CalibratorOptions{});
  LogReader r(session.log);
  ImuSample s;
  CHECK_THROWS_WITH(
      [&] {
        while (r.next(s)) kf.push(s);
      }(),
      Catch::Contains("the data jump from t = 0.08 s to") && Catch::Contains("closed-form"));
}

TEST_CASE("NovAtel: the CRC-32 of the documented example logs", "[log][novatel]") {
  // Example lines of the receiver manual (RAWIMUSA, RAWIMUSXA, RAWIMUXA with a long header) and a
  // support note (RAWIMUSA of an iIMAR IMU): each one reads as one good sample.
  const std::vector<std::string> examples = {
      "%RAWIMUSA,2209,491612.254;2209,491612.253588,ea5afe00,329303960,-2512321,4410363,309705,"
      "607017,-1009773*1fb76c28",
      "%RAWIMUSXA,2209,491674.014;04,41,2209,491674.013699,ea59fe00,329308016,-2706935,4508389,"
      "196192,417138,-1000837*038422a7",
      "%RAWIMUSA,1500,202729.304;1500,202729.304063700,00000000,31695,617,378,1536,15615,-7680*"
      "fc8f8ff8",
      "#RAWIMUXA,USB1,0,64.5,FINESTEERING,2209,491740.110,02000020,0dc5,16809;04,41,2209,491740."
      "109817,ea57fe00,329394068,-2396829,4481425,321199,257329,-936077*cf9c035d"};
  const std::string dir = test::temp_dir("h2_novatel_examples");
  test::write_file(dir + "/s.ini",
                   "[log]\nfile = x.asc\nformat = novatel\ngyro_scale = 9.5367431640625e-07\n"
                   "accel_scale = 1.52587890625e-06\n");  // 2^-20 rad, 0.05 * 2^-15 m/s
  for (const auto& line : examples) {
    CAPTURE(line);
    test::write_file(dir + "/x.asc", line + "\r\n");
    LogReader r(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 200.0));
    const auto s = read_all(r);
    REQUIRE(s.size() == 1);
    // One changed digit: a CRC mismatch, a bad sample naming file and line.
    std::string bad = line;
    bad[bad.find(';') + 3] = bad[bad.find(';') + 3] == '1' ? '2' : '1';
    test::write_file(dir + "/x.asc", "[COM1]\n" + bad + "\r\n");
    CHECK_THAT(read_error([&] {
                 return LogReader(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 200.0));
               }),
               Catch::Contains("x.asc:2: CRC-32 mismatch: the log says"));
  }
  // The iIMAR example: z accel 31695 counts of 0.05 * 2^-15 m/s per 5 ms sample is 9.67 m/s^2
  // (the manufacturer's note); body y is minus the log's fifth field.
  test::write_file(dir + "/x.asc", examples[2] + "\r\n");
  test::write_file(dir + "/s.ini",
                   "[log]\nfile = x.asc\nformat = novatel\n"
                   "gyro_scale = 9.5367431640625e-07\naccel_scale = 1.52587890625e-06\n");
  LogReader r(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 200.0));
  ImuSample s;
  REQUIRE(r.next(s));
  CHECK(s.t == Approx(202729.3040637));
  CHECK(s.dv_b.z() / 0.005 == Approx(9.67).margin(0.005));
  CHECK(s.dv_b.y() == Approx(-617 * 1.52587890625e-06));
  CHECK(s.dv_b.x() == Approx(378 * 1.52587890625e-06));
  const double rad_per_count = 9.5367431640625e-07;  // 2^-20: products exact
  CHECK(s.dtheta_b.z() == 1536.0 * rad_per_count);
  CHECK(s.dtheta_b.y() == -15615.0 * rad_per_count);
  CHECK(s.dtheta_b.x() == -7680.0 * rad_per_count);
}

TEST_CASE("NovAtel: RAWIMUSXA across a GPS week, other logs skipped, bad lines", "[log][novatel]") {
  const std::string file = data_path("novatel/rawimusxa.asc");
  const std::string dir = test::temp_dir("h2_novatel");
  const std::string keys =
      "format = novatel\ngyro_scale = 1e-9\ngyro_unit = rad\naccel_scale = 0.001\n"
      "accel_unit = mm/s\n";
  test::write_file(dir + "/s.ini", "[log]\nfile = " + file + "\n" + keys);
  LogReader r(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0));
  const auto s = read_all(r);
  // Six RAWIMUSXA logs; the RAWIMUSA and BESTPOSA logs and the port prompt are skipped.
  REQUIRE(s.size() == 6);
  for (std::size_t k = 0; k < s.size(); ++k) {
    CAPTURE(k);
    const double c = static_cast<double>(k);
    // Seconds of the first log's week, going on past the week's end (604800 s).
    CHECK(s[k].t == Approx(604799.97 + 0.01 * c).epsilon(1e-13));
    if (k > 0) CHECK(s[k].dt == Approx(0.01).epsilon(1e-6));
    // Fields z, -y, x: body x = 100 + k, y = 200 + k, z = 3000 + k counts (1e-6 m/s each).
    CHECK(s[k].dv_b.x() == Approx((100 + c) * 1e-6));
    CHECK(s[k].dv_b.y() == Approx((200 + c) * 1e-6));
    CHECK(s[k].dv_b.z() == Approx((3000 + c) * 1e-6));
    CHECK(s[k].dtheta_b.x() == Approx((10 + c) * 1e-9));
    CHECK(s[k].dtheta_b.y() == Approx((20 + c) * 1e-9));
    CHECK(s[k].dtheta_b.z() == Approx((30 + c) * 1e-9));
  }
  // A damaged line (one digit changed): a bad sample; skipped, the reading goes on.
  std::string text = file_text(file);
  text.replace(text.find(",3004,"), 6, ",3904,");
  test::write_file(dir + "/bad.asc", text);
  test::write_file(dir + "/b.ini", "[log]\nfile = bad.asc\n" + keys);
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/b.ini"), dir, 100.0));
             }),
             Catch::Contains("bad.asc:8: CRC-32 mismatch: the log says 5c512330, its text gives"));
  {
    LogReader rb(LogFormat::from_ini(IniFile(dir + "/b.ini"), dir, 100.0));
    std::vector<std::string> skipped;
    rb.skip_bad_samples([&](const BadSampleError& e) { skipped.push_back(e.what()); });
    const auto sb = read_all(rb);
    CHECK(sb.size() == 5);
    REQUIRE(skipped.size() == 1);
    CHECK_THAT(skipped[0], Catch::Contains("bad.asc:8"));
    // The skipped interval is bridged: the next sample covers both intervals.
    CHECK(sb[4].dt == Approx(0.02).epsilon(1e-6));
  }
  // IMU Info bit 0 (an IMU error) is a bad sample; bit 1 (encrypted) stops the reading.
  // (CRCs computed by an independent implementation, the generator of tests/data/novatel.)
  auto one_line = [&](const std::string& info, const std::string& status, const char* crc) {
    return "%RAWIMUSXA,2209,1.000;" + info + ",41,2209,1.000000," + status + ",1,2,3,4,5,6*" + crc;
  };
  test::write_file(dir + "/e.asc", one_line("05", "00000000", "c2a5802e") + "\n");
  test::write_file(dir + "/e.ini", "[log]\nfile = e.asc\n" + keys);
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/e.ini"), dir, 100.0));
             }),
             Catch::Contains("e.asc:1: the receiver flags an IMU error (IMU Info bit 0"));
  test::write_file(dir + "/e.asc", one_line("06", "00000000", "113e9cd5") + "\n");
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/e.ini"), dir, 100.0));
             }),
             Catch::Contains("e.asc:1: the IMU data are encrypted"));
  // status_mask: a status with a masked bit set is a bad sample; other bits are not checked.
  test::write_file(dir + "/e.asc", one_line("04", "00000004", "4c95e111") + "\n");
  test::write_file(dir + "/m.ini", "[log]\nfile = e.asc\n" + keys + "status_mask = 0x0000000c\n");
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/m.ini"), dir, 100.0));
             }),
             Catch::Contains("e.asc:1: IMU status 00000004 has bits 00000004 of status_mask set"));
  test::write_file(dir + "/m.ini", "[log]\nfile = e.asc\n" + keys + "status_mask = 3\n");
  CHECK(read_error([&] {
          return LogReader(LogFormat::from_ini(IniFile(dir + "/m.ini"), dir, 100.0));
        }).empty());
  test::write_file(dir + "/m.ini", "[log]\nfile = e.asc\n" + keys + "status_mask = 0xg\n");
  CHECK_THAT(config_error(dir + "/m.ini", dir), Catch::Contains("m.ini:8"));
  // A file without raw IMU logs, a truncated last line, a missing scale.
  test::write_file(dir + "/none.asc", "[COM1]\n#BESTPOSA,COM1;x*00000000\n");
  test::write_file(dir + "/n.ini", "[log]\nfile = none.asc\n" + keys);
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/n.ini"), dir, 100.0));
             }),
             Catch::Contains("none.asc:2: no RAWIMUSA, RAWIMUSXA, RAWIMUA or RAWIMUXA log"));
  const std::string first = text.substr(0, text.find("*211a33af") + 4);
  test::write_file(dir + "/t.asc", first);
  test::write_file(dir + "/t.ini", "[log]\nfile = t.asc\n" + keys);
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/t.ini"), dir, 100.0));
             }),
             Catch::Contains("t.asc:2: truncated line"));
  test::write_file(dir + "/k.ini", "[log]\nfile = t.asc\nformat = novatel\naccel_scale = 1\n");
  CHECK_THAT(config_error(dir + "/k.ini", dir), Catch::Contains("missing 'gyro_scale'"));
  test::write_file(dir + "/k.ini",
                   "[log]\nfile = t.asc\nformat = novatel\naccel_scale = 1\ngyro_scale = 1\n"
                   "gyro = rate\n");
  CHECK_THAT(config_error(dir + "/k.ini", dir),
             Catch::Contains("k.ini:6") && Catch::Contains("unknown key"));
}

TEST_CASE("Reader limits: a line without an end is refused after 64 KiB", "[log][limits]") {
  const std::string dir = test::temp_dir("h2_long_line");
  // 200 KiB without a newline after a good first sample.
  test::write_file(dir + "/imu.csv", "0.01,0,0,0,0,0,0\n" + std::string(200 * 1024, '7'));
  test::write_file(dir + "/s.ini",
                   "[log]\nfile = imu.csv\nformat = custom\ncolumns = t gx gy gz ax ay az\n");
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0));
             }),
             Catch::Contains("imu.csv:2: line longer than 65536 bytes"));
  // From a stream too (the reader never holds more than the limit).
  std::istringstream in(std::string(100000, 'x'));
  LogFormat f = LogFormat::native_format("<stdin>", 100.0);
  CHECK_THROWS_WITH(LogReader(in, f), Catch::Contains("<stdin>:1: line longer than 65536"));
  // A line of exactly the limit is read (and found not to be a number).
  test::write_file(dir + "/imu.csv", "0.01,0,0,0,0,0," + std::string(65536 - 15, '1') + "\n");
  CHECK_THAT(read_error([&] {
               return LogReader(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0));
             }),
             Catch::Contains("imu.csv:1: field 7") && !Catch::Contains("longer"));
}

TEST_CASE("Log configuration: header_lines, axes, scales and max_gap out of range are refused",
          "[log][limits]") {
  const std::string dir = test::temp_dir("h2_log_config");
  const std::string head = "[log]\nfile = f.txt\nformat = custom\ncolumns = t gx gy gz ax ay az\n";
  auto error_of = [&](const std::string& extra) {
    test::write_file(dir + "/s.ini", head + extra);
    return config_error(dir + "/s.ini", dir);
  };
  for (const char* v : {"-1", "1e12", "2.5", "100001", "nan", "inf"}) {
    CAPTURE(v);
    CHECK_THAT(error_of(std::string("header_lines = ") + v + "\n"),
               Catch::Contains("s.ini:5") && Catch::Contains("header_lines"));
  }
  CHECK(error_of("header_lines = 100000\n") == "no error");
  CHECK_THAT(error_of("gyro_axes = x y z w\n"),
             Catch::Contains("s.ini:5") && Catch::Contains("expected three axes"));
  CHECK_THAT(error_of("accel_axes = x y\n"), Catch::Contains("s.ini:5"));
  CHECK_THAT(error_of("accel_axes = x y y\n"), Catch::Contains("permutation"));
  CHECK_THAT(error_of("gyro_scale = 0\n"), Catch::Contains("s.ini:5") && Catch::Contains("zero"));
  CHECK_THAT(error_of("gyro_saturation = -5\n"), Catch::Contains("s.ini:5"));
  CHECK_THAT(error_of("max_gap = 0.5\n"), Catch::Contains("s.ini:5"));
  CHECK_THAT(error_of("columns2 = t\n"), Catch::Contains("unknown key"));
  CHECK_THAT(error_of("time_unit = deg\n"), Catch::Contains("s.ini:5") && Catch::Contains("unit"));
  CHECK_THAT(error_of("gyro_unit = m/s\n"), Catch::Contains("s.ini:5"));
  test::write_file(dir + "/c.ini", "[log]\nfile = f.txt\nformat = custom\ncolumns = t gx gy gz\n");
  CHECK_THAT(config_error(dir + "/c.ini", dir), Catch::Contains("column 'ax' missing"));
  test::write_file(dir + "/c.ini", "[log]\nfile = f.txt\nformat = csv\n");
  CHECK_THAT(config_error(dir + "/c.ini", dir), Catch::Contains("c.ini:3"));
}

TEST_CASE("Custom log: text columns skipped, a label column, a sample counter as time",
          "[log][label]") {
  // imucal's layout: a text label first, a counter, then counts; '-' skips any text.
  const std::string dir = test::temp_dir("label-log");
  test::write_file(dir + "/log.csv",
                   "part,samples,acc_x,acc_y,acc_z,gyr_x,gyr_y,gyr_z\n"
                   "x_p,10,2048,0,0,1,2,3\n"
                   "x_p,11,2048,0,0,1,2,3\n"
                   "x_a,12,-2048,0,0,1,2,3\n"
                   ",13,0,0,2048,1,2,3\n");
  test::write_file(dir + "/session.ini",
                   "[session]\nrate = 100 Hz\n[site]\ngravity = 9.81 m/s^2\n[log]\nfile = log.csv\n"
                   "format = custom\nheader_lines = 1\ncolumns = label t ax ay az gx gy gz\n"
                   "time_unit = samples\naccel = rate\naccel_unit = g\n"
                   "accel_scale = 0.00048828125\ngyro = rate\ngyro_unit = deg/s\n");
  const Session s = Session::load(dir + "/session.ini", Session::PlanNeed::Optional);
  LogReader r(s.log);
  ImuSample x;
  std::vector<int> labels;
  std::vector<double> times;
  while (r.next(x)) {
    labels.push_back(x.label);
    times.push_back(x.t);
  }
  REQUIRE(labels.size() == 4);
  CHECK(r.labels() == std::vector<std::string>{"x_p", "x_a", ""});
  CHECK(labels == std::vector<int>{0, 0, 1, 2});
  CHECK(times[0] == Approx(0.10));  // counter 10 at 100 Hz
  CHECK(times[3] == Approx(0.13));
  // '-' skips a text column too; a label in a numeric column is still an error.
  test::write_file(dir + "/session2.ini",
                   "[session]\nrate = 100 Hz\n[site]\ngravity = 9.81 m/s^2\n[log]\nfile = log.csv\n"
                   "format = custom\nheader_lines = 1\ncolumns = - - ax ay az gx gy gz\n"
                   "accel = rate\ngyro = rate\n");
  LogReader r2(Session::load(dir + "/session2.ini", Session::PlanNeed::Optional).log);
  std::size_t n = 0;
  while (r2.next(x)) ++n;
  CHECK(n == 4);
  CHECK(x.label == -1);
  test::write_file(dir + "/session3.ini",
                   "[session]\nrate = 100 Hz\n[site]\ngravity = 9.81 m/s^2\n[log]\nfile = log.csv\n"
                   "format = custom\nheader_lines = 1\ncolumns = t - ax ay az gx gy gz\n"
                   "accel = rate\ngyro = rate\n");
  LogReader r3(Session::load(dir + "/session3.ini", Session::PlanNeed::Optional).log);
  CHECK_THROWS_WITH(r3.next(x),
                    Catch::Matchers::Contains("log.csv:2: field 1 'x_p' is not a number"));
}

// --- Temperature columns (issue 19; docs/formats.md "Temperature columns") ---------------------

namespace {

std::string number_text(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// A custom log of n samples at 100 Hz: t, gyro x, y, z (rad/s), accel x, y, z (m/s^2), then
// `temps(k)` (the temperature fields of sample k, from 0, with their leading commas).
template <class Temps>
std::string temperature_log(int n, Temps temps) {
  std::string out;
  for (int k = 0; k < n; ++k)
    out += number_text(0.01 * (k + 1)) + ",0.1,0,0,0,0,9.8" + temps(k) + "\n";
  return out;
}

const char* kRateKeys = "format = custom\ngyro = rate\naccel = rate\n";

// Reads a custom log `text` with [log] keys `keys` (file = f.txt added): the samples, or the
// error's message in `error`.
std::vector<ImuSample> read_custom(const std::string& dir, const std::string& text,
                                   const std::string& keys, std::string* error = nullptr) {
  test::write_file(dir + "/f.txt", text);
  test::write_file(dir + "/s.ini", "[log]\nfile = f.txt\n" + keys);
  try {
    LogReader r(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0));
    return read_all(r);
  } catch (const std::exception& e) {
    if (!error) throw;
    *error = e.what();
  }
  return {};
}

std::string custom_error(const std::string& dir, const std::string& text, const std::string& keys) {
  std::string error = "no error";
  read_custom(dir, text, keys, &error);
  return error;
}

}  // namespace

TEST_CASE("Temperature: custom log, one column per unit or per triad, C, K, F and raw counts",
          "[log][temperature]") {
  const std::string dir = test::temp_dir("temp_custom");
  // One per unit, deg C: both triads read it, exactly.
  auto unit_c = [](int k) { return "," + number_text(20.0 + 0.01 * k); };
  const auto s = read_custom(dir, temperature_log(50, unit_c),
                             std::string(kRateKeys) + "columns = t gx gy gz ax ay az temp\n");
  REQUIRE(s.size() == 50);
  for (std::size_t k = 0; k < s.size(); ++k) {
    CAPTURE(k);
    CHECK(s[k].has_temperature);
    CHECK(s[k].accel_temperature_c == 20.0 + 0.01 * static_cast<double>(k));
    CHECK(s[k].gyro_temperature_c == s[k].accel_temperature_c);
    CHECK(s[k].dtheta_b.x() == Approx(0.001));  // the sensors' columns are where they were
  }
  // One per triad, in any column order; kelvin and Fahrenheit.
  auto per_triad = [](double a, double g) {
    return [a, g](int k) { return "," + number_text(a + 0.01 * k) + "," + number_text(g); };
  };
  const std::string triad_cols = "columns = t gx gy gz ax ay az temp_g temp_a\n";
  auto check_triad = [](const std::vector<ImuSample>& v, double accel0, double gyro) {
    REQUIRE(v.size() == 30);
    for (std::size_t k = 0; k < v.size(); ++k) {
      CHECK(v[k].accel_temperature_c == Approx(accel0 + 0.01 * static_cast<double>(k) * 5 / 9));
      CHECK(v[k].gyro_temperature_c == Approx(gyro));
    }
  };
  // temp_g first: 300.15 K = 27 C; temp_a from 298.15 K = 25 C.
  const auto kelvin = read_custom(dir, temperature_log(30, per_triad(300.15, 298.15)),
                                  std::string(kRateKeys) + triad_cols + "temperature_unit = K\n");
  REQUIRE(kelvin.size() == 30);
  CHECK(kelvin[0].accel_temperature_c == Approx(25.0));
  CHECK(kelvin[29].gyro_temperature_c == Approx(27.0 + 0.29));
  // Fahrenheit: temp_a 77 F = 25 C (steps of 0.01 F = 1/180 C), temp_g 98.6 F = 37 C.
  check_triad(read_custom(dir, temperature_log(30, per_triad(98.6, 77.0)),
                          std::string(kRateKeys) + "columns = t gx gy gz ax ay az temp_a temp_g\n" +
                              "temperature_unit = F\n"),
              37.0, 25.0);
  // Raw counts, the MPU-6050's conversion: T = counts / 340 + 36.53 C.
  const auto raw = read_custom(
      dir, temperature_log(10, [](int k) { return "," + std::to_string(-3920 + 34 * k); }),
      std::string(kRateKeys) + "columns = t gx gy gz ax ay az temp\n" +
          "temperature_scale = 0.0029411764705882353\ntemperature_offset = -12420.2\n");
  REQUIRE(raw.size() == 10);
  CHECK(raw[0].accel_temperature_c == Approx(-3920.0 / 340.0 + 36.53));
  CHECK(raw[9].gyro_temperature_c == Approx((-3920.0 + 306.0) / 340.0 + 36.53));
  // Without a temperature column: no temperature.
  const auto none = read_custom(dir, temperature_log(3, [](int) { return std::string(); }),
                                std::string(kRateKeys) + "columns = t gx gy gz ax ay az\n");
  REQUIRE(none.size() == 3);
  CHECK_FALSE(none[0].has_temperature);
}

TEST_CASE("Temperature: the [log] keys and columns are checked, each error naming the line",
          "[log][temperature]") {
  const std::string dir = test::temp_dir("temp_config");
  auto error_of = [&](const std::string& extra) {
    test::write_file(dir + "/s.ini", "[log]\nfile = f.txt\n" + std::string(kRateKeys) + extra);
    return config_error(dir + "/s.ini", dir);
  };
  const std::string cols = "columns = t gx gy gz ax ay az temp\n";
  CHECK(error_of(cols + "temperature_unit = K\n") == "no error");
  // A temperature key without a temperature column (line 6).
  CHECK_THAT(error_of("columns = t gx gy gz ax ay az\ntemperature_unit = K\n"),
             Catch::Contains("s.ini:7: 'log.temperature_unit'") &&
                 Catch::Contains("a temperature key without a temperature column"));
  CHECK_THAT(error_of("columns = t gx gy gz ax ay az\ntemperature_scale = 0.1\n"),
             Catch::Contains("s.ini:7: 'log.temperature_scale'"));
  CHECK_THAT(error_of(cols + "temperature_unit = celsius\n"),
             Catch::Contains("s.ini:7") && Catch::Contains("expected C, K or F"));
  CHECK_THAT(error_of(cols + "temperature_scale = 0\n"),
             Catch::Contains("s.ini:7") && Catch::Contains("must not be zero"));
  CHECK_THAT(error_of(cols + "temperature_scale = 1000\n"),
             Catch::Contains("s.ini:7") && Catch::Contains("one count would be 1000 C"));
  CHECK_THAT(error_of(cols + "temperature_offset = nan\n"),
             Catch::Contains("s.ini:7") && Catch::Contains("not a finite number"));
  CHECK_THAT(error_of("columns = t gx gy gz ax ay az temp_a\n"),
             Catch::Contains("s.ini:6") && Catch::Contains("both per-triad temperature columns"));
  CHECK_THAT(error_of("columns = t gx gy gz ax ay az temp temp_g\n"),
             Catch::Contains("s.ini:6") && Catch::Contains("not both"));
  CHECK_THAT(error_of("columns = t gx gy gz ax ay az temp temp\n"),
             Catch::Contains("s.ini:6") && Catch::Contains("given twice"));
  // The native format has no temperature keys (its header says).
  test::write_file(dir + "/n.ini", "[log]\nfile = f.txt\ntemperature_unit = K\n");
  CHECK_THAT(config_error(dir + "/n.ini", dir),
             Catch::Contains("n.ini:3") && Catch::Contains("unknown key"));
}

TEST_CASE("Temperature: NaN, text, out of range, jumps are bad samples naming file and line",
          "[log][temperature]") {
  const std::string dir = test::temp_dir("temp_checks");
  const std::string keys = std::string(kRateKeys) + "columns = t gx gy gz ax ay az temp\n";
  auto with = [](int line, const std::string& value, double base = 25.0) {
    return [line, value, base](int k) {
      return "," + (k + 1 == line ? value : number_text(base + 0.001 * k));
    };
  };
  CHECK_THAT(custom_error(dir, temperature_log(20, with(7, "nan")), keys),
             Catch::Contains("f.txt:7: field 8 (temperature) is NaN"));
  CHECK_THAT(custom_error(dir, temperature_log(20, with(7, "warm")), keys),
             Catch::Contains("f.txt:7: field 8 (temperature) 'warm' is not a number"));
  CHECK_THAT(custom_error(dir, temperature_log(20, with(7, "inf")), keys),
             Catch::Contains("f.txt:7: field 8 (temperature) is infinite"));
  // Kelvin declared as C: the first line is out of range, and the message says what it is.
  CHECK_THAT(custom_error(dir, temperature_log(20, with(0, "", 298.15)), keys),
             Catch::Contains("f.txt:1: temperature reads 298.15 C, outside") &&
                 Catch::Contains("outside -60 ... 130 C") &&
                 Catch::Contains("read as K it would be 25 C (temperature_unit = K?)"));
  // C declared as K: 25 K is -248 C; as C or F it would be in range.
  CHECK_THAT(custom_error(dir, temperature_log(20, with(0, "")), keys + "temperature_unit = K\n"),
             Catch::Contains("f.txt:1: temperature reads 25 (-248.15 C), outside") &&
                 Catch::Contains("read as C it would be 25 C"));
  // Beyond the range in any unit: a wrong column or scale.
  CHECK_THAT(custom_error(dir, temperature_log(20, with(3, "12345")), keys),
             Catch::Contains("f.txt:3: temperature reads 12345") &&
                 Catch::Contains("a wrong unit, scale or column?"));
  // Raw counts (the MPU-6050's conversion): the count, then its temperature.
  CHECK_THAT(custom_error(dir, temperature_log(20, with(0, "", 40000.0)),
                          keys + "temperature_scale = 0.0029411764705882353\n" +
                              "temperature_offset = -12420.2\n"),
             Catch::Contains("f.txt:1: temperature reads 40000 (154.177 C), outside"));
  // The range's ends: -59.5 and 129.5 C are temperatures, -60.5 and 130.5 C are not.
  CHECK(custom_error(dir, temperature_log(20, with(0, "", -59.5)), keys) == "no error");
  CHECK(custom_error(dir, temperature_log(20, with(0, "", 129.5)), keys) == "no error");
  CHECK_THAT(custom_error(dir, temperature_log(20, with(0, "", -60.5)), keys),
             Catch::Contains("f.txt:1: temperature reads -60.5"));
  CHECK_THAT(custom_error(dir, temperature_log(20, with(0, "", 130.5)), keys),
             Catch::Contains("f.txt:1: temperature reads 130.5"));
  // A jump: 3 C in one sample of 0.01 s (bound 2 C + 5 C/s x 0.01 s = 2.05 C), up and down.
  CHECK_THAT(custom_error(dir, temperature_log(20, with(12, "28.011")), keys),
             Catch::Contains("f.txt:12: temperature jumps to 28.011 C") &&
                 Catch::Contains("from 25.01 C at t = 0.110000 s (line 11)") &&
                 Catch::Contains("beyond 2 C + 5 C/s x the time between them"));
  CHECK_THAT(custom_error(dir, temperature_log(20, with(12, "22.9")), keys),
             Catch::Contains("f.txt:12: temperature jumps to 22.9 C"));
  // 2 C in one sample is within the bound (a quantized sensor's step).
  CHECK(custom_error(dir, temperature_log(20, with(12, "27.01")), keys).find("jumps") ==
        std::string::npos);
  // A sustained ramp of 10 C/s (0.1 C per sample): within the step bound sample by sample, beyond
  // the rate over 0.4 s (4 C against 2 C + 2 C).
  CHECK_THAT(custom_error(
                 dir, temperature_log(100, [](int k) { return "," + number_text(0.1 * k); }), keys),
             Catch::Contains("f.txt:42: temperature jumps to 4.1 C") &&
                 Catch::Contains("from 0 C at t = 0.010000 s (line 1)"));
  // A chamber's fast ramp (1 C/s) is fine.
  CHECK(custom_error(dir, temperature_log(300, [](int k) { return "," + number_text(0.01 * k); }),
                     keys) == "no error");
  // Per triad: the gyro's column names the gyro.
  CHECK_THAT(custom_error(dir,
                          temperature_log(
                              20, [](int k) { return ",30," + std::string(k == 9 ? "40" : "31"); }),
                          std::string(kRateKeys) + "columns = t gx gy gz ax ay az temp_a temp_g\n"),
             Catch::Contains("f.txt:10: gyro temperature jumps to 40 C"));
}

TEST_CASE("Temperature: skipped bad samples, the jump check resumes against the last good one",
          "[log][temperature]") {
  const std::string dir = test::temp_dir("temp_skip");
  test::write_file(dir + "/s.ini", "[log]\nfile = f.txt\n" + std::string(kRateKeys) +
                                       "columns = t gx gy gz ax ay az temp\n");
  auto read_skipping = [&](const std::string& text, std::vector<std::string>& skipped) {
    test::write_file(dir + "/f.txt", text);
    LogReader r(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0));
    r.skip_bad_samples([&](const BadSampleError& e) { skipped.emplace_back(e.what()); });
    return read_all(r);
  };
  // One glitch (60 C in a 25 C log): skipped, the next sample compared with the last good one.
  std::vector<std::string> skipped;
  auto s = read_skipping(
      temperature_log(50, [](int k) { return std::string(k == 20 ? ",60" : ",25"); }), skipped);
  CHECK(s.size() == 49);
  REQUIRE(skipped.size() == 1);
  CHECK_THAT(skipped[0], Catch::Contains("f.txt:21: temperature jumps to 60 C"));
  // A lasting step of 10.02 C: skipped until the bound has grown to it, (10.02 - 2) / 5 = 1.604 s
  // after the last good sample (t = 1 s): the first sample taken is at 2.61 s.
  skipped.clear();
  s = read_skipping(
      temperature_log(400, [](int k) { return std::string(k >= 100 ? ",35.02" : ",25"); }),
      skipped);
  CHECK(skipped.size() == 160);
  CHECK(s.size() == 240);
  CHECK(s[100].accel_temperature_c == 35.02);
  CHECK(s[100].t == Approx(2.61));
}

TEST_CASE("Temperature: a stuck sensor over more than 10 min is an error of the thermal check",
          "[log][temperature]") {
  const std::string dir = test::temp_dir("temp_stuck");
  // 11 min at 10 Hz, exactly 23.5 C throughout.
  std::string text;
  for (int k = 1; k <= 6600; ++k) text += number_text(0.1 * k) + ",0,0,0,0,0,9.8,23.5,24\n";
  test::write_file(dir + "/f.txt", text);
  test::write_file(dir + "/s.ini", "[log]\nfile = f.txt\n" + std::string(kRateKeys) +
                                       "columns = t gx gy gz ax ay az temp_a temp_g\n");
  LogFormat f = LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 10.0);
  LogReader r(f);
  const auto s = read_all(r);  // the reader itself does not refuse it (a non-thermal use is fine)
  REQUIRE(s.size() == 6600);
  const TemperatureSummary& sum = r.temperature_summary();
  CHECK(sum.samples == 6600);
  CHECK(sum.accel_min_c == 23.5);
  CHECK(sum.gyro_max_c == 24.0);
  CHECK_THROWS_WITH(check_temperature_not_stuck(sum),
                    Catch::Contains("f.txt:6600: the accelerometer temperature reads exactly "
                                    "23.5 C over the whole log, 11.0 min") &&
                        Catch::Contains("f.txt:1") && Catch::Contains("a stuck sensor"));
  // Shorter than the span: passes (a short record may hold one quantized value).
  CHECK_NOTHROW(check_temperature_not_stuck(sum, 700.0));
  // One count of change in 11 min is not stuck; the gyro's column, still constant, is named.
  text.replace(text.rfind(",23.5,"), 6, ",23.6,");
  test::write_file(dir + "/f.txt", text);
  LogReader r2(f);
  read_all(r2);
  CHECK_THROWS_WITH(check_temperature_not_stuck(r2.temperature_summary()),
                    Catch::Contains("the gyro temperature reads exactly 24 C"));
  // Both varying: not stuck.
  std::string g;
  for (int k = 1; k <= 6600; ++k)
    g += number_text(0.1 * k) + ",0,0,0,0,0,9.8," + number_text(20.0 + 1e-3 * k) + "," +
         number_text(24.0 + 1e-4 * k) + "\n";
  test::write_file(dir + "/f.txt", g);
  LogReader r3(f);
  read_all(r3);
  CHECK_NOTHROW(check_temperature_not_stuck(r3.temperature_summary()));
  // A log without temperatures passes.
  CHECK_NOTHROW(check_temperature_not_stuck(TemperatureSummary{}));
}

TEST_CASE("Temperature: split per-triad files, each triad's own or one file's for the unit",
          "[log][temperature][split]") {
  const std::string dir = test::temp_dir("temp_split");
  // Row k (from 1): accelerometer 30 + 0.01 k C, gyro `gyro_temp(k)`.
  auto write_files = [&](const std::function<std::string(int)>& gyro_temp) {
    std::string a, g;
    for (int k = 1; k <= 20; ++k) {
      const std::string t = number_text(0.01 * k);
      a += t + " 0 0 9.8 " + number_text(30.0 + 0.01 * k) + "\n";
      g += t + " " + gyro_temp(k) + " 0.1 0 0\n";
    }
    test::write_file(dir + "/a.txt", a);
    test::write_file(dir + "/g.txt", g);
  };
  auto gyro_31 = [](int k) { return number_text(31.0 - 0.01 * k); };
  write_files(gyro_31);
  const std::string files =
      "[log]\naccel_file = a.txt\ngyro_file = g.txt\ndelimiter = whitespace\n" +
      std::string(kRateKeys);
  const std::string both = "accel_columns = t x y z temp\ngyro_columns = t temp x y z\n";
  auto read_split = [&](const std::string& cols) {
    test::write_file(dir + "/s.ini", files + cols);
    LogReader r(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0));
    return read_all(r);
  };
  auto s = read_split(both);
  REQUIRE(s.size() == 20);
  for (std::size_t k = 0; k < s.size(); ++k) {
    const int n = static_cast<int>(k) + 1;
    CHECK(s[k].accel_temperature_c == 30.0 + 0.01 * n);
    CHECK(s[k].gyro_temperature_c == 31.0 - 0.01 * n);
    CHECK(s[k].dtheta_b.x() == Approx(0.001));
    CHECK(s[k].dv_b.z() == Approx(0.098));
  }
  // Only the gyro file has one: the unit's temperature (the accelerometer file's column skipped).
  s = read_split("accel_columns = t x y z -\ngyro_columns = t temp x y z\n");
  REQUIRE(s.size() == 20);
  CHECK(s[4].accel_temperature_c == s[4].gyro_temperature_c);
  CHECK(s[4].gyro_temperature_c == Approx(31.0 - 0.05));
  // Errors name the file the temperature is in.
  auto split_error = [&] {
    return read_error(
        [&] { return LogReader(LogFormat::from_ini(IniFile(dir + "/s.ini"), dir, 100.0)); });
  };
  write_files([&](int k) { return k == 10 ? std::string("nan") : gyro_31(k); });
  CHECK_THAT(split_error(), Catch::Contains("g.txt:10: field 2 (temperature) is NaN"));
  write_files([&](int k) { return k == 10 ? std::string("39.9") : gyro_31(k); });
  test::write_file(dir + "/s.ini", files + both);
  CHECK_THAT(split_error(), Catch::Contains("g.txt:10: gyro temperature jumps to 39.9 C"));
  // The temperature keys need a temp column in one of the files.
  test::write_file(dir + "/s.ini", files + "temperature_unit = K\n");
  CHECK_THAT(config_error(dir + "/s.ini", dir),
             Catch::Contains("s.ini:8") &&
                 Catch::Contains("neither accel_columns nor gyro_columns names temp"));
  test::write_file(dir + "/s.ini", files + "accel_columns = t x y z warmth\n");
  CHECK_THAT(config_error(dir + "/s.ini", dir), Catch::Contains("known: t x y z temp"));
}

TEST_CASE("Temperature: one file per dwell, custom and native; every file has them or none",
          "[log][temperature][segments]") {
  const std::string dir = test::temp_dir("temp_segments");
  std::filesystem::copy_file(data_path("segments/plan.ini"), dir + "/plan.ini");
  // Custom: pos<d>.csv with a temperature column 20 + d C (each file checked on its own).
  for (int d = 1; d <= 3; ++d) {
    std::ifstream in(data_path("segments/pos" + std::to_string(d) + ".csv"));
    std::string out;
    for (std::string l; std::getline(in, l);) out += l + "," + std::to_string(20 + d) + "\n";
    test::write_file(dir + "/pos" + std::to_string(d) + ".csv", out);
  }
  test::write_file(dir + "/session.ini",
                   "[session]\nrate = 100 Hz\nplan = plan.ini\n[log]\nformat = custom\n"
                   "files = pos1.csv pos2.csv pos3.csv\ncolumns = t gx gy gz ax ay az temp\n"
                   "gyro = rate\ngyro_unit = deg/s\naccel = rate\naccel_unit = g\n");
  {
    LogReader r(Session::load(dir + "/session.ini").log);
    const auto s = read_all(r);
    REQUIRE(s.size() == 24);
    CHECK(s[0].accel_temperature_c == 21.0);
    CHECK(s[8].gyro_temperature_c == 22.0);  // dwell 2's first sample
    CHECK(s[23].accel_temperature_c == 23.0);
    CHECK(r.temperature_summary().samples == 24);
    CHECK(r.temperature_summary().accel_max_c == 23.0);
  }
  // Native: files written with temperatures; one without them is an error naming it.
  const Session plain = Session::load(data_path("segments/session.ini"));
  LogReader source(plain.log);
  const auto samples = read_all(source);
  auto write_native = [&](const std::string& name, std::size_t from, std::size_t to, bool temp) {
    LogWriter w(dir + "/" + name, 100.0, false, temp);
    for (std::size_t k = from; k < to; ++k) {
      ImuSample s = samples[k];
      s.has_temperature = temp;
      s.accel_temperature_c = 40.0 + 0.125 * static_cast<double>(k);
      s.gyro_temperature_c = -10.5;
      w.write(s);
    }
    w.close();
  };
  write_native("n1.csv", 0, 8, true);
  write_native("n2.csv", 8, 18, true);
  write_native("n3.csv", 18, 24, true);
  test::write_file(dir + "/native.ini",
                   "[session]\nrate = 100 Hz\nplan = plan.ini\n[log]\nformat = sinscal\n"
                   "files = n1.csv n2.csv n3.csv\n");
  {
    LogReader r(Session::load(dir + "/native.ini").log);
    const auto s = read_all(r);
    REQUIRE(s.size() == 24);
    for (std::size_t k = 0; k < s.size(); ++k) {
      CHECK(s[k].accel_temperature_c == 40.0 + 0.125 * static_cast<double>(k));
      CHECK(s[k].gyro_temperature_c == -10.5);
      CHECK(s[k].dtheta_b == samples[k].dtheta_b);
    }
  }
  write_native("n2.csv", 8, 18, false);
  CHECK_THAT(read_error([&] { return LogReader(Session::load(dir + "/native.ini").log); }),
             Catch::Contains("n2.csv:4: this file has no temperature columns but") &&
                 Catch::Contains("n1.csv has them"));
}

TEST_CASE("Temperature: the native log round-trips them, and is unchanged without them",
          "[log][temperature]") {
  const std::string dir = test::temp_dir("temp_native");
  std::vector<ImuSample> in;
  for (int k = 1; k <= 200; ++k) {
    ImuSample s;
    s.t = 0.01 * k;
    s.dt = 0.01;
    s.dtheta_b = Vector3d(1e-7 * k, -3.3e-6 / k, 0.1 / 3.0);
    s.dv_b = Vector3d(0.0981 / 7.0, -1e-5, 0.0980665);
    s.has_table = true;
    s.table_outer = 0.01 * k;
    s.table_inner = -0.02 * k;
    s.has_temperature = true;
    s.accel_temperature_c = 21.0 + 1.0 / 3.0 + 1e-3 * k;
    s.gyro_temperature_c = 22.0 - 1e-3 * k;
    in.push_back(s);
  }
  for (const bool table : {false, true}) {
    CAPTURE(table);
    LogWriter w(dir + "/imu.csv", 100.0, table, true);
    for (const auto& s : in) w.write(s);
    w.close();
    LogReader r(LogFormat::native_format(dir + "/imu.csv", 100.0));
    const auto out = read_all(r);
    REQUIRE(out.size() == in.size());
    for (std::size_t k = 0; k < in.size(); ++k) {
      CHECK(out[k].has_temperature);
      CHECK(out[k].has_table == table);
      CHECK(out[k].accel_temperature_c == in[k].accel_temperature_c);  // shortest exact text
      CHECK(out[k].gyro_temperature_c == in[k].gyro_temperature_c);
      CHECK(out[k].dv_b == in[k].dv_b);
    }
    std::ifstream text(dir + "/imu.csv");
    std::string line;
    for (int i = 0; i < 3; ++i) std::getline(text, line);
    CHECK(line == std::string("t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],"
                              "dv_y [m/s],dv_z [m/s]") +
                      (table ? ",outer [deg],inner [deg]" : "") +
                      ",temperature_accel [C],temperature_gyro [C]");
  }
  // Without the flag: the format of before, byte for byte, whatever the samples carry.
  ImuSample plain = in[0];
  plain.t = 0.5;
  plain.dtheta_b = Vector3d(0.25, -0.125, 1.0);
  plain.dv_b = Vector3d(2.0, 0.0, -0.5);
  LogWriter w(dir + "/plain.csv", 100.0);
  w.write(plain);
  w.close();
  CHECK(file_text(dir + "/plain.csv") ==
        "# sinscal IMU log, format 1: increments over (t - dt, t], body axes\n# rate_hz = 100\n"
        "t [s],dtheta_x [rad],dtheta_y [rad],dtheta_z [rad],dv_x [m/s],dv_y [m/s],dv_z [m/s]\n"
        "0.5,0.25,-0.125,1,2,0,-0.5\n");
  // A writer that declares them refuses a sample without them; a bad native value is checked.
  LogWriter w2(dir + "/imu2.csv", 100.0, false, true);
  CHECK_THROWS_AS(w2.write(ImuSample{}), std::invalid_argument);
  std::string text = file_text(dir + "/imu.csv");
  std::size_t line8 = 0;
  for (int i = 0; i < 7; ++i) line8 = text.find('\n', line8) + 1;
  const std::size_t last_comma = text.rfind(',', text.find('\n', line8));
  text.replace(last_comma + 1, text.find('\n', line8) - last_comma - 1, "250");
  test::write_file(dir + "/bad.csv", text);
  CHECK_THAT(
      read_error([&] { return LogReader(LogFormat::native_format(dir + "/bad.csv", 100.0)); }),
      Catch::Contains("bad.csv:8: gyro temperature reads 250 C, outside"));
}
