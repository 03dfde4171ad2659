#include "report/monitor.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "models/imu_error_model.hpp"
#include "models/sensor_profile.hpp"
#include "report/gnuplot.hpp"
#include "report/output.hpp"

namespace sinscal {

std::string monitor_line(const MonitorRecord& record) {
  nlohmann::ordered_json rec;
  rec["t"] = record.t;
  rec["nis_per_dof"] = record.nis_per_dof;
  rec["converged"] = record.converged;
  rec["body_frame"] = record.accel_triad_frame ? "accelerometer triad" : "table";
  nlohmann::ordered_json c = nlohmann::ordered_json::object();
  for (const auto& [name, e] : result_coefficients(record.estimates))
    if (!e.fixed_by_convention) c[name] = {e.value, *e.sigma};
  rec["coefficients"] = c;
  return rec.dump();
}

MonitorSeries read_monitor(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  const auto& catalog = coefficient_catalog();
  std::map<std::string, std::size_t> index;
  for (std::size_t i = 0; i < catalog.size(); ++i) index[catalog[i].name] = i;
  // Per catalog coefficient; names that never appear are dropped at the end.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<std::vector<double>> value(catalog.size()), sigma(catalog.size());
  MonitorSeries m;
  m.path = path;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::string where = path + ":" + std::to_string(number) + ": ";
    try {
      const auto rec = nlohmann::json::parse(line);
      const double t = rec.at("t").get<double>();
      if (!m.t.empty() && !(t > m.t.back()))
        throw std::runtime_error("time " + std::to_string(t) + " s does not increase");
      m.t.push_back(t);
      m.nis_per_dof.push_back(rec.at("nis_per_dof").get<double>());
      m.converged.push_back(rec.value("converged", false));
      if (rec.contains("body_frame")) m.body_frame = rec.at("body_frame").get<std::string>();
      for (auto& v : value) v.push_back(nan);
      for (auto& s : sigma) s.push_back(nan);
      for (const auto& [name, pair] : rec.at("coefficients").items()) {
        const auto it = index.find(name);
        if (it == index.end()) throw std::runtime_error("unknown coefficient '" + name + "'");
        if (!pair.is_array() || pair.size() != 2)
          throw std::runtime_error("coefficient '" + name + "' is not [estimate, sigma]");
        value[it->second].back() = pair[0].get<double>();
        sigma[it->second].back() = pair[1].get<double>();
      }
    } catch (const nlohmann::json::parse_error& e) {
      if (in.eof()) {  // the last line, without its newline: cut by a kill of the writer
        m.cut_last_line = true;
        break;
      }
      throw std::runtime_error(where + "not a monitor record: " + e.what());
    } catch (const nlohmann::json::exception& e) {
      throw std::runtime_error(where + "not a monitor record: " + e.what());
    } catch (const std::runtime_error& e) {
      throw std::runtime_error(where + e.what());
    }
  }
  if (m.t.empty()) throw std::runtime_error(path + ": no monitor records");
  for (std::size_t i = 0; i < catalog.size(); ++i) {
    bool present = false;
    for (double v : value[i]) present |= !std::isnan(v);
    if (!present) continue;
    m.names.push_back(catalog[i].name);
    m.value.push_back(std::move(value[i]));
    m.sigma.push_back(std::move(sigma[i]));
  }
  return m;
}

namespace {

std::string printable(const std::string& s) { return gnuplot_printable(s); }
std::string quoted(const std::string& s) { return gnuplot_quoted(s); }
std::string num(double v) { return gnuplot_number(v); }

}  // namespace

std::string convergence_plot_script(const MonitorSeries& series,
                                    const ConvergencePlotOptions& options,
                                    const std::string& png_path, ConvergencePlot* layout) {
  // Families in catalog order, each with its members' indices into the series.
  std::vector<std::pair<std::string, std::vector<std::size_t>>> families;
  for (std::size_t i = 0; i < series.names.size(); ++i) {
    const std::string f = coefficient_family(series.names[i]);
    if (families.empty() || families.back().first != f) families.push_back({f, {}});
    families.back().second.push_back(i);
  }
  if (!options.families.empty()) {
    std::vector<std::pair<std::string, std::vector<std::size_t>>> chosen;
    for (const auto& want : options.families) {
      bool found = false;
      for (const auto& f : families)
        if (f.first == want) {
          chosen.push_back(f);
          found = true;
        }
      if (!found) {
        std::string have;
        for (const auto& f : families) have += " " + f.first;
        throw std::invalid_argument("family '" + want + "' is not in " + series.path +
                                    " (it has:" + have + ")");
      }
    }
    families = chosen;
  }
  const int rows = static_cast<int>(families.size()) + 1;
  const int height = rows * options.row_height_px;
  std::ostringstream g;
  g << "# Written by sinscal plot-convergence from " << printable(series.path)
    << "\n# gnuplot this file to redraw; the data are inline.\n"
    << "set terminal pngcairo size " << options.width_px << "," << height
    << " font 'sans,9' noenhanced\n"
    << "if (!exists('output')) output = " << quoted(png_path) << "\n"
    << "set output output\nset datafile missing '?'\n"
    << "set key outside right top vertical samplen 2\nset grid\nset xlabel 't [s]'\n";
  g << "$nis << EOD\n";
  for (std::size_t k = 0; k < series.t.size(); ++k)
    g << num(series.t[k]) << " " << num(series.nis_per_dof[k]) << " "
      << (series.converged[k] ? 1 : 0) << "\n";
  g << "EOD\n";
  for (std::size_t f = 0; f < families.size(); ++f) {
    g << "$f" << f << " << EOD\n";
    for (std::size_t k = 0; k < series.t.size(); ++k) {
      g << num(series.t[k]);
      for (std::size_t i : families[f].second) g << " " << num(series.value[i][k]);
      for (std::size_t i : families[f].second) g << " " << num(series.sigma[i][k]);
      g << "\n";
    }
    g << "EOD\n";
  }
  g << "set multiplot layout " << rows << ",2 title "
    << quoted("sinscal convergence: " + series.path) << "\n";
  g << "set title 'NIS per degree of freedom (1 when the measurement sigmas are the noise, below "
       "1 when they are bounds)'\nset ylabel ''\n"
    << "plot $nis using 1:2 with lines lw 1.5 title 'NIS/dof', 1 with lines dt 2 lc 'black' "
       "title 'expected'\n";
  g << "set title 'converged: every sigma below its target'\nset yrange [-0.1:1.1]\n"
    << "plot $nis using 1:3 with steps lw 1.5 title 'converged'\nset autoscale y\n";
  for (std::size_t f = 0; f < families.size(); ++f) {
    const std::string& family = families[f].first;  // named: a lambda below captures it
    const auto& members = families[f].second;
    const CoefficientInfo& first = coefficient_info(series.names[members.front()]);
    const std::string unit = first.unit;
    const int n = static_cast<int>(members.size());
    auto component = [&](std::size_t i) {
      const std::string& name = series.names[i];
      return name.size() > family.size() ? name.substr(family.size() + 1) : name;
    };
    g << "set title "
      << quoted(family + ": estimate [" + unit + "]" +
                (options.truth.empty() ? "" : " (dashed: truth)"))
      << "\nplot ";
    for (int j = 0; j < n; ++j) {
      const std::size_t i = members[j];
      g << (j ? ", " : "") << "$f" << f << " using 1:" << 2 + j << " with lines lw 1.5 lc " << j + 1
        << " title " << quoted(component(i));
      const auto t = options.truth.find(series.names[i]);
      if (t != options.truth.end() && t->second.observable)
        g << ", " << num(t->second.value) << " with lines dt 2 lc " << j + 1 << " notitle";
    }
    g << "\nset title " << quoted(family + ": sigma [" + unit + "]") << "\nset logscale y\nplot ";
    for (int j = 0; j < n; ++j)
      g << (j ? ", " : "") << "$f" << f << " using 1:" << 2 + n + j << " with lines lw 1.5 lc "
        << j + 1 << " title " << quoted(component(members[j]));
    const auto target = options.sigma_targets.find(family);
    if (target != options.sigma_targets.end())
      g << ", " << num(target->second / first.si_per_unit)
        << " with lines dt 2 lw 2 lc 'black' title 'target'";
    g << "\nunset logscale y\n";
  }
  g << "unset multiplot\nset output\n";
  if (layout) {
    layout->png = png_path;
    layout->families.clear();
    for (const auto& f : families) layout->families.push_back(f.first);
    layout->width_px = options.width_px;
    layout->height_px = height;
  }
  return g.str();
}

std::string convergence_script_path(const std::string& png_path) {
  return gnuplot_script_path(png_path);
}

ConvergencePlot plot_convergence(const MonitorSeries& series, const ConvergencePlotOptions& options,
                                 const std::string& png_path) {
  ConvergencePlot plot;
  const std::string script = convergence_plot_script(series, options, png_path, &plot);
  plot.script = convergence_script_path(png_path);
  write_atomically(plot.script, [&](std::ostream& out) { out << script; });
  run_gnuplot(options.gnuplot, plot.script, png_path);
  return plot;
}

}  // namespace sinscal
