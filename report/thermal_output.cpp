#include "report/thermal_output.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "report/gnuplot.hpp"
#include "report/output.hpp"

namespace sinscal {

ResultCoefficients thermal_coefficients(const ThermalFit& fit) {
  const auto& cat = coefficient_catalog();
  ResultCoefficients out;
  for (std::size_t k = 0; k < fit.catalog.size(); ++k) {
    const CoefficientInfo& info = cat[static_cast<std::size_t>(fit.catalog[k])];
    const auto i = static_cast<Eigen::Index>(k);
    ResultCoefficient c;
    c.value = fit.value(i) / info.si_per_unit;
    c.sigma = std::sqrt(std::max(0.0, fit.covariance(i, i))) / info.si_per_unit;
    c.unit = info.unit;
    out[info.name] = c;
  }
  return out;
}

nlohmann::ordered_json thermal_section(const ThermalFit& fit,
                                       const std::vector<SoakRecord>& soaks) {
  nlohmann::ordered_json j;
  j["method"] = "soaks";
  j["reference_temperature_c"] = fit.options.reference_temperature_c;
  auto& s = j["soaks"];
  s = nlohmann::ordered_json::array();
  for (const auto& r : soaks)
    s.push_back({{"session", r.session},
                 {"result", r.result},
                 {"accel_temperature_c", r.accel_temperature_c},
                 {"gyro_temperature_c", r.gyro_temperature_c},
                 {"temperature_span_c", r.span_c},
                 {"nis_per_dof", r.nis_per_dof}});
  auto& d = j["degrees"];
  d = nlohmann::ordered_json::array();
  for (const auto& t : fit.degrees)
    d.push_back({{"family", t.family},
                 {"degree", t.degree},
                 {"max_degree", t.max_degree},
                 {"chi2", t.chi2},
                 {"dof_step", t.dof_step},
                 {"threshold", t.threshold}});
  j["significance"] = fit.options.significance;
  j["fit"] = {{"chi2", fit.chi2}, {"dof", fit.dof}, {"p_value", fit.p_value}};
  return j;
}

void write_thermal_table(const std::string& path, const ThermalFit& fit, double from_c, double to_c,
                         double step_c) {
  const auto& cat = coefficient_catalog();
  std::vector<int> base;
  for (int c : fit.catalog)
    if (!coefficient_family_info(cat[static_cast<std::size_t>(c)].family).thermal())
      base.push_back(c);
  // The row count as a double first: a tiny step gives a count no int holds.
  const double span = std::floor((to_c - from_c) / step_c + 1e-9);
  if (!(std::isfinite(span) && step_c > 0.0 && span >= 0.0 && span < kMaxThermalTableRows))
    throw std::invalid_argument(path + ": a table from " + std::to_string(from_c) + " to " +
                                std::to_string(to_c) + " C every " + std::to_string(step_c) +
                                " C would exceed " + std::to_string(kMaxThermalTableRows) +
                                " rows (or its bounds are not numbers)");
  const int steps = static_cast<int>(span);
  write_atomically(path, [&](std::ostream& out) {
    out << "# sinscal thermal compensation table: each coefficient at the temperature of the row "
           "(deg C), value and 1-sigma, from the thermal fit (T0 = "
        << fit.options.reference_temperature_c << " C); units:";
    for (int c : base)
      out << " " << cat[static_cast<std::size_t>(c)].name << " "
          << cat[static_cast<std::size_t>(c)].unit << ";";
    out << "\ntemperature_c";
    for (int c : base)
      out << "," << cat[static_cast<std::size_t>(c)].name << ","
          << cat[static_cast<std::size_t>(c)].name << ".sigma";
    out << "\n";
    char buf[64];
    for (int k = 0; k <= steps; ++k) {
      const double T = from_c + k * step_c;
      std::snprintf(buf, sizeof buf, "%.6g", T);
      out << buf;
      for (int c : base) {
        const auto [v, s] = fit.at(c, T);
        const double u = cat[static_cast<std::size_t>(c)].si_per_unit;
        std::snprintf(buf, sizeof buf, ",%.9g,%.4g", v / u, s / u);
        out << buf;
      }
      out << "\n";
    }
  });
}

std::string thermal_plot_script(const ThermalFit& fit, const std::vector<SoakEstimate>& soaks,
                                const std::string& png_path) {
  const auto& cat = coefficient_catalog();
  std::vector<const ThermalDegreeTest*> varying;
  for (const auto& t : fit.degrees)
    if (t.degree > 0) varying.push_back(&t);
  double lo = 1e9, hi = -1e9;
  for (const auto& e : soaks) {
    lo = std::min({lo, e.gyro_temperature_c, e.accel_temperature_c});
    hi = std::max({hi, e.gyro_temperature_c, e.accel_temperature_c});
  }
  const int columns = varying.size() > 1 ? 2 : 1;
  const int rows = std::max(1, static_cast<int>((varying.size() + 1) / 2));
  std::ostringstream g;
  g << "# Written by sinscal thermal; gnuplot this file to redraw, the data are inline.\n"
    << "set terminal pngcairo size " << 700 * columns << "," << 380 * rows
    << " font 'sans,10' noenhanced\n"
    << "if (!exists('output')) output = " << gnuplot_quoted(png_path) << "\n"
    << "set output output\nset grid\nset key outside right\nset xlabel 'temperature [C]'\n"
    << "set xrange [" << lo - 5.0 << ":" << hi + 5.0 << "]\n"
    << "set multiplot layout " << rows << "," << columns << " title "
    << gnuplot_quoted(
           "sinscal thermal: per-soak estimates (1-sigma bars) and the fit (dashed), "
           "T0 = " +
           gnuplot_number(fit.options.reference_temperature_c) + " C")
    << "\n";
  for (const ThermalDegreeTest* t : varying) {
    // The family's coefficients, as the soaks and the fit have them.
    std::vector<int> members;
    for (int c : fit.catalog)
      if (cat[static_cast<std::size_t>(c)].family == t->family) members.push_back(c);
    if (members.empty()) continue;
    const CoefficientInfo& first = cat[static_cast<std::size_t>(members.front())];
    const double u = first.si_per_unit;
    const bool accel = coefficient_family_info(t->family).output == FamilyOutput::Accel;
    g << "$soaks_" << members.front() << " << EOD\n";
    for (const auto& e : soaks) {
      g << gnuplot_number(accel ? e.accel_temperature_c : e.gyro_temperature_c);
      for (int c : members) {
        const auto it = std::find(e.catalog.begin(), e.catalog.end(), c);
        if (it == e.catalog.end()) {
          g << " ? ?";
          continue;
        }
        const auto i = static_cast<Eigen::Index>(it - e.catalog.begin());
        g << " " << gnuplot_number(e.value(i) / u) << " "
          << gnuplot_number(std::sqrt(e.covariance(i, i)) / u);
      }
      g << "\n";
    }
    g << "EOD\n$fit_" << members.front() << " << EOD\n";
    for (int k = 0; k <= 100; ++k) {
      const double T = lo - 5.0 + (hi - lo + 10.0) * k / 100.0;
      g << gnuplot_number(T);
      for (int c : members) g << " " << gnuplot_number(fit.at(c, T).first / u);
      g << "\n";
    }
    g << "EOD\nset title " << gnuplot_quoted(t->family + ": degree " + std::to_string(t->degree))
      << "\nset ylabel " << gnuplot_quoted("[" + first.unit + "]") << "\nplot ";
    for (std::size_t m = 0; m < members.size(); ++m) {
      const std::string name = cat[static_cast<std::size_t>(members[m])].name;
      const std::string component = name.substr(t->family.size() + 1);
      const auto col = 2 + 2 * m;
      g << (m ? ", " : "") << "$soaks_" << members.front() << " using 1:" << col << ":" << col + 1
        << " with yerrorbars lc " << m + 1 << " pt 7 ps 0.6 title " << gnuplot_quoted(component)
        << ", $fit_" << members.front() << " using 1:" << m + 2 << " with lines dt 2 lc " << m + 1
        << " notitle";
    }
    g << "\n";
  }
  g << "unset multiplot\nset output\n";
  return g.str();
}

void plot_thermal(const ThermalFit& fit, const std::vector<SoakEstimate>& soaks,
                  const std::string& png_path, const std::string& gnuplot) {
  const std::string script_path = gnuplot_script_path(png_path);
  const std::string script = thermal_plot_script(fit, soaks, png_path);
  write_atomically(script_path, [&](std::ostream& out) { out << script; });
  run_gnuplot(gnuplot, script_path, png_path);
}

}  // namespace sinscal
