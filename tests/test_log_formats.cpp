// Log formats labs and tools produce: a log split over one file per triad (imu_tk), one file per
// dwell of the plan, NovAtel RAWIMUSA / RAWIMUSXA ASCII logs; limits of the line reader.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
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
  const std::string data = test::source_path("../shared/data/xsens-mti-handheld");
  if (!std::filesystem::exists(data + "/xsens_acc.txt")) {
    WARN("shared data not present, skipped: " << data);
    return;
  }
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
