#include "filter/thermal/soak_run.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "models/coefficient_families.hpp"
#include "models/config.hpp"

namespace sinscal {

bool ChamberSoaks::is_chamber(const std::string& path) {
  const IniFile ini(path);
  return ini.has("thermal.soaks");
}

ChamberSoaks ChamberSoaks::load(const std::string& path) {
  const IniFile ini(path);
  ChamberSoaks c;
  c.path = path;
  ini.check_keys("thermal", {"soaks", "soak_tolerance"});
  for (const auto& key : ini.keys())
    if (key.rfind("thermal.", 0) != 0) throw ConfigError(ini.where(key) + "unknown section");
  std::string list = ini.get_string("thermal.soaks");
  for (char& ch : list)
    if (ch == ',') ch = ' ';
  std::istringstream words(list);
  std::string w;
  while (words >> w)
    c.sessions.push_back(path_in(std::filesystem::path(path).parent_path().string(), w));
  if (c.sessions.size() < 2)
    throw ConfigError(ini.where("thermal.soaks") + "a thermal fit needs at least 2 soaks, got " +
                      std::to_string(c.sessions.size()));
  if (ini.has("thermal.soak_tolerance")) {
    c.tolerance_c = ini.get_quantities("thermal.soak_tolerance", {{"C", 1.0}}, "C", 1).front();
    if (!(c.tolerance_c > 0.0))
      throw ConfigError(ini.where("thermal.soak_tolerance") + "must be positive");
  }
  return c;
}

namespace {
// The soak's observed coefficients and their covariance.
SoakEstimate soak_estimate(const KalmanRun& run, const CalibratorOptions& o,
                           const std::string& session_path, const SoakTemperature& T) {
  const auto& cat = coefficient_catalog();
  SoakEstimate e;
  e.name = session_path;
  e.accel_temperature_c = T.accel_mean_c;
  e.gyro_temperature_c = T.gyro_mean_c;
  std::vector<Eigen::Index> rows;
  for (std::size_t k = 0; k < run.covariance_catalog.size(); ++k) {
    const int c = run.covariance_catalog[k];
    if (!run.estimates[static_cast<std::size_t>(c)].observed()) continue;
    e.catalog.push_back(c);
    rows.push_back(static_cast<Eigen::Index>(k));
  }
  const auto n = static_cast<Eigen::Index>(rows.size());
  e.value.resize(n);
  e.covariance.resize(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    e.value(i) =
        run.estimates[static_cast<std::size_t>(e.catalog[static_cast<std::size_t>(i)])].value;
    for (Eigen::Index j = 0; j < n; ++j)
      e.covariance(i, j) = run.coefficient_covariance(rows[static_cast<std::size_t>(i)],
                                                      rows[static_cast<std::size_t>(j)]);
  }
  // Without the wander's states the filter's bias states follow the bias as it wanders (the bias
  // instability, a random walk in the filter): the estimate is then the bias at the soak's end,
  // and that differs from the bias the thermal model describes by the wander's value then, of
  // the bias instability's stationary sigma, independent between soaks (hours apart, the
  // correlation time minutes). A MEMS unit's 10 deg/h is several of the filter's sigmas: without
  // it the fit's biases were 2 sigma RMS off. With the states (the default) the bias families
  // hold the constant bias.
  if (!effective_layout(o).bias_wander)
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto& family =
          cat[static_cast<std::size_t>(e.catalog[static_cast<std::size_t>(i)])].family;
      const CoefficientFamily& info = coefficient_family_info(family);
      if (!info.wanders_with_bias_noise) continue;
      const TriadNoise& tn = info.output == FamilyOutput::Gyro ? o.noise.gyro : o.noise.accel;
      e.covariance(i, i) += tn.bias_instability * tn.bias_instability;
    }
  return e;
}
}  // namespace

void check_soak_settled(const SoakTemperature& T, const ChamberSoaks& chamber) {
  if (!(T.max_c - T.min_c > chamber.tolerance_c)) return;
  char msg[400];
  std::snprintf(msg, sizeof msg,
                "the temperature moves by %.2f C during the soak (%.2f C at t = %.1f s, line "
                "%zu; %.2f C at t = %.1f s, line %zu), more than the soak tolerance %g C of %s: "
                "the soak had not settled (its settling time too short for the sensor's lag)",
                T.max_c - T.min_c, T.min_c, T.t_min, T.line_min, T.max_c, T.t_max, T.line_max,
                chamber.tolerance_c, chamber.path.c_str());
  throw LogError(T.line_min > T.line_max ? T.file_min : T.file_max,
                 std::max(T.line_min, T.line_max), msg);
}

SoakRun calibrate_soak(const std::string& session_path, const ChamberSoaks& chamber,
                       const KalmanRunOptions& run) {
  SoakRun r;
  r.session = Session::load(session_path);
  if (r.session.sensor_file.empty())
    throw ConfigError(session_path +
                      ": a soak's session needs its sensor profile ([session] sensor =)");
  r.temperature = measure_soak_temperature(r.session.log);
  const SoakTemperature& T = r.temperature;
  check_soak_settled(T, chamber);
  const SensorProfile profile = SensorProfile::load(r.session.sensor_file);
  r.reference_temperature_c = profile.reference_temperature_c;
  CalibratorOptions o = calibrator_options_from_profile(profile);
  o.time_offset = r.session.time_offset;
  o.attitude_sigma = chamber.table_sigma;
  const auto& cat = coefficient_catalog();
  for (const auto& f : coefficient_families()) {
    if (!f.thermal()) continue;
    o.layout.set(f.name, false);
  }
  for (const auto& f : chamber.extra_families) o.layout.set(f, true);
  // Priors at the soak's temperature: each thermal family's range at this |T - T0| added.
  for (std::size_t i = 0; i < cat.size(); ++i) {
    const std::string& family = cat[i].family;
    if (coefficient_family_info(family).thermal() || o.initial_sigma[i] == 0.0) continue;
    const bool accel = coefficient_family_info(family).output == FamilyOutput::Accel;
    const double dT =
        std::abs((accel ? T.accel_mean_c : T.gyro_mean_c) - profile.reference_temperature_c);
    const std::string component = cat[i].name.substr(family.size());
    for (int d = 1; d <= 3; ++d) {
      const std::string thermal = family + "_temp" + std::to_string(d);
      const auto it = profile.ranges.find(thermal);
      if (it == profile.ranges.end() || !it->second.present()) continue;
      o.initial_sigma[i] += o.prior_scale *
                            std::max(std::abs(it->second.lo), std::abs(it->second.hi)) *
                            std::pow(dT, d);
    }
  }
  r.run = run_kalman(r.session, o, nullptr, run);
  if (!r.run.stopped.empty() || !r.run.diverged.empty())
    throw SoakStopped(session_path + ": the soak's calibration stopped: " +
                      (r.run.stopped.empty() ? r.run.diverged : r.run.stopped));
  r.estimate = soak_estimate(r.run, o, session_path, T);
  return r;
}

ChamberRuns calibrate_soaks_keep_going(const ChamberSoaks& chamber, const KalmanRunOptions& run) {
  ChamberRuns out;
  for (std::size_t k = 0; k < chamber.sessions.size(); ++k) {
    try {
      out.runs.push_back(calibrate_soak(chamber.sessions[k], chamber, run));
      out.index.push_back(k);
    } catch (const SoakStopped& e) {
      out.failed.push_back({k, chamber.sessions[k], e.what()});
    }
  }
  return out;
}

std::string soak_failure_stop(const SoakFailure& f, std::size_t soaks) {
  return "soak " + std::to_string(f.index + 1) + " of " + std::to_string(soaks) +
         " set aside, the fit and the tests use the others: " + f.cause +
         " (its data do not follow the filter's model at that temperature: an effect the model "
         "lacks, thermal or not; the non-thermal families' test of one soak may name it)";
}

}  // namespace sinscal
