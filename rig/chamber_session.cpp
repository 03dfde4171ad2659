// simulate --chamber: a chamber's soaks (one session each) or its ramp (one session, the plan
// repeated), the sensor lagging the air (rig/thermal.hpp).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "models/config.hpp"
#include "rig/session.hpp"

namespace sinscal {

ChamberSimulation simulate_chamber(const std::string& out_dir, const SessionSimulation& spec,
                                   const ChamberProgram& chamber) {
  const Plan plan = Plan::load(spec.plan_path);
  if (!plan.has_site)
    throw ConfigError(spec.plan_path + ": the plan has no [site] for the simulation");
  const double plan_s = build_motion(plan, plan.site, spec.table).duration();
  const double tau = SensorProfile::load(spec.data_sensor_path).thermal_time_constant;
  ChamberSimulation out;
  char note[200];
  if (chamber.type == ChamberProgram::Type::Ramp) {
    const SensorTemperature temperature(chamber.ramp_air(), tau);
    SessionSimulation s = spec;
    s.temperature = &temperature;
    s.plan_repeat = static_cast<int>(std::ceil(chamber.ramp_duration() / plan_s - 1e-9));
    std::snprintf(note, sizeof note,
                  "chamber ramp %g C to %g C at %g C/min after %g s at %g C; sensor lag %g s",
                  chamber.from_c, chamber.to_c, chamber.rate_c_per_s * 60.0, chamber.settle_s,
                  chamber.from_c, tau);
    s.note = note;
    out.sessions.push_back(simulate_session(out_dir, s));
    out.path = out.sessions.back().session_path;
    return out;
  }
  std::filesystem::create_directories(out_dir);
  std::string list;
  for (std::size_t k = 0; k < chamber.soaks_c.size(); ++k) {
    const SensorTemperature temperature(chamber.soak_air(k, plan_s), tau);
    SessionSimulation s = spec;
    s.temperature = &temperature;
    s.noise_stream = k + 1;
    s.name = (spec.name.empty() ? plan.name : spec.name) + "-soak-" + std::to_string(k + 1);
    std::snprintf(note, sizeof note,
                  "chamber soak %zu of %zu: air %g C, %g s after it got there; "
                  "sensor lag %g s",
                  k + 1, chamber.soaks_c.size(), chamber.soaks_c[k], chamber.settle_s, tau);
    s.note = note;
    const std::string dir = "soak-" + std::to_string(k + 1);
    out.sessions.push_back(simulate_session(out_dir + "/" + dir, s));
    out.soak_c.push_back(chamber.soaks_c[k]);
    list += (list.empty() ? "" : ", ") + dir + "/session.ini";
  }
  out.path = out_dir + "/chamber.ini";
  std::ofstream f(out.path);
  f << "# Written by sinscal simulate --chamber " << chamber.path
    << "\n# One session per soak; sinscal thermal --chamber chamber.ini fits the coefficients "
       "against temperature.\n[thermal]\nsoaks = "
    << list << "\n";
  f.close();
  if (!f) throw std::runtime_error(out.path + ": cannot write");
  return out;
}

}  // namespace sinscal
