// sinscal allan: overlapping Allan deviation of a static record (or one static pose of a
// session), the fitted noise terms as a sensor-profile fragment, and a plot.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "apps/print.hpp"
#include "filter/plausibility/rest_plausibility.hpp"
#include "models/earth.hpp"
#include "report/allan_output.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

namespace {

// The plausibility gate on the stretch analysed (filter/plausibility/rest_plausibility.hpp): the
// record's length at the declared rate and the noise it implies are stated; a failure stops
// (exit 2) unless --force, whose failed checks go in the fragment's header.
void allan_gate(const Session& session, bool force, AllanRunOptions& o, PlausibilityReport& gate) {
  std::optional<SensorProfile> profile;
  if (!session.sensor_file.empty()) profile = SensorProfile::load(session.sensor_file);
  const RestLimits limits = RestLimits::from_profile(profile ? &*profile : nullptr);
  const double g = session.gravity > 0.0 ? session.gravity
                   : session.has_site
                       ? Earth::wgs84().gravity_n(session.site.lat_rad, session.site.h_m).norm()
                       : units::g0;
  o.before_analysis = [&session, force, limits, g, &gate](const AllanRecord& rec,
                                                          const std::vector<ImuReading>& part) {
    std::printf("%s\n", record_statement(session.log, rec.count, rec.t_last - rec.t_first).c_str());
    gate = check_rests({rest_statistics(part, 0, part.size() - 1, "the stretch analysed")}, g,
                       limits, rec.file);
    gate.checks.push_back(check_same_files(session.log));
    if (gate.checks.back().passed)
      gate.checks.back() = check_same_signal(rec.readings, limits, rec.file);
    for (const auto& c : gate.checks)
      if (c.name == "noise") std::printf("%s\n\n", c.detail.c_str());
    enforce(gate, force);
  };
}

}  // namespace

int cmd_allan(const std::vector<std::string>& args) {
  po::options_description d("sinscal allan options");
  std::string session_path, out_dir;
  AllanRunOptions o;
  int pose = 0;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("session", po::value(&session_path)->required(),
       "session.ini of the record (a plan is not needed)")
      ("out", po::value(&out_dir)->required(),
       "directory to write allan.csv, profile-fragment.ini, allan.png and allan.gp into")
      ("all", "the whole record even when it is not static (with a warning); without a "
       "selection the whole record, refused when it is not static")
      ("longest-pose", "the longest static pose the detector finds")
      ("pose", po::value(&pose), "static pose N (1-based, in time order) the detector finds")
      ("pose-window", po::value(&o.detector.window)->default_value(1.0),
       "window of the pose detector's variances [s]")
      ("min-pose", po::value(&o.detector.min_duration)->default_value(2.0),
       "shortest static pose the detector takes [s]")
      ("pose-accel-only", "the accelerometers alone find the poses")
      ("force", "run even when the plausibility gate fails (gravity and rate at rest, noise "
       "band, one signal in both triads); the failed checks go in the fragment's header")
      ("points-per-decade", po::value(&o.allan.points_per_decade)->default_value(0),
       "cluster times per decade (0: octaves, 1, 2, 4, ... samples)")
      ("fit-quantization", "fit the quantization term too (slope -1)")
      ("fit-rate-ramp", "fit the rate-ramp term too (slope +1)");
  // clang-format on
  const auto vm =
      parse(args, d,
            "Usage: sinscal allan --session S --out DIR [--all | --longest-pose | --pose N]\n"
            "Overlapping Allan deviation of each axis with confidence bounds, the fitted noise\n"
            "model (angle / velocity random walk, bias instability, rate random walk; with\n"
            "options quantization and rate ramp) with 1-sigma as a sensor-profile fragment and a\n"
            "table, and a PNG of measured against fitted (gnuplot). The log is streamed: memory\n"
            "does not grow with its length.");
  if (!vm) return 0;
  const int chosen =
      static_cast<int>(vm->count("all") + vm->count("longest-pose") + vm->count("pose"));
  if (chosen > 1) throw UsageError("give one of --all, --longest-pose, --pose N");
  o.require_static = chosen == 0;  // --all takes a record that is not static, with a warning
  if (vm->count("longest-pose")) o.selection = AllanSelection::LongestPose;
  if (vm->count("pose")) {
    if (pose < 1) throw UsageError("--pose must be 1 or more");
    o.selection = AllanSelection::Pose;
    o.pose = pose;
  }
  o.detector.use_gyro = vm->count("pose-accel-only") == 0;
  o.allan.fit_quantization = vm->count("fit-quantization") > 0;
  o.allan.fit_rate_ramp = vm->count("fit-rate-ramp") > 0;
  if (!(o.detector.window > 0.0 && o.detector.window <= 60.0))
    throw UsageError("--pose-window must be above 0 and at most 60 s");
  if (!(o.detector.min_duration > 0.0 && o.detector.min_duration <= 3600.0))
    throw UsageError("--min-pose must be above 0 and at most 3600 s");
  if (o.allan.points_per_decade < 0 || o.allan.points_per_decade > 100)
    throw UsageError("--points-per-decade must be 0 to 100");
  const Session session = Session::load(session_path, Session::PlanNeed::Optional);
  apply_table_free_settings(session.table_free, *vm, o.detector, nullptr);
  const std::string csv = out_dir + "/allan.csv", fragment = out_dir + "/profile-fragment.ini",
                    png = out_dir + "/allan.png", script = out_dir + "/allan.gp",
                    terms = out_dir + "/allan-terms.csv";
  refuse_overwrite(session_inputs(session), {{"allan.csv", csv},
                                             {"profile-fragment.ini", fragment},
                                             {"allan.png", png},
                                             {"allan.gp", script},
                                             {"allan-terms.csv", terms}});
  PlausibilityReport gate;
  allan_gate(session, vm->count("force") > 0, o, gate);
  const AllanRun run = run_allan(session, o);
  if (!run.warning.empty()) std::cerr << "sinscal allan: warning: " << run.warning << "\n";
  std::filesystem::create_directories(out_dir);
  write_allan_csv(csv, run.analysis);
  write_allan_terms_csv(terms, run.analysis);
  const std::string what =
      run.pose > 0 ? "pose " + std::to_string(run.pose) : std::string("the whole record");
  write_atomically(fragment, [&](std::ostream& out) {
    out << "# sinscal allan --session " << session.path << ": " << what << ", t = " << run.t_start
        << " to " << run.t_end << " s\n";
    for (const auto& c : gate.checks)
      if (!c.passed)
        out << "# plausibility gate failed (--force): " << c.name << ": " << c.detail << "\n";
    out << run.analysis.profile_fragment();
  });
  print_allan(run);
  plot_allan(run.analysis, session.name + " (" + what + ")", png, script);
  std::printf("\nWritten: %s, %s, %s, %s (gnuplot script %s)\n", csv.c_str(), terms.c_str(),
              fragment.c_str(), png.c_str(), script.c_str());
  return 0;
}

}  // namespace sinscal::cli
