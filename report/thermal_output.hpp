// A chamber's thermal calibration as files (docs/formats.md "Thermal results"): result.json
// with the coefficients at T0 and the thermal coefficients with sigmas, the soaks and each
// family's degree test; the compensation table (each coefficient on a temperature grid).
#pragma once

#include <string>
#include <vector>

#include "filter/thermal/soak_fit.hpp"
#include "report/result.hpp"

namespace sinscal {

/// The fit's coefficients (at T0, and the thermal ones), engineering units, sigma from its
/// covariance.
ResultCoefficients thermal_coefficients(const ThermalFit& fit);

/// One soak in the result: its session, result file and temperatures.
struct SoakRecord {
  std::string session, result;
  double accel_temperature_c = 0.0, gyro_temperature_c = 0.0, span_c = 0.0;
  double nis_per_dof = 0.0;
};
/// The "thermal" section of result.json.
nlohmann::ordered_json thermal_section(const ThermalFit& fit, const std::vector<SoakRecord>& soaks);

/// The most rows a compensation table holds (-55 ... 125 C every 0.01 C is 18001).
constexpr int kMaxThermalTableRows = 100000;

/// The compensation table: every fitted coefficient (not the thermal ones) at each temperature
/// from `from_c` to `to_c` in steps of `step_c`, value and sigma, engineering units. Written
/// atomically. Throws std::invalid_argument, before writing, when the bounds are not finite, the
/// step not positive or the table would hold more than kMaxThermalTableRows rows.
void write_thermal_table(const std::string& path, const ThermalFit& fit, double from_c, double to_c,
                         double step_c);

/// The plot script: one panel per fitted family whose degree is above 0 (the ones that vary), each
/// component's per-soak estimates with their 1-sigma bars and the fitted curve (dashed), against
/// temperature; written with its data inline (gnuplot redraws it).
std::string thermal_plot_script(const ThermalFit& fit, const std::vector<SoakEstimate>& soaks,
                                const std::string& png_path);
/// Writes the script beside the PNG and runs gnuplot (report/gnuplot.hpp).
void plot_thermal(const ThermalFit& fit, const std::vector<SoakEstimate>& soaks,
                  const std::string& png_path, const std::string& gnuplot = "gnuplot");

}  // namespace sinscal
