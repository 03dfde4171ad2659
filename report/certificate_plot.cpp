// The certificate's convergence plot: per coefficient family, the largest sigma of its
// coefficients over time from the Kalman filter's monitor file, relative to the family's sigma
// target when the sensor profile sets one (else to its first record), drawn by gnuplot and
// inlined in the page.
#include <unistd.h>  // getpid: a temporary directory of this run's own

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "models/coefficient_families.hpp"
#include "models/sensor_profile.hpp"
#include "report/certificate.hpp"
#include "report/gnuplot.hpp"
#include "report/monitor.hpp"

namespace sinscal {

namespace {

struct FamilyCurve {
  std::string family;
  std::vector<double> ratio;  // per record
};

// The largest sigma of each family per record, over its target (or its first record's).
std::vector<FamilyCurve> family_curves(const MonitorSeries& s,
                                       const std::map<std::string, double>& targets,
                                       bool& by_target) {
  std::map<std::string, std::vector<double>> worst;
  for (std::size_t i = 0; i < s.names.size(); ++i) {
    auto& w = worst[coefficient_info(s.names[i]).family];
    w.resize(s.t.size(), std::nan(""));
    for (std::size_t k = 0; k < s.t.size(); ++k)
      if (std::isfinite(s.sigma[i][k]) && !(w[k] >= s.sigma[i][k])) w[k] = s.sigma[i][k];
  }
  by_target = !targets.empty();
  for (const auto& [family, w] : worst) by_target &= targets.count(family) > 0;
  std::vector<FamilyCurve> out;
  for (const auto& [family, w] : worst) {
    double scale = std::nan("");
    if (by_target) {
      scale = targets.at(family) / coefficient_family_info(family).si_per_unit();
    } else {
      for (double v : w)
        if (std::isfinite(v) && v > 0.0) {
          scale = v;
          break;
        }
    }
    FamilyCurve c{family, {}};
    for (double v : w) c.ratio.push_back(scale > 0.0 ? v / scale : std::nan(""));
    out.push_back(c);
  }
  return out;
}

std::string plot_script(const MonitorSeries& s, const std::vector<FamilyCurve>& curves,
                        bool by_target, double converged_at_t) {
  std::ostringstream g;
  g << "set terminal pngcairo size 1200,560 font 'sans,11' noenhanced\n"
    << "set output output\nset datafile missing '?'\n"
    << "set logscale y\nset grid\nset format y '%g'\n"
    << "set key outside right top vertical samplen 2\n"
    << "set xlabel 'time [s]'\n"
    << "set ylabel "
    << gnuplot_quoted(by_target ? "largest sigma / target" : "largest sigma / first") << "\n";
  if (by_target)
    g << "set arrow from graph 0, first 1 to graph 1, first 1 nohead dt 2 lw 2 lc rgb '#c00000'\n";
  if (converged_at_t >= 0.0)
    g << "set arrow from " << gnuplot_number(converged_at_t) << ", graph 0 to "
      << gnuplot_number(converged_at_t) << ", graph 1 nohead dt 3 lc rgb '#2e7d32'\n";
  g << "$data << EOD\n";
  for (std::size_t k = 0; k < s.t.size(); ++k) {
    g << gnuplot_number(s.t[k]);
    for (const auto& c : curves) g << " " << gnuplot_number(c.ratio[k]);
    g << "\n";
  }
  g << "EOD\nplot ";
  for (std::size_t i = 0; i < curves.size(); ++i)
    g << (i ? ", \\\n     " : "") << "$data using 1:" << i + 2 << " with lines lw 2 dt "
      << (i < 8 ? 1 : 2) << " title " << gnuplot_quoted(curves[i].family);
  g << "\n";
  return g.str();
}

}  // namespace

CertificateSection convergence_section(const std::string& monitor_path,
                                       const std::string& sensor_profile, double converged_at_t,
                                       const std::string& gnuplot) {
  namespace fs = std::filesystem;
  CertificateSection sec;
  sec.title = "Convergence";
  std::error_code ec;
  if (monitor_path.empty() || !fs::is_regular_file(monitor_path, ec)) {
    sec.paragraphs.push_back(
        monitor_path.empty()
            ? "Not available: the calibration wrote no monitor file (calibrate --monitor FILE)."
            : "Not available: the monitor file " + monitor_path + " is not there any more.");
    return sec;
  }
  const MonitorSeries series = read_monitor(monitor_path);
  if (series.t.size() < 2) {
    sec.paragraphs.push_back("Not available: the monitor file " + monitor_path +
                             " holds fewer than two records.");
    return sec;
  }
  std::map<std::string, double> targets;
  if (!sensor_profile.empty() && fs::is_regular_file(sensor_profile, ec))
    targets = SensorProfile::load(sensor_profile).sigma_targets;
  bool by_target = false;
  const auto curves = family_curves(series, targets, by_target);
  const fs::path dir = fs::temp_directory_path() / ("sinscal-report-" + std::to_string(getpid()));
  fs::create_directories(dir);
  const std::string script = (dir / "convergence.gp").string();
  const std::string png = (dir / "convergence.png").string();
  try {
    {
      std::ofstream out(script);
      out << plot_script(series, curves, by_target, converged_at_t);
      if (!out) throw std::runtime_error(script + ": cannot write");
    }
    try {
      run_gnuplot(gnuplot, script, png);
    } catch (const std::runtime_error& e) {  // the page says so; the certificate stands
      fs::remove_all(dir, ec);
      sec.paragraphs.push_back("Not available: the plot could not be drawn: " +
                               std::string(e.what()));
      return sec;
    }
    std::ifstream in(png, std::ios::binary);
    std::ostringstream bytes;
    bytes << in.rdbuf();
    sec.png = bytes.str();
  } catch (...) {
    fs::remove_all(dir, ec);
    throw;
  }
  fs::remove_all(dir, ec);
  sec.png_alt = "largest sigma of each coefficient family against time";
  sec.paragraphs.push_back(
      std::string("The largest 1-sigma of each coefficient family against log time, ") +
      (by_target ? "over the family's target in the sensor profile (dashed line: the target)"
                 : "over its value at the first record (the sensor profile's targets are not "
                   "available)") +
      (converged_at_t >= 0.0 ? "; dotted line: converged" : "") + ". From " + monitor_path + ", " +
      std::to_string(series.t.size()) + " records.");
  return sec;
}

}  // namespace sinscal
