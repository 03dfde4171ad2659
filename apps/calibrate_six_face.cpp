// sinscal calibrate --method six-face: a session of the six-face and known-turn procedure
// (filter/six_face/six_face.hpp): its labelled parts read from the log, the calibration, its
// result file and table.
#include <chrono>
#include <cstdio>
#include <iostream>

#include "apps/calibrate.hpp"
#include "report/six_face_result.hpp"

namespace sinscal::cli {

SessionSummary calibrate_six_face_session(const CalibrateOptions& o,
                                          const std::string& session_path,
                                          const std::string& out_path, bool verbose) {
  const Session session = Session::load(session_path, Session::PlanNeed::Optional);
  if (!session.six_face)
    throw ConfigError(session.path +
                      ": --method six-face needs a [six_face] section (the labels of the faces "
                      "and turns, docs/formats.md \"Six-face sessions\")");
  refuse_overwrite(session_inputs(session), {{"--out", out_path}});
  SixFaceOptions so;
  so.declared = *session.six_face;
  so.gravity = o.gravity > 0.0 ? o.gravity : session.gravity;
  if (session.has_site) so.site = session.site;
  if (!session.sensor_file.empty()) {
    const SensorProfile profile = SensorProfile::load(session.sensor_file);
    so.gyro_bias_instability = profile.noise.gyro.bias_instability;
    so.accel_bias_instability = profile.noise.accel.bias_instability;
  }
  const auto t0 = std::chrono::steady_clock::now();
  LogReader reader(session.log);
  PartAccumulator parts({so.declared.turns.begin(), so.declared.turns.end()});
  ImuSample s;
  double duration = 0.0;
  while (reader.next(s)) {
    if (s.label < 0)
      throw LogError(session.log.file, reader.line(),
                     "a six-face log needs a label column (columns = ... label ...): the part "
                     "each sample belongs to");
    try {
      parts.push(s, reader.labels()[static_cast<std::size_t>(s.label)]);
    } catch (const SixFaceError& e) {
      throw LogError(session.log.file, reader.line(), e.what());
    }
    duration += s.dt;
  }
  const SixFaceResult r = six_face_calibrate(parts.parts(), so);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const ResultCoefficients coefficients = result_coefficients(r);
  write_result_json(out_path, coefficients, result_sections(r, so, session.log));
  const ResultCoefficients truth = load_truth(session);
  SessionSummary row{session.path, session.name,
                     out_path,     "ok",
                     "",           reader.count(),
                     duration,     std::nullopt,
                     std::nullopt, max_error_over_sigma(coefficients, truth),
                     coefficients};
  if (!verbose) return row;
  std::printf("Six-face calibration of %s: %zu readings, %.1f s\n\n", session.name.c_str(),
              reader.count(), duration);
  std::cout << six_face_table(r, truth);
  std::printf("\nResult written to %s (%.3f s: reading and calibration)\n", out_path.c_str(),
              seconds);
  return row;
}

}  // namespace sinscal::cli
