// sinscal diagnose on a hand-held session (no plan): the table-free calibration, then model
// discovery on its poses and turns (filter/diagnosis/handheld_diagnosis.hpp), held-out validation
// records before and after, the files of report/handheld_diagnosis_report.hpp.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "apps/diagnose.hpp"
#include "apps/handheld_gate.hpp"
#include "filter/diagnosis/handheld_diagnosis.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/diagnosis_common.hpp"
#include "report/handheld_diagnosis_report.hpp"
#include "rig/io/log_io.hpp"

namespace sinscal::cli {

namespace {

// --candidates: families of the family table, "noise" (both noise candidates) and its two
// names, "temperature". Fills the options; returns whether temperature was asked for.
bool parse_candidates(const std::string& list, HandheldDiagnosisOptions& o) {
  if (list.empty()) return false;
  bool temperature = false;
  o.noise = false;
  std::stringstream ss(list);
  std::string name;
  while (std::getline(ss, name, ',')) {
    if (name == "temperature") {
      temperature = true;
    } else if (name == "noise" || name == "noise.bias_instability" ||
               name == "noise.rate_random_walk") {
      o.noise = o.noise_requested = true;
    } else {
      bool known = false;
      for (const auto& f : coefficient_families()) known = known || (f.name == name && !f.base);
      if (!known)
        throw UsageError("--candidates: '" + name +
                         "' is not an extended family of the family table, noise, "
                         "noise.bias_instability, noise.rate_random_walk or temperature");
      o.candidates.push_back(name);
    }
  }
  // Only temperature or noise asked for: no coefficient family.
  if (o.candidates.empty()) o.candidates.push_back("");
  return temperature;
}

void print(const HandheldDiagnosisInput& in, const HandheldDiagnosisFiles& files, double seconds) {
  const DiagnosisReport& r = in.diagnosis.report;
  const HandheldUnits u = handheld_units(in.calibration);
  std::printf(
      "Table-free calibration: %zu poses, %d turns; chi2/dof %.3f; residual RMS: gravity "
      "magnitude %.5g %s, rate at rest %.5g %s, turns %.4f deg\n",
      in.diagnosis.poses.size(), in.diagnosis.turns, r.initial.fit.chi2_per_dof,
      r.initial.accel_rms / u.accel_si, u.accel.c_str(), r.initial.gyro_rms / u.gyro_si,
      u.gyro.c_str(), r.initial.turn_rms / units::deg);
  if (r.findings.empty())
    std::printf("Findings: none (%s at the family-wise level %g)\n",
                r.rejected.empty() ? "no candidate significant"
                                   : "the significant candidate is refused by the held-out data",
                r.alpha);
  for (const auto& s : r.stops) std::printf("Unexplained: %s\n", s.c_str());
  const FitFigures* before = &r.initial;
  for (const auto& f : r.findings) {
    std::printf(
        "Found %s: %s, p = %.3g; gravity residual %.5g -> %.5g %s, "
        "turns %.4f -> %.4f deg; held-out %.3f -> %.3f sigma; base moved up to %.1f sigma\n",
        f.family.c_str(), diagnosis_output::statistic_text(f).c_str(), f.p_value,
        before->accel_rms / u.accel_si, f.with.accel_rms / u.accel_si, u.accel.c_str(),
        before->turn_rms / units::deg, f.with.turn_rms / units::deg, before->heldout,
        f.with.heldout, f.base_shift_sigma);
    before = &f.with;
  }
  for (const auto& a : r.ambiguous)
    std::printf("Ambiguous: %s and %zu other candidates explain the residual equally well\n",
                a.family.c_str(), a.ambiguous_with.size());
  for (const auto& c : r.not_separable)
    std::printf("Not separable on this session: %s (%zu of its components); separated by %s\n",
                c.family.c_str(), c.aliased.size(), c.separated_by.c_str());
  for (const auto& n : in.diagnosis.noise)
    if (n.significant)
      std::printf(
          "Noise: %s on %s (the Allan deviation of pose %d leaves the white-noise model "
          "at %.3g s)\n",
          n.effect.c_str(), n.channel.c_str(), in.diagnosis.noise_pose, n.tau);
  for (const auto& [b, a] : in.validations) {
    std::printf("Validation %s: gravity magnitude %.5g -> %.5g %s, rate at rest %.5g -> %.5g %s",
                b.session.c_str(), b.gravity_rms_calibrated / u.accel_si,
                a.gravity_rms_calibrated / u.accel_si, u.accel.c_str(),
                b.rate_rms_calibrated / u.gyro_si, a.rate_rms_calibrated / u.gyro_si,
                u.gyro.c_str());
    if (!b.turns.empty())
      std::printf(", turns %.3f -> %.3f deg", b.turn_rms_calibrated / units::deg,
                  a.turn_rms_calibrated / units::deg);
    std::printf("\n");
  }
  std::printf("Written: %s, %s%s%s%s%s (%.2f s: reading, calibration and diagnosis)\n",
              files.json.c_str(), files.markdown.c_str(), files.png.empty() ? "" : ", ",
              files.png.c_str(), files.allan_png.empty() ? "" : ", ", files.allan_png.c_str(),
              seconds);
}

// Whether the session's log has temperature columns (its first sample says).
bool log_has_temperature(const Session& session) {
  LogReader reader(session.log);
  ImuSample s;
  return reader.next(s) && s.has_temperature;
}

}  // namespace

int diagnose_handheld_session(const Session& session, const HandheldDiagnoseOptions& o) {
  HandheldDiagnosisOptions ho;
  ho.alpha = o.alpha;
  const bool temperature = parse_candidates(o.candidates, ho);
  std::vector<Session> validations;
  auto inputs = session_inputs(session);
  for (const auto& path : o.validate) {
    validations.push_back(Session::load(path, Session::PlanNeed::Optional));
    const auto more = session_inputs(validations.back());
    inputs.insert(inputs.end(), more.begin(), more.end());
  }
  const HandheldDiagnosisFiles files = handheld_diagnosis_files(o.out_dir);
  refuse_overwrite(inputs, {{"diagnosis.json", files.json},
                            {"report.md", files.markdown},
                            {"residuals.png", files.png},
                            {"allan.png", files.allan_png}});
  const auto t0 = std::chrono::steady_clock::now();
  PlausibilityReport gate;
  TableFreeRun run = gated_table_free_run(session, o.run, o.force, gate);
  const HandheldDiagnosis d = diagnose_handheld(run.readings, run.result, run.options, ho);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  HandheldDiagnosisInput in{d, run.result, session.path, {}};
  TableFreeRun extended = run;
  extended.result.model = diagnosed_model(d, run.result);
  for (const auto& v : validations)
    in.validations.emplace_back(validate_table_free(v, run, o.run.detector),
                                validate_table_free(v, extended, o.run.detector));
  std::filesystem::create_directories(o.out_dir);
  const HandheldDiagnosisFiles written =
      write_handheld_diagnosis(in, o.out_dir, o.plot ? "gnuplot" : "");
  print(in, written, seconds);
  // Bad requests fail after the findings so far are written.
  if (temperature)
    throw std::runtime_error(
        (session.log.file.empty() ? session.path : session.log.file) +
        (log_has_temperature(session)
             ? ": the candidate 'temperature' is not tested yet (the log's temperature columns "
               "are read; the thermal families are to come)"
             : ": the candidate 'temperature' needs a temperature column in the log, which has "
               "none") +
        " (the other candidates' findings are written to " + written.json + ")");
  if (!d.refused.empty())
    throw std::runtime_error(d.refused.front() +
                             " (the other candidates' findings are written to " + written.json +
                             ")");
  return 0;
}

}  // namespace sinscal::cli
