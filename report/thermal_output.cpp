#include "report/thermal_output.hpp"

#include <cmath>
#include <cstdio>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
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
    const int steps = static_cast<int>(std::floor((to_c - from_c) / step_c + 1e-9));
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

}  // namespace sinscal
