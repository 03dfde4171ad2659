// sinscal diagnose on a chamber session (apps/cmd_diagnose.cpp): each soak calibrated by the
// Kalman filter, then the thermal families the model lacks tested against the soaks
// (filter/diagnosis/thermal_diagnosis.hpp).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "apps/cli.hpp"
#include "apps/diagnose.hpp"
#include "filter/diagnosis/thermal_diagnosis.hpp"
#include "filter/thermal/soak_run.hpp"
#include "models/coefficient_families.hpp"
#include "models/sensor_profile.hpp"
#include "models/units.hpp"
#include "report/output.hpp"
#include "report/thermal_diagnosis_report.hpp"
#include "rig/session.hpp"

namespace sinscal::cli {

namespace {

void print_heldout(const HeldoutSoaks& h) {
  if (h.soaks == 0) {
    std::printf("no held-out soaks (the others do not determine the model)");
    return;
  }
  std::printf("held-out soaks %.2f sigma", h.sigmas);
}

void print_thermal_findings(const ThermalDiagnosis& d) {
  std::printf("\nModel fit: chi2 %.1f on %d dof; ", d.initial_chi2, d.initial_dof);
  print_heldout(d.initial_heldout);
  std::printf(" (1: the soaks predicted as their sigmas say)\n");
  if (d.findings.empty())
    std::printf("Findings: none (no thermal family significant at the family-wise level %g)\n",
                d.alpha);
  int number = 0;
  for (const auto& f : d.findings) {
    const ThermalCandidateTest& t = f.test;
    std::printf("%d. %s: ", ++number, t.family.c_str());
    if (t.test == "F")
      std::printf("F(%d, %d) = %.2f", t.dof, t.dof2, t.statistic);
    else
      std::printf("chi2(%d) = %.2f", t.dof, t.statistic);
    std::printf(
        ", p = %s (below %.3g); ",
        t.p_value > 1e-300 ? fmt("%.3g", t.p_value).c_str() : fmt("1e%.0f", t.log10_p).c_str(),
        t.threshold);
    const std::string base = thermal_family_parts(t.family).first;
    const CoefficientFamily& b = coefficient_family_info(base);
    if (f.before.soaks > 0 && f.after.soaks > 0)
      std::printf("held-out soaks %.2f -> %.2f sigma; %s at a held-out soak %.4g -> %.4g %s RMS\n",
                  f.before.sigmas, f.after.sigmas, base.c_str(),
                  f.family_error_before / b.si_per_unit(), f.family_error_after / b.si_per_unit(),
                  b.unit().c_str());
    else
      std::printf("no held-out soaks (the others do not determine the model)\n");
    const CoefficientFamily& info = coefficient_family_info(t.family);
    for (const auto& c : f.coefficients)
      std::printf("     %-28s %12.4g +- %-10.3g %s\n",
                  coefficient_catalog()[static_cast<std::size_t>(c.catalog)].name.c_str(),
                  c.value / info.si_per_unit(), c.sigma / info.si_per_unit(), info.unit().c_str());
  }
  for (const auto& m : d.model)
    if (thermal_family_parts(m).second == 0)
      std::printf(
          "In the model, not fitted on soaks: %s (a soak holds its temperature: a ramp "
          "separates it)\n",
          m.c_str());
  for (const auto& t : d.not_testable)
    std::printf("Not testable on these soaks: %s (%s)\n", t.family.c_str(), t.not_testable.c_str());
  if (d.unexplained)
    std::printf(
        "Unexplained: with the findings the soaks' fit is still chi2 %.1f on %d dof (p %.2g): no "
        "thermal family explains the rest; the sigmas above are scaled by %.2f\n",
        d.final_fit.chi2, d.final_fit.dof, d.final_fit.p_value, d.sigma_scale);
  for (const auto& s : d.stops) std::printf("Stop: %s\n", s.c_str());
}

// The soak nearest the reference temperature, each soak's log read once for its temperature (a
// soak not settled is refused here, before any calibration).
struct NearestSoak {
  std::size_t index = 0;
  double gyro_temperature_c = 0.0;
};

NearestSoak nearest_soak(const ChamberSoaks& chamber, double t0) {
  NearestSoak n;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < chamber.sessions.size(); ++k) {
    const SoakTemperature T = measure_soak_temperature(Session::load(chamber.sessions[k]).log);
    check_soak_settled(T, chamber);
    if (std::abs(T.gyro_mean_c - t0) < best) {
      best = std::abs(T.gyro_mean_c - t0);
      n = {k, T.gyro_mean_c};
    }
  }
  return n;
}

struct NonThermal {
  std::string statement;
  std::vector<std::string> named;  // the families its diagnosis named
};

// The non-thermal families (K2, g-sensitivity, lever arms, ...) act at every temperature: they
// are tested on the soak nearest the reference temperature, where the thermal terms vanish (a
// thermal family the model lacks cannot pose as one of them), as a table session; its diagnosis
// goes to DIR/soak-K. What it names joins every soak's filter before the thermal fit: a soak
// calibrated without it absorbs it into its coefficients differently at each temperature (a
// hidden g-sensitivity made one soak's filter diverge and the others' fit name
// gyro.scale_temp2, whose truth is zero).
NonThermal diagnose_non_thermal(const ChamberSoaks& chamber, double t0,
                                const ChamberDiagnoseOptions& o) {
  const NearestSoak n = nearest_soak(chamber, t0);
  char b[120];
  std::snprintf(b, sizeof b, "soak %zu (%.2f C, the nearest to T0 = %g C)", n.index + 1,
                n.gyro_temperature_c, t0);
  const std::string where = b;
  std::printf("Non-thermal families, tested on %s as a table session:\n", where.c_str());
  TableDiagnoseOptions t;
  t.out_dir = o.out_dir + "/soak-" + std::to_string(n.index + 1);
  t.dwells.alpha = o.alpha;
  t.table_sigma = o.table_sigma;
  t.plot = false;
  NonThermal out;
  try {
    const TableDiagnosis d = diagnose_table_session(chamber.sessions[n.index], t);
    for (const auto& f : d.findings) out.named.push_back(f.family);
  } catch (const std::exception& e) {
    out.statement = "the non-thermal families not tested: the table diagnosis of " + where +
                    " stopped (" + e.what() + ")";
    return out;
  }
  std::string found;
  for (const auto& f : out.named) found += (found.empty() ? "" : ", ") + f;
  out.statement =
      "the non-thermal families (K2, g-sensitivity, scale asymmetry, lever arms, time delay, "
      "...) tested on " +
      where + " only, as a table session (" + t.out_dir + "): " +
      (found.empty() ? "none named"
                     : "named " + found + ", added to every soak's filter before the thermal fit") +
      "; on the other soaks they are fitted soak by soak, not tested";
  return out;
}

// A table log's temperature span below which it is one temperature for the diagnosis.
constexpr double kConstantTemperatureSpan = 2.0;  // deg C

}  // namespace

bool log_temperature_varies(const Session& session) {
  {
    LogReader reader(session.log);
    ImuSample s;
    if (!reader.next(s) || !s.has_temperature) return false;
  }
  const SoakTemperature T = measure_soak_temperature(session.log);
  const double span = T.max_c - T.min_c;
  if (span < kConstantTemperatureSpan) {
    std::printf(
        "Temperature: %.2f ... %.2f C over the log (span %.2f C, below %.0f C): one "
        "temperature, the thermal families are not tested (a chamber's soaks test them: "
        "diagnose --session chamber.ini)\n",
        T.min_c, T.max_c, span, kConstantTemperatureSpan);
    return false;
  }
  std::printf(
      "Temperature: %.2f ... %.2f C over the log (span %.1f C): the thermal families are "
      "candidates, each dwell at its mean temperature and rate\n",
      T.min_c, T.max_c, span);
  return true;
}

int diagnose_chamber(const std::string& chamber_path, const ChamberDiagnoseOptions& o) {
  ChamberSoaks chamber = ChamberSoaks::load(chamber_path);
  chamber.table_sigma = o.table_sigma * units::arcsec;
  const std::string json_path = o.out_dir + "/diagnosis.json";
  std::vector<std::pair<std::string, std::string>> inputs = {{"chamber", chamber_path}};
  for (const auto& s : chamber.sessions) inputs.emplace_back("soak session", s);
  if (!o.sensor.empty()) inputs.emplace_back("sensor profile", o.sensor);
  refuse_overwrite(inputs, {{"diagnosis.json", json_path}});
  std::vector<SoakEstimate> estimates;
  std::vector<SoakRecord> records;
  const std::string profile_path =
      o.sensor.empty() ? Session::load(chamber.sessions.front()).sensor_file : o.sensor;
  if (profile_path.empty())
    throw std::runtime_error(chamber.sessions.front() +
                             ": a soak's session needs its sensor profile ([session] sensor =)");
  const SensorProfile profile = SensorProfile::load(profile_path);
  const NonThermal non_thermal = diagnose_non_thermal(chamber, profile.reference_temperature_c, o);
  std::printf("\n");
  chamber.extra_families = non_thermal.named;
  const ChamberRuns runs = calibrate_soaks_keep_going(chamber);
  std::printf("%-5s %-40s %10s %10s %8s\n", "soak", "session", "T accel", "T gyro", "NIS/dof");
  for (std::size_t i = 0; i < runs.runs.size(); ++i) {
    const SoakRun& r = runs.runs[i];
    estimates.push_back(r.estimate);
    records.push_back({chamber.sessions[runs.index[i]], "", r.temperature.accel_mean_c,
                       r.temperature.gyro_mean_c, r.temperature.max_c - r.temperature.min_c,
                       r.run.nis_per_dof});
    std::printf("%-5zu %-40s %10.2f %10.2f %8.3f\n", runs.index[i] + 1,
                chamber.sessions[runs.index[i]].c_str(), r.temperature.accel_mean_c,
                r.temperature.gyro_mean_c, r.run.nis_per_dof);
  }
  std::vector<std::string> set_aside;
  for (const auto& f : runs.failed) {
    std::printf("%-5zu %-40s set aside: %s\n", f.index + 1, f.session.c_str(), f.cause.c_str());
    set_aside.push_back(soak_failure_stop(f, chamber.sessions.size()));
  }
  if (runs.runs.size() < 2)
    throw std::runtime_error(chamber_path + ": " + std::to_string(runs.runs.size()) + " of " +
                             std::to_string(chamber.sessions.size()) +
                             " soaks calibrated, a thermal fit needs at least 2: " +
                             (runs.failed.empty() ? "" : runs.failed.front().cause));
  ThermalDiagnosisOptions to;
  to.alpha = o.alpha;
  for (const auto& f : coefficient_families())
    if (f.thermal() && profile.has(f.name)) to.model.push_back(f.name);
  std::string model;
  for (const auto& m : to.model) model += (model.empty() ? "" : ", ") + m;
  std::printf("\nThermal model of %s (T0 = %g C): %s\n", profile_path.c_str(),
              profile.reference_temperature_c, model.empty() ? "none" : model.c_str());
  to.non_thermal_elsewhere = true;
  ThermalDiagnosis d = diagnose_soaks(estimates, profile.reference_temperature_c, to);
  d.stops.insert(d.stops.begin(), set_aside.begin(), set_aside.end());
  d.stops.push_back(non_thermal.statement);
  print_thermal_findings(d);
  std::filesystem::create_directories(o.out_dir);
  std::printf("Written: %s\n",
              write_thermal_diagnosis(d, chamber_path, records, o.out_dir).c_str());
  return 0;
}

}  // namespace sinscal::cli
