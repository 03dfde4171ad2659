// sinscal plot-convergence: a Kalman monitor file drawn to PNG with gnuplot.
#include <cstdio>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "report/monitor.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

int cmd_plot_convergence(const std::vector<std::string>& args) {
  po::options_description d("sinscal plot-convergence options");
  std::string monitor_path, out_path, session_path, sensor_path;
  std::vector<std::string> families;
  ConvergencePlotOptions o;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("monitor", po::value(&monitor_path)->required(),
       "monitor JSON lines (calibrate --method kf --monitor)")
      ("out", po::value(&out_path)->required(), "PNG to write (the gnuplot script goes beside it, .gp)")
      ("family", po::value(&families)->composing(),
       "coefficient family to draw, e.g. gyro.scale (repeatable; default: all)")
      ("session", po::value(&session_path),
       "session.ini: draw its truth (simulations) and its sensor profile's sigma targets")
      ("sensor", po::value(&sensor_path), "sensor profile whose [targets] are drawn")
      ("width", po::value(&o.width_px)->default_value(1400), "picture width [px]")
      ("row-height", po::value(&o.row_height_px)->default_value(260),
       "height of each family's row [px]");
  // clang-format on
  if (!parse(args, d,
             "Usage: sinscal plot-convergence --monitor M.jsonl --out conv.png [--session S]\n"
             "Draws, per coefficient family, the estimates and their sigma (log scale, with the\n"
             "target) over time, and the NIS per dof and the converged verdict, with gnuplot."))
    return 0;
  if (o.width_px < 200 || o.row_height_px < 80 || o.width_px > 20000 || o.row_height_px > 5000)
    throw UsageError("--width must be 200 to 20000 px and --row-height 80 to 5000 px");
  refuse_overwrite(
      {{"monitor file", monitor_path}, {"session", session_path}, {"sensor profile", sensor_path}},
      {{"--out", out_path}, {"gnuplot script", convergence_script_path(out_path)}});
  const MonitorSeries series = read_monitor(monitor_path);
  if (series.cut_last_line)
    std::fprintf(stderr,
                 "sinscal plot-convergence: note: %s: the last line is cut (the run writing it was "
                 "killed): drawn up to the line before\n",
                 monitor_path.c_str());
  o.families = families;
  if (!session_path.empty()) {
    const Session session = Session::load(session_path);
    o.truth = load_truth(session, series.body_frame == "accelerometer triad");
    if (sensor_path.empty() && !session.sensor_file.empty()) sensor_path = session.sensor_file;
  }
  if (!sensor_path.empty()) o.sigma_targets = SensorProfile::load(sensor_path).sigma_targets;
  const ConvergencePlot plot = plot_convergence(series, o, out_path);
  std::printf(
      "Convergence of %zu records (t = %.1f to %.1f s), %zu families, drawn to %s (%d x %d "
      "px)\ngnuplot script: %s\n",
      series.t.size(), series.t.front(), series.t.back(), plot.families.size(), plot.png.c_str(),
      plot.width_px, plot.height_px, plot.script.c_str());
  return 0;
}

}  // namespace sinscal::cli
