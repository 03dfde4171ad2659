// sinscal diagnose on a six-face session ([six_face] in session.ini): the gyro g-sensitivity test
// on the rests (filter/six_face/six_face.hpp, GSensitivityTest): the calibration refitted with
// the 9 terms of K, K against zero. Prints the verdict and K with sigmas, writes
// DIR/diagnosis.json (docs/formats.md "Six-face diagnosis").
#include <cstdio>
#include <filesystem>

#include "apps/diagnose.hpp"
#include "filter/six_face/six_face.hpp"
#include "models/coefficient_families.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

int diagnose_six_face_session(const Session& session, const std::string& out_dir, double alpha) {
  if (!out_dir.empty()) {
    std::filesystem::create_directories(out_dir);
    auto inputs = session_inputs(session);
    refuse_overwrite(inputs, {{"--out", out_dir + "/diagnosis.json"}});
  }
  SixFaceOptions o = six_face_options(session);
  o.g_sensitivity = true;
  o.alpha = alpha;
  SixFaceResult r;
  try {
    r = six_face_calibrate(read_parts(session), o);
  } catch (const SixFaceError& e) {
    throw SixFaceError(six_face_where(session) + e.what());
  }
  const GSensitivityTest& t = *r.g_test;
  const CoefficientFamily& info = coefficient_family_info("gyro.g_sensitivity");
  const double per = info.si_per_unit();
  std::printf(
      "Six-face session %s: the gyro g-sensitivity (imucal's K_ga) tested on the six rests and "
      "three turns\n\n",
      session.name.c_str());
  std::printf("K [%s], value (sigma), rows: gyro x, y, z; columns: specific force x, y, z\n",
              info.unit().c_str());
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j)
      std::printf("  %9.4f (%7.4f)", t.K(i, j) / per, t.K_sigma(i, j) / per);
    std::printf("\n");
  }
  std::printf("\nWald statistic %.1f on %d dof, p = %.3g: ", t.statistic, t.dof, t.p_value);
  if (t.significant)
    std::printf("g-sensitivity DETECTED at alpha %.3g (largest term %.4f %s).\n", t.threshold,
                t.K.cwiseAbs().maxCoeff() / per, info.unit().c_str());
  else
    std::printf(
        "not detected at alpha %.3g: below the detection limit of %.4f %s per term on this "
        "session.\n",
        t.threshold, t.detection_limit / per, info.unit().c_str());
  if (out_dir.empty()) return 0;
  nlohmann::ordered_json K = nlohmann::ordered_json::array(), S = nlohmann::ordered_json::array();
  for (int i = 0; i < 3; ++i) {
    K.push_back({t.K(i, 0) / per, t.K(i, 1) / per, t.K(i, 2) / per});
    S.push_back({t.K_sigma(i, 0) / per, t.K_sigma(i, 1) / per, t.K_sigma(i, 2) / per});
  }
  const nlohmann::ordered_json j = {{"session", session.path},
                                    {"method", "six-face"},
                                    {"g_sensitivity",
                                     {{"unit", info.unit()},
                                      {"K", K},
                                      {"K_sigma", S},
                                      {"statistic", t.statistic},
                                      {"dof", t.dof},
                                      {"p_value", t.p_value},
                                      {"alpha", t.threshold},
                                      {"detected", t.significant},
                                      {"detection_limit", t.detection_limit / per}}}};
  write_atomically(out_dir + "/diagnosis.json",
                   [&](std::ostream& out) { out << j.dump(2) << "\n"; });
  std::printf("Wrote %s/diagnosis.json\n", out_dir.c_str());
  return 0;
}

}  // namespace sinscal::cli
