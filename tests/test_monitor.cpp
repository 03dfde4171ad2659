// Convergence monitor files read back, and drawn with gnuplot.
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>

#include "helpers.hpp"
#include "models/units.hpp"
#include "report/monitor.hpp"

using namespace sinscal;

namespace {
// Three records as `calibrate --monitor` writes them; time_delay appears from the second on.
const char* kMonitor =
    R"({"t":10.0,"nis_per_dof":0.9,"converged":false,"body_frame":"table","coefficients":{"gyro.bias.x":[0.2,0.5],"gyro.bias.y":[-0.1,0.4]}})"
    "\n"
    R"({"t":20.0,"nis_per_dof":1.1,"converged":false,"body_frame":"table","coefficients":{"gyro.bias.x":[0.25,0.05],"gyro.bias.y":[-0.12,0.04],"time_delay":[4.0,1.0]}})"
    "\n\n"
    R"({"t":30.0,"nis_per_dof":1.0,"converged":true,"body_frame":"table","coefficients":{"gyro.bias.y":[-0.11,0.004],"gyro.bias.x":[0.24,0.003],"time_delay":[5.0,0.01]}})"
    "\n";

// Width and height from a PNG's IHDR chunk (big-endian at bytes 16 and 20); 0 if not a PNG.
std::pair<int, int> png_size(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[24] = {};
  in.read(reinterpret_cast<char*>(h), 24);
  const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (!in || !std::equal(sig, sig + 8, h)) return {0, 0};
  auto be = [&](int at) {
    return (h[at] << 24) | (h[at + 1] << 16) | (h[at + 2] << 8) | h[at + 3];
  };
  return {be(16), be(20)};
}
}  // namespace

TEST_CASE("Monitor file read back as series, catalog order, gaps as NaN", "[monitor]") {
  const std::string dir = test::temp_dir("monitor_read");
  test::write_file(dir + "/m.jsonl", kMonitor);
  const MonitorSeries m = read_monitor(dir + "/m.jsonl");
  REQUIRE(m.t == std::vector<double>{10.0, 20.0, 30.0});
  CHECK(m.nis_per_dof == std::vector<double>{0.9, 1.1, 1.0});
  CHECK(m.converged == std::vector<bool>{false, false, true});
  CHECK(m.body_frame == "table");
  REQUIRE(m.names == std::vector<std::string>{"gyro.bias.x", "gyro.bias.y", "time_delay"});
  CHECK(m.value[0] == std::vector<double>{0.2, 0.25, 0.24});
  CHECK(m.sigma[1] == std::vector<double>{0.4, 0.04, 0.004});
  CHECK(std::isnan(m.value[2][0]));
  CHECK(m.value[2][2] == 5.0);
}

TEST_CASE("Monitor file errors name file and line", "[monitor]") {
  const std::string dir = test::temp_dir("monitor_bad");
  const std::string first = std::string(kMonitor).substr(0, std::string(kMonitor).find('\n') + 1);
  test::write_file(dir + "/cut.jsonl", first + "{\"t\":20.0,\"nis_per\n");
  CHECK_THROWS_WITH(read_monitor(dir + "/cut.jsonl"),
                    Catch::Contains("cut.jsonl:2: not a monitor record"));
  test::write_file(dir + "/back.jsonl", first + first);
  CHECK_THROWS_WITH(read_monitor(dir + "/back.jsonl"),
                    Catch::Contains("back.jsonl:2: time 10.000000 s does not increase"));
  test::write_file(dir + "/unknown.jsonl",
                   R"({"t":1,"nis_per_dof":1,"coefficients":{"gyro.bogus.x":[1,2]}})");
  CHECK_THROWS_WITH(read_monitor(dir + "/unknown.jsonl"),
                    Catch::Contains("unknown.jsonl:1: unknown coefficient 'gyro.bogus.x'"));
  test::write_file(dir + "/empty.jsonl", "\n");
  CHECK_THROWS_WITH(read_monitor(dir + "/empty.jsonl"), Catch::Contains("no monitor records"));
}

TEST_CASE("Monitor file: a last line cut by a kill is skipped, a complete one is a record",
          "[monitor]") {
  const std::string dir = test::temp_dir("monitor_cut");
  const std::string all = kMonitor;
  const std::string two = all.substr(0, all.rfind('\n', all.size() - 2) + 1);  // first two lines
  // Killed while writing the third record: no line end, not JSON.
  test::write_file(dir + "/killed.jsonl", two + all.substr(two.size(), 40));
  const MonitorSeries killed = read_monitor(dir + "/killed.jsonl");
  CHECK(killed.t == std::vector<double>{10.0, 20.0});
  CHECK(killed.cut_last_line);
  // The whole third record without its line end is a record.
  test::write_file(dir + "/no_end.jsonl", all.substr(0, all.size() - 1));
  const MonitorSeries whole = read_monitor(dir + "/no_end.jsonl");
  CHECK(whole.t == std::vector<double>{10.0, 20.0, 30.0});
  CHECK_FALSE(whole.cut_last_line);
  // A cut line followed by another is not a kill's: an error naming its line.
  test::write_file(dir + "/middle.jsonl", all.substr(0, 40) + "\n" + two);
  CHECK_THROWS_WITH(read_monitor(dir + "/middle.jsonl"),
                    Catch::Contains("middle.jsonl:1: not a monitor record"));
  // Killed before its first record was whole: nothing to draw, said so.
  test::write_file(dir + "/first.jsonl", all.substr(0, 40));
  CHECK_THROWS_WITH(read_monitor(dir + "/first.jsonl"), Catch::Contains("no monitor records"));
}

TEST_CASE("Convergence plot: a row per family, targets and truth drawn, PNG of that size",
          "[monitor]") {
  const std::string dir = test::temp_dir("monitor_plot");
  test::write_file(dir + "/m.jsonl", kMonitor);
  const MonitorSeries m = read_monitor(dir + "/m.jsonl");
  ConvergencePlotOptions o;
  o.sigma_targets["gyro.bias"] = 0.005 * units::deg_per_h;
  o.truth["gyro.bias.x"].value = 0.245;
  o.width_px = 900;
  o.row_height_px = 200;
  ConvergencePlot layout;
  const std::string script = convergence_plot_script(m, o, dir + "/c.png", &layout);
  CHECK(layout.families == std::vector<std::string>{"gyro.bias", "time_delay"});
  CHECK(layout.height_px == 3 * 200);  // NIS row + two families
  // The target in the family's unit, the truth at its value, the missing first delay as '?'.
  CHECK_THAT(script, Catch::Contains("0.005 with lines dt 2 lw 2 lc 'black' title 'target'"));
  CHECK_THAT(script, Catch::Contains("0.245 with lines dt 2 lc 1 notitle"));
  CHECK_THAT(script, Catch::Contains("10 ?"));
  CHECK_THAT(script, Catch::Contains("set multiplot layout 3,2"));

  const ConvergencePlot plot = plot_convergence(m, o, dir + "/c.png");
  CHECK(plot.script == dir + "/c.gp");
  CHECK(png_size(dir + "/c.png") == std::make_pair(900, 600));

  o.families = {"time_delay"};
  CHECK(plot_convergence(m, o, dir + "/d.png").height_px == 2 * 200);
  CHECK(png_size(dir + "/d.png") == std::make_pair(900, 400));
  o.families = {"accel.k2"};
  CHECK_THROWS_WITH(
      plot_convergence(m, o, dir + "/e.png"),
      Catch::Contains("family 'accel.k2' is not in") && Catch::Contains("gyro.bias time_delay"));
}

TEST_CASE("Convergence plot without gnuplot: the error names the package", "[monitor]") {
  const std::string dir = test::temp_dir("monitor_nognuplot");
  test::write_file(dir + "/m.jsonl", kMonitor);
  ConvergencePlotOptions o;
  o.gnuplot = "sinscal-test-no-such-program";
  CHECK_THROWS_WITH(
      plot_convergence(read_monitor(dir + "/m.jsonl"), o, dir + "/c.png"),
      Catch::Contains("cannot run sinscal-test-no-such-program") && Catch::Contains("gnuplot-nox"));
}
