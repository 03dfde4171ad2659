#include "report/allan_output.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "models/units.hpp"
#include "report/gnuplot.hpp"
#include "report/output.hpp"

namespace sinscal {

namespace {

const char* kAxis[3] = {"x", "y", "z"};

// Rows of both triads, one per cluster time (every channel has the same cluster times: the
// same record length and interval).
struct Channel {
  std::string name;
  const std::vector<AllanPoint>* points;
  const AllanFit* fit;
  double per_unit;
};

std::vector<Channel> channels(const AllanAnalysis& a) {
  std::vector<Channel> c;
  c.reserve(6);
  for (int i = 0; i < 3; ++i)
    c.push_back({std::string("gyro.") + kAxis[i], &a.gyro[static_cast<std::size_t>(i)],
                 &a.gyro_fit[static_cast<std::size_t>(i)], units::deg_per_h});
  for (int i = 0; i < 3; ++i)
    c.push_back({std::string("accel.") + kAxis[i], &a.accel[static_cast<std::size_t>(i)],
                 &a.accel_fit[static_cast<std::size_t>(i)], units::ug});
  for (const auto& ch : c)
    if (ch.points->size() != c.front().points->size())
      throw std::logic_error("Allan analysis: channels of different lengths");
  return c;
}

std::string number(double v) { return gnuplot_number(v); }

// One row of values per cluster time: tau, then adev, lower, upper, fit per channel (NaN for a
// fit that is not valid).
void rows(const AllanAnalysis& a, std::ostream& out, char sep) {
  const auto ch = channels(a);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < ch.front().points->size(); ++k) {
    const double tau = (*ch.front().points)[k].tau;
    out << number(tau);
    for (const auto& c : ch) {
      const AllanPoint& p = (*c.points)[k];
      const double fit = c.fit->valid ? c.fit->adev(p.tau) / c.per_unit : nan;
      out << sep << number(p.adev / c.per_unit) << sep << number(p.adev_low / c.per_unit) << sep
          << number(p.adev_high / c.per_unit) << sep << number(fit);
    }
    out << "\n";
  }
}

}  // namespace

void write_allan_csv(const std::string& path, const AllanAnalysis& a) {
  const auto ch = channels(a);
  write_atomically(path, [&](std::ostream& out) {
    out << "tau [s]";
    for (const auto& c : ch) {
      const std::string u = c.name[0] == 'g' ? " [deg/h]" : " [ug]";
      out << "," << c.name << " adev" << u << "," << c.name << " lower" << u << "," << c.name
          << " upper" << u << "," << c.name << " fit" << u;
    }
    out << "\n";
    std::ostringstream body;
    rows(a, body, ',');
    // A missing fit is an empty field in the CSV.
    std::string text = body.str();
    std::string clean;
    for (std::size_t i = 0; i < text.size(); ++i)
      if (text[i] != '?') clean += text[i];
    out << clean;
  });
}

namespace {

struct TermColumn {
  const char* gyro_name;
  const char* accel_name;
  double AllanFit::*value;
  double AllanFit::*sigma;
  double gyro_unit, accel_unit;  // SI per unit
  const char* gyro_unit_name;
  const char* accel_unit_name;
};

std::vector<TermColumn> term_columns() {
  using F = AllanFit;
  const double sqrt12 = std::sqrt(12.0);
  return {
      {"quantum", "quantum", &F::quantization, &F::quantization_sigma, units::arcsec / sqrt12,
       1.0 / sqrt12, "arcsec", "m/s"},
      {"arw", "vrw", &F::white, &F::white_sigma, units::deg_per_sqrt_h, units::ug_per_sqrt_hz,
       "deg/sqrt(h)", "ug/sqrt(Hz)"},
      {"bias_instability", "bias_instability", &F::floor_bias_instability,
       &F::floor_bias_instability_sigma, units::deg_per_h, units::ug, "deg/h", "ug"},
      {"flicker", "flicker", &F::bias_instability, &F::bias_instability_sigma, units::deg_per_h,
       units::ug, "deg/h", "ug"},
      {"rate_random_walk", "random_walk", &F::random_walk, &F::random_walk_sigma,
       units::deg_per_h_per_sqrt_h, units::ug_per_sqrt_h, "deg/h/sqrt(h)", "ug/sqrt(h)"},
      {"rate_ramp", "rate_ramp", &F::rate_ramp, &F::rate_ramp_sigma, units::deg_per_h / units::hour,
       units::ug / units::hour, "deg/h/h", "ug/h"},
  };
}

}  // namespace

void write_allan_terms_csv(const std::string& path, const AllanAnalysis& a) {
  const auto ch = channels(a);
  write_atomically(path, [&](std::ostream& out) {
    out << "channel,term,value,sigma,unit\n";
    for (const auto& c : ch) {
      const bool gyro = c.name[0] == 'g';
      for (const auto& t : term_columns()) {
        const double per = gyro ? t.gyro_unit : t.accel_unit;
        const double v = (*c.fit).*t.value / per, sd = (*c.fit).*t.sigma / per;
        out << c.name << "," << (gyro ? t.gyro_name : t.accel_name) << "," << number(v) << ","
            << (v != 0.0 ? number(sd) : std::string()) << ","
            << (gyro ? t.gyro_unit_name : t.accel_unit_name) << "\n";
      }
    }
  });
}

std::string allan_plot_script(const AllanAnalysis& a, const std::string& title,
                              const std::string& png_path) {
  std::ostringstream g;
  g << "# Written by sinscal allan: " << gnuplot_printable(title)
    << "\n# gnuplot this file to redraw; the data are inline.\n"
    << "set terminal pngcairo size 1400,560 font 'sans,10' noenhanced\n"
    << "if (!exists('output')) output = " << gnuplot_quoted(png_path) << "\n"
    << "set output output\nset datafile missing '?'\n"
    << "set logscale xy\nset grid xtics ytics mxtics mytics\nset format x '%g'\n"
    << "set format y '%g'\nset key top right\nset xlabel 'cluster time tau [s]'\n";
  g << "$allan << EOD\n";
  rows(a, g, ' ');
  g << "EOD\n";
  g << "set multiplot layout 1,2 title " << gnuplot_quoted("sinscal allan: " + title) << "\n";
  for (int triad = 0; triad < 2; ++triad) {
    const bool gyro = triad == 0;
    g << "set title "
      << gnuplot_quoted(gyro ? "gyros: Allan deviation (dashed: fitted model)"
                             : "accelerometers: Allan deviation (dashed: fitted "
                               "model)")
      << "\nset ylabel " << gnuplot_quoted(gyro ? "[deg/h]" : "[ug]") << "\nplot ";
    for (int i = 0; i < 3; ++i) {
      const int col = 2 + 4 * (3 * triad + i);
      g << (i ? ", " : "") << "$allan using 1:" << col << ":" << col + 1 << ":" << col + 2
        << " with yerrorlines lc " << i + 1 << " pt 7 ps 0.5 title '" << kAxis[i] << "', "
        << "$allan using 1:" << col + 3 << " with lines dt 2 lw 1.5 lc " << i + 1 << " notitle";
    }
    g << "\n";
  }
  g << "unset multiplot\nset output\n";
  return g.str();
}

void plot_allan(const AllanAnalysis& a, const std::string& title, const std::string& png_path,
                const std::string& script_path, const std::string& gnuplot) {
  const std::string script = allan_plot_script(a, title, png_path);
  write_atomically(script_path, [&](std::ostream& out) { out << script; });
  run_gnuplot(gnuplot, script_path, png_path);
}

}  // namespace sinscal
