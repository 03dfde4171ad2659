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
#include "report/output.hpp"
#include "report/provenance.hpp"
#include "report/thermal_output.hpp"

namespace sinscal::cli {

int cmd_thermal(const std::vector<std::string>& args) {
  po::options_description d("sinscal thermal options");
  std::string chamber_path, out_dir;
  double significance = 0.01, grid_step = 5.0, table_sigma = 2.5;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("chamber", po::value(&chamber_path)->required(),
       "the chamber session: [thermal] soaks = DIR/session.ini, ... (simulate --chamber writes one)")
      ("out", po::value(&out_dir)->required(), "output directory (created; results are replaced)")
      ("significance", po::value(&significance),
       "of each degree's chi-square test (default 0.01)")
      ("grid-step", po::value(&grid_step), "C between the compensation table's rows (default 5)")
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
  if (!(grid_step > 0.0)) throw UsageError("--grid-step must be positive");
  if (!(table_sigma > 0.0 && table_sigma < 3600.0))
    throw UsageError("--table-sigma must be above 0 and below 3600 arcsec");
  ChamberSoaks chamber = ChamberSoaks::load(chamber_path);
  chamber.table_sigma = table_sigma * units::arcsec;
  std::filesystem::create_directories(out_dir);
  std::vector<SoakEstimate> estimates;
  std::vector<SoakRecord> records;
  double t_lo = 1e9, t_hi = -1e9, reference = 25.0;
  std::printf("%-5s %-40s %10s %10s %8s\n", "soak", "session", "T accel", "T gyro", "NIS/dof");
  for (std::size_t k = 0; k < chamber.sessions.size(); ++k) {
    const SoakRun r = calibrate_soak(chamber.sessions[k], chamber);
    const std::string result = out_dir + "/soak-" + std::to_string(k + 1) + ".json";
    write_result_json(result, result_coefficients(r.run), result_sections(r.run));
    reference = r.reference_temperature_c;
    estimates.push_back(r.estimate);
    records.push_back({chamber.sessions[k], result, r.temperature.accel_mean_c,
                       r.temperature.gyro_mean_c, r.temperature.max_c - r.temperature.min_c,
                       r.run.nis_per_dof});
    t_lo = std::min(t_lo, r.temperature.min_c);
    t_hi = std::max(t_hi, r.temperature.max_c);
    std::printf("%-5zu %-40s %10.2f %10.2f %8.3f\n", k + 1, chamber.sessions[k].c_str(),
                r.temperature.accel_mean_c, r.temperature.gyro_mean_c, r.run.nis_per_dof);
  }
  ThermalFitOptions fo;
  fo.reference_temperature_c = reference;
  fo.significance = significance;
  const ThermalFit fit = fit_soaks(estimates, fo);
  nlohmann::ordered_json sections;
  sections["method"] = {{"name", "thermal"},
                        {"per_soak", "kf"},
                        {"soaks", estimates.size()},
                        {"body_frame", "table"}};
  sections["thermal"] = thermal_section(fit, records);
  ProvenanceInput prov{g_command_line, "", "", "", "", {{"chamber", chamber_path}}, false, ""};
  sections["provenance"] = provenance_section(prov);
  write_result_json(out_dir + "/result.json", thermal_coefficients(fit), sections);
  const double from = std::floor(t_lo / grid_step) * grid_step;
  const double to = std::ceil(t_hi / grid_step) * grid_step;
  write_thermal_table(out_dir + "/thermal_table.csv", fit, from, to, grid_step);
  std::string plotted = out_dir + "/thermal.png";
  if (vm->count("no-plot")) {
    plotted.clear();
  } else {
    try {
      plot_thermal(fit, estimates, plotted);
    } catch (const std::runtime_error& e) {
      std::fprintf(stderr, "sinscal thermal: warning: no plot: %s\n", e.what());
      plotted.clear();
    }
  }
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
  std::printf("Written: %s/result.json, %s/thermal_table.csv (%g ... %g C)%s%s\n", out_dir.c_str(),
              out_dir.c_str(), from, to, plotted.empty() ? "" : ", ", plotted.c_str());
  return 0;
}

}  // namespace sinscal::cli
