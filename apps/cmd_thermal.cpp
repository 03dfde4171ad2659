// sinscal thermal: a chamber's soaks calibrated one by one (Kalman filter), then each coefficient
// fitted against temperature (filter/thermal/soak_fit.hpp); result.json, the compensation table.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "filter/thermal/soak_run.hpp"
#include "models/units.hpp"
#include "report/duplicates.hpp"
#include "report/output.hpp"
#include "report/provenance.hpp"
#include "report/thermal_output.hpp"

namespace sinscal::cli {

namespace {

// The grid step's range: below 0.01 C a row says nothing a sensor resolves; the table is bounded
// by kMaxThermalTableRows whatever the soaks' span (report/thermal_output.hpp).
constexpr double kMinGridStep = 0.01;
constexpr double kMaxGridStep = 100.0;
// The marker of a directory thermal wrote: the files it wrote, one per line.
constexpr const char* kThermalMarker = ".sinscal-thermal";

// A chamber naming one soak twice (the same session, another path to it, a copied log or folder)
// would be fitted as independent soaks, its sigmas sqrt(2) too small.
void refuse_repeated_soaks(const ChamberSoaks& chamber) {
  std::vector<DataSet> sets;
  for (std::size_t k = 0; k < chamber.sessions.size(); ++k)
    sets.push_back({"soak " + std::to_string(k + 1) + " (" + chamber.sessions[k] + ")",
                    session_inputs(Session::load(chamber.sessions[k]))});
  try {
    refuse_duplicate_data(sets);
  } catch (const std::invalid_argument& e) {
    throw UsageError(chamber.path + ": " + e.what());
  }
}

// --out: new, empty, or an earlier thermal output (its files replaced); a directory holding
// anything else (the chamber's sessions, an earlier result of another run) is refused unless
// --force; a directory holding an input is refused always.
void check_thermal_out(const std::string& out_dir, bool force) {
  try {
    refuse_protected("--out", out_dir, true);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  std::vector<std::string> foreign;
  if (directory_state(out_dir, kThermalMarker, foreign) != DirectoryState::Foreign || force) return;
  std::string names;
  for (std::size_t i = 0; i < foreign.size() && i < 3; ++i)
    names += (i > 0 ? ", " : "") + foreign[i];
  if (foreign.size() > 3) names += " and " + std::to_string(foreign.size() - 3) + " more";
  throw UsageError("--out " + out_dir + ": not empty and not an earlier thermal output (it holds " +
                   names +
                   "): thermal writes a new or empty directory or replaces its own "
                   "earlier files; --force writes into it anyway, keeping the files it does not "
                   "write");
}

struct Soaks {
  std::vector<SoakEstimate> estimates;
  std::vector<SoakRecord> records;
  std::vector<std::string> written;
  double t_lo = 1e9, t_hi = -1e9, reference = 25.0;
};

Soaks calibrate_soaks(const ChamberSoaks& chamber, const std::string& out_dir) {
  Soaks s;
  std::printf("%-5s %-40s %10s %10s %8s\n", "soak", "session", "T accel", "T gyro", "NIS/dof");
  for (std::size_t k = 0; k < chamber.sessions.size(); ++k) {
    const SoakRun r = calibrate_soak(chamber.sessions[k], chamber);
    const std::string name = "soak-" + std::to_string(k + 1) + ".json";
    const std::string result = out_dir + "/" + name;
    write_result_json(result, result_coefficients(r.run), result_sections(r.run));
    s.written.push_back(name);
    s.reference = r.reference_temperature_c;
    s.estimates.push_back(r.estimate);
    s.records.push_back({chamber.sessions[k], result, r.temperature.accel_mean_c,
                         r.temperature.gyro_mean_c, r.temperature.max_c - r.temperature.min_c,
                         r.run.nis_per_dof});
    s.t_lo = std::min(s.t_lo, r.temperature.min_c);
    s.t_hi = std::max(s.t_hi, r.temperature.max_c);
    std::printf("%-5zu %-40s %10.2f %10.2f %8.3f\n", k + 1, chamber.sessions[k].c_str(),
                r.temperature.accel_mean_c, r.temperature.gyro_mean_c, r.run.nis_per_dof);
    std::fflush(stdout);
  }
  return s;
}

void print_degrees(const ThermalFit& fit, double reference, double significance) {
  std::printf(
      "\nDegrees in T - T0 (T0 = %g C), chosen by chi-square tests at %g over the %zu "
      "families:\n",
      reference, significance, fit.degrees.size());
  for (const auto& t : fit.degrees) {
    std::string chi2;
    for (double c : t.chi2) chi2 += fmt(" %.1f", c);
    std::printf("  %-22s degree %d of %d   chi2 by degree:%s (a step must drop %.1f)\n",
                t.family.c_str(), t.degree, t.max_degree, chi2.c_str(), t.threshold);
  }
  std::printf("Joint fit: chi2 %.1f on %d dof, p = %.3g\n", fit.chi2, fit.dof, fit.p_value);
}

// The marker listing what this run wrote; files an earlier run listed and this one did not
// write (a chamber that had more soaks) removed.
void write_thermal_marker(const std::string& out_dir, const std::vector<std::string>& written) {
  std::vector<std::string> foreign;
  if (directory_state(out_dir, kThermalMarker, foreign) == DirectoryState::EarlierOutput) {
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator(out_dir)) {
      const std::string name = e.path().filename().string();
      if (name != kThermalMarker && e.is_regular_file() &&
          std::find(written.begin(), written.end(), name) == written.end())
        std::filesystem::remove(e.path(), ec);
    }
  }
  write_atomically(out_dir + "/" + kThermalMarker, [&](std::ostream& out) {
    for (const auto& n : written) out << n << "\n";
  });
}

}  // namespace

int cmd_thermal(const std::vector<std::string>& args) {
  po::options_description d("sinscal thermal options");
  std::string chamber_path, out_dir;
  double significance = 0.01, grid_step = 5.0, table_sigma = 2.5;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("chamber", po::value(&chamber_path)->required(),
       "the chamber session: [thermal] soaks = DIR/session.ini, ... (simulate --chamber writes one)")
      ("out", po::value(&out_dir)->required(),
       "output directory: new, empty or an earlier thermal output (its files replaced)")
      ("force", "write into a non-empty --out that is not an earlier thermal output")
      ("significance", po::value(&significance),
       "of each degree's chi-square test (default 0.01)")
      ("grid-step", po::value(&grid_step),
       "C between the compensation table's rows, 0.01 to 100 (default 5)")
      ("table-sigma", po::value(&table_sigma),
       "the table's attitude error per dwell and axis, arcsec (default 2.5)")
      ("no-plot", "no DIR/thermal.png (gnuplot)");
  // clang-format on
  const auto vm =
      parse(args, d,
            "Usage: sinscal thermal --chamber chamber.ini --out DIR\n"
            "Thermal calibration from soaks: each soak calibrated by the Kalman "
            "filter at its temperature,\nthen each coefficient fitted against "
            "temperature, its polynomial degree chosen by a chi-square test.\n"
            "Writes DIR/soak-K.json, DIR/result.json, DIR/thermal_table.csv, DIR/thermal.png.");
  if (!vm) return 0;
  if (!(significance > 0.0 && significance < 0.5))
    throw UsageError("--significance must be above 0 and below 0.5");
  if (!(grid_step >= kMinGridStep && grid_step <= kMaxGridStep))
    throw UsageError("--grid-step must be from " + fmt("%g", kMinGridStep) + " to " +
                     fmt("%g", kMaxGridStep) + " C (the table holds at most " +
                     std::to_string(kMaxThermalTableRows) + " rows)");
  if (!(table_sigma > 0.0 && table_sigma < 3600.0))
    throw UsageError("--table-sigma must be above 0 and below 3600 arcsec");
  ChamberSoaks chamber = ChamberSoaks::load(chamber_path);
  chamber.table_sigma = table_sigma * units::arcsec;
  std::vector<std::pair<std::string, std::string>> inputs = {{"chamber", chamber_path}};
  for (const auto& session : chamber.sessions)
    for (const auto& in : session_inputs(Session::load(session))) inputs.push_back(in);
  protect_inputs(inputs);
  refuse_repeated_soaks(chamber);
  check_thermal_out(out_dir, vm->count("force") > 0);
  std::filesystem::create_directories(out_dir);
  std::printf(
      "%zu soaks to calibrate (a Kalman filter each), then the fit and a table every %g C "
      "over their temperatures\n",
      chamber.sessions.size(), grid_step);
  Soaks s = calibrate_soaks(chamber, out_dir);
  ThermalFitOptions fo;
  fo.reference_temperature_c = s.reference;
  fo.significance = significance;
  const ThermalFit fit = fit_soaks(s.estimates, fo);
  nlohmann::ordered_json sections;
  sections["method"] = {{"name", "thermal"},
                        {"per_soak", "kf"},
                        {"soaks", s.estimates.size()},
                        {"body_frame", "table"}};
  sections["thermal"] = thermal_section(fit, s.records);
  ProvenanceInput prov{g_command_line, "", "", "", "", {{"chamber", chamber_path}}, false, ""};
  sections["provenance"] = provenance_section(prov);
  write_result_json(out_dir + "/result.json", thermal_coefficients(fit), sections);
  const double from = std::floor(s.t_lo / grid_step) * grid_step;
  const double to = std::ceil(s.t_hi / grid_step) * grid_step;
  write_thermal_table(out_dir + "/thermal_table.csv", fit, from, to, grid_step);
  s.written.insert(s.written.end(), {"result.json", "thermal_table.csv"});
  std::string plotted = out_dir + "/thermal.png";
  if (vm->count("no-plot")) {
    plotted.clear();
  } else {
    try {
      plot_thermal(fit, s.estimates, plotted);
    } catch (const std::runtime_error& e) {
      std::fprintf(stderr, "sinscal thermal: warning: no plot: %s\n", e.what());
      plotted.clear();
    }
  }
  for (const char* f : {"thermal.gp", "thermal.png"})  // the script even when gnuplot failed
    if (vm->count("no-plot") == 0 && std::filesystem::is_regular_file(out_dir + "/" + f))
      s.written.emplace_back(f);
  write_thermal_marker(out_dir, s.written);
  print_degrees(fit, s.reference, significance);
  std::printf("Written: %s/result.json, %s/thermal_table.csv (%g ... %g C)%s%s\n", out_dir.c_str(),
              out_dir.c_str(), from, to, plotted.empty() ? "" : ", ", plotted.c_str());
  return 0;
}

}  // namespace sinscal::cli
