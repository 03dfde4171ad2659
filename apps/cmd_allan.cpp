// sinscal allan: overlapping Allan deviation of a static record (or one static pose of a
// session), the fitted noise terms as a sensor-profile fragment, and a plot.
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "apps/print.hpp"
#include "report/allan_output.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

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
      ("points-per-decade", po::value(&o.allan.points_per_decade)->default_value(0),
       "cluster times per decade (0: octaves, 1, 2, 4, ... samples)");
  // clang-format on
  const auto vm =
      parse(args, d,
            "Usage: sinscal allan --session S --out DIR [--all | --longest-pose | --pose N]\n"
            "Overlapping Allan deviation of each axis with confidence bounds, the fitted noise\n"
            "model (angle / velocity random walk, bias instability, rate random walk) as a\n"
            "sensor-profile fragment, and a PNG of measured against fitted (gnuplot).");
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
  if (!(o.detector.window > 0.0 && o.detector.window <= 60.0))
    throw UsageError("--pose-window must be above 0 and at most 60 s");
  if (!(o.detector.min_duration > 0.0 && o.detector.min_duration <= 3600.0))
    throw UsageError("--min-pose must be above 0 and at most 3600 s");
  if (o.allan.points_per_decade < 0 || o.allan.points_per_decade > 100)
    throw UsageError("--points-per-decade must be 0 to 100");
  const Session session = Session::load(session_path, Session::PlanNeed::Optional);
  const std::string csv = out_dir + "/allan.csv", fragment = out_dir + "/profile-fragment.ini",
                    png = out_dir + "/allan.png", script = out_dir + "/allan.gp";
  refuse_overwrite(session_inputs(session), {{"allan.csv", csv},
                                             {"profile-fragment.ini", fragment},
                                             {"allan.png", png},
                                             {"allan.gp", script}});
  const AllanRun run = run_allan(session, o);
  if (!run.warning.empty()) std::cerr << "sinscal allan: warning: " << run.warning << "\n";
  std::filesystem::create_directories(out_dir);
  write_allan_csv(csv, run.analysis);
  const std::string what =
      run.pose > 0 ? "pose " + std::to_string(run.pose) : std::string("the whole record");
  write_atomically(fragment, [&](std::ostream& out) {
    out << "# sinscal allan --session " << session.path << ": " << what << ", t = " << run.t_start
        << " to " << run.t_end << " s\n"
        << run.analysis.profile_fragment();
  });
  print_allan(run);
  plot_allan(run.analysis, session.name + " (" + what + ")", png, script);
  std::printf("\nWritten: %s, %s, %s (gnuplot script %s)\n", csv.c_str(), fragment.c_str(),
              png.c_str(), script.c_str());
  return 0;
}

}  // namespace sinscal::cli
