// sinscal navigate: the navigator through each static dwell of a session, from the plan's known
// attitude, zero velocity and the known position; its errors written and summarized.
#include <cstdio>
#include <fstream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "filter/strapdown/dwell_navigation.hpp"
#include "models/attitude.hpp"
#include "models/units.hpp"
#include "report/output.hpp"
#include "rig/io/log_io.hpp"
#include "rig/session.hpp"

namespace sinscal::cli {

namespace {
std::string nav_row(const DwellNavRow& r) {
  char b[400];
  const NavError& e = r.error;
  std::snprintf(b, sizeof b, "%d,%.6f,%.6f,%.9e,%.9e,%.9e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e\n", r.dwell,
                r.t_log, e.t, e.dv_n.x(), e.dv_n.y(), e.dv_n.z(), e.phi_n.x() / units::arcsec,
                e.phi_n.y() / units::arcsec, e.phi_n.z() / units::arcsec, e.dp_n.x(), e.dp_n.y(),
                e.dp_n.z());
  return b;
}

void print_summary(const Session& session, const DwellNavigation& run, const std::string& vertical,
                   const std::string& out_path) {
  std::printf("Navigation through the dwells of '%s' (%s convention), vertical channel %s\n",
              session.plan.name.c_str(), to_string(session.plan.convention).c_str(),
              vertical.c_str());
  std::printf("%5s %-14s %8s %8s %8s %7s %10s %10s %10s %10s %10s\n", "dwell", "label", "heading",
              "pitch", "roll", "T", "dv_n", "dv_e", "phi_n", "phi_e", "phi_d");
  std::printf("%5s %-14s %8s %8s %8s %7s %10s %10s %10s %10s %10s\n", "", "", "[deg]", "[deg]",
              "[deg]", "[s]", "[mm/s]", "[mm/s]", "[arcsec]", "[arcsec]", "[arcsec]");
  for (const auto& s : run.summaries()) {
    const EulerAngles a = euler_from_C_b_n(session.plan.convention, s.dwell.C_b_n_known);
    const NavError& e = s.final_error;
    std::printf("%5d %-14s %8.2f %8.2f %8.2f %7.1f %10.4f %10.4f %10.4f %10.4f %10.4f\n",
                s.dwell.index, s.dwell.label.c_str(), a.heading / units::deg, a.pitch / units::deg,
                a.roll / units::deg, e.t, e.dv_n.x() * 1e3, e.dv_n.y() * 1e3,
                e.phi_n.x() / units::arcsec, e.phi_n.y() / units::arcsec,
                e.phi_n.z() / units::arcsec);
  }
  std::printf("Navigation errors written to %s\n", out_path.c_str());
}
}  // namespace

int cmd_navigate(const std::vector<std::string>& args) {
  po::options_description d("sinscal navigate options");
  std::string session_path, out_path;
  Vertical vertical = Vertical::Free;
  double interval = 1.0;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("session", po::value(&session_path)->required(), "session.ini of the recording")
      ("out", po::value(&out_path)->required(), "navigation error CSV to write")
      ("interval", po::value(&interval)->default_value(1.0), "output interval [s] (0: every sample)")
      ("vertical", po::value(&vertical)->default_value(Vertical::Free, "free"),
       "vertical channel: free | held");
  // clang-format on
  if (!parse(args, d,
             "Usage: sinscal navigate --session DIR/session.ini --out nav.csv\nNavigates through "
             "each static dwell of the plan from its known attitude, zero velocity and known "
             "position, and writes the navigation errors against them."))
    return 0;
  if (!(interval >= 0.0 && interval < 1e6)) throw UsageError("--interval must be 0 to 1e6 s");
  const Session session = Session::load(session_path);
  refuse_overwrite(session_inputs(session), {{"--out", out_path}});
  const PlanTimeline timeline = PlanTimeline::of(session.plan, session.site);
  DwellNavOptions opt;
  opt.output_interval = interval;
  opt.time_offset = session.time_offset;
  opt.input = session.log.file;
  opt.strapdown.vertical_held = vertical == Vertical::Held;
  DwellNavigation run(timeline.dwells, session.site, opt);
  LogReader reader(session.log);
  const std::string vertical_name = vertical == Vertical::Held ? "held" : "free";
  // Rows go to a temporary file renamed at the end: an error keeps the rows computed so far
  // (and the summaries of finished dwells), never a truncated earlier file.
  try {
    write_atomically(
        out_path,
        [&](std::ostream& out) {
          out << "dwell,t_log [s],t [s],dv_n [m/s],dv_e [m/s],dv_d [m/s],phi_n [arcsec],"
                 "phi_e [arcsec],phi_d [arcsec],dp_n [m],dp_e [m],dp_d [m]\n";
          run.run(reader, [&](const DwellNavRow& r) { out << nav_row(r); });
        },
        /*keep_partial=*/true);
  } catch (...) {
    print_summary(session, run, vertical_name, out_path);  // what was computed is shown
    throw;
  }
  print_summary(session, run, vertical_name, out_path);
  return 0;
}

}  // namespace sinscal::cli
