// sinscal calibrate --method six-face: a session of the six-face and known-turn procedure
// (filter/six_face/six_face.hpp): its labelled parts read from the log, the calibration, its
// result file and table.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>

#include "apps/calibrate.hpp"
#include "filter/plausibility/rest_plausibility.hpp"
#include "models/earth.hpp"
#include "models/units.hpp"
#include "report/six_face_result.hpp"

namespace sinscal::cli {

namespace {
SessionSummary calibrate_six_face_loaded(const CalibrateOptions& o, const Session& session,
                                         const std::string& out_path, bool verbose);
}  // namespace

SessionSummary calibrate_six_face_session(const CalibrateOptions& o,
                                          const std::string& session_path,
                                          const std::string& out_path, bool verbose) {
  const Session session = Session::load(session_path, Session::PlanNeed::Optional);
  if (!session.six_face)
    throw ConfigError(session.path +
                      ": --method six-face needs a [six_face] section (the labels of the faces "
                      "and turns, docs/formats.md \"Six-face sessions\")");
  refuse_overwrite(session_inputs(session), {{"--out", out_path}});
  try {
    return calibrate_six_face_loaded(o, session, out_path, verbose);
  } catch (const SixFaceError& e) {
    throw SixFaceError(six_face_where(session) + e.what());
  }
}

namespace {
SessionSummary calibrate_six_face_loaded(const CalibrateOptions& o, const Session& session,
                                         const std::string& out_path, bool verbose) {
  SixFaceOptions so = six_face_options(session);
  if (o.gravity > 0.0) so.gravity = o.gravity;
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<PartStatistics> parts = read_parts(session);
  std::size_t readings = 0;
  double duration = 0.0;
  for (const auto& p : parts) {
    readings += p.count;
    duration += p.duration;
  }
  // The plausibility gate on the faces before the fit, then on its chi2/dof (exit 2 unless
  // --force, which records it).
  std::optional<SensorProfile> profile;
  if (!session.sensor_file.empty()) profile = SensorProfile::load(session.sensor_file);
  const RestLimits limits = RestLimits::from_profile(profile ? &*profile : nullptr);
  const double g = so.gravity > 0.0 ? so.gravity
                   : so.site ? Earth::wgs84().gravity_n(so.site->lat_rad, so.site->h_m).norm()
                             : units::g0;
  PlausibilityReport gate =
      check_six_face(session.log, parts, so.declared, g, limits, session.log.file);
  enforce(gate, o.force);
  const SixFaceResult r = six_face_calibrate(parts, so);
  gate.checks.push_back(check_fit(r.accel_dof > 0 ? r.accel_chi2 / r.accel_dof : 0.0, limits,
                                  session.log.file, "the six-face accelerometer fit"));
  enforce(gate, o.force);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const ResultCoefficients coefficients = result_coefficients(r);
  auto sections = result_sections(r, so, session.log);
  record_gate(sections, gate);
  record_provenance(sections, session);
  write_result_json(out_path, coefficients, sections);
  const ResultCoefficients truth = load_truth(session);
  SessionSummary row{session.path, session.name,
                     out_path,     "ok",
                     "",           readings,
                     duration,     std::nullopt,
                     std::nullopt, max_error_over_sigma(coefficients, truth),
                     coefficients};
  if (!verbose) return row;
  std::printf("Six-face calibration of %s: %zu readings in its parts, %.1f s\n\n",
              session.name.c_str(), readings, duration);
  std::cout << six_face_table(r, truth);
  std::printf("\nResult written to %s (%.3f s: reading and calibration)\n", out_path.c_str(),
              seconds);
  return row;
}

}  // namespace

}  // namespace sinscal::cli
