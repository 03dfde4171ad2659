// sinscal calibrate: the calibration coefficients of one session or a batch of sessions.
#include <unistd.h>  // isatty: the live table only on a terminal

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "apps/calibrate.hpp"
#include "apps/commands.hpp"
#include "report/duplicates.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

namespace {

// The options and where each one acts: an option of the other method is refused by name.
void add_options(po::options_description& d, CalibrateOptions& o) {
  // clang-format off
  d.add_options()
      ("method", po::value(&o.method)->default_value(Method::ClosedForm, "closed-form"),
       "closed-form | kf (error-state Kalman filter) | table-free (hand-held session, no table) | "
       "six-face (faces and known turns, labelled) | rate-table (constant-rate segments and "
       "static positions from their means: no integration)")
      ("force", "run even when the plausibility gate fails (docs/formats.md: dwells against gravity, "
       "Earth rate and plan, saturation, fits; rests without a table); the result records it")
      ("table-sigma", po::value(&o.table_sigma)->default_value(2.5),
       "table attitude error per orientation and axis, 1-sigma [arcsec]")
      ("cross-asymmetry", po::bool_switch(&o.cross_asymmetry),
       "rate-table: the gyros' response to |rate| across each turn's axis in the model "
       "(gyro.cross_asym.ij: offsets while turning that depend on the turn's direction)")
      ("gyro-drift", po::bool_switch(&o.gyro_drift),
       "rate-table: the gyros' bias drift over the log in the model (gyro.bias_drift.i, with each "
       "segment at its readings' time at the session's nominal rate)")
      ("keep-unsteady-rests", po::bool_switch(&o.keep_unsteady),
       "rate-table: keep in the fit a rest whose outputs change level within it (tested against "
       "the other rests' noise) and whose mean disagrees with the fit; by default it is left out "
       "and named")
      ("misalignment-frame", po::value(&o.misalignment_frame),
       "kf, closed-form: the frame of the misalignments: table (relative to the table's platform; "
       "the default with table-attitude updates) | triad (within the triads, the accelerometer "
       "triad as the body frame; the default and only frame with --attitude none)")
      ("stage1", po::value(&o.stage1)->default_value(Stage1Method::Fit, "fit"),
       "closed-form: fit (weighted least squares over each dwell) | point (the paper's eq. 5)")
      ("model", po::value(&o.model)->default_value(ErrorModelKind::Coupled, "coupled"),
       "closed-form: coupled | uncoupled (the paper's Schuler channels)")
      ("channels", po::value(&o.channels)->default_value(o.channels, "north,east,vertical,heading"),
       "closed-form: stage-1 channels, comma separated (the paper: north,east)")
      ("arw", po::value(&o.arw), "closed-form: gyro angle random walk [deg/sqrt(h)] (default: the "
       "session's sensor)")
      ("vrw", po::value(&o.vrw), "closed-form: accelerometer velocity random walk [ug/sqrt(Hz)]")
      ("min-dwell", po::value(&o.min_dwell)->default_value(20.0), "closed-form: shortest dwell [s]")
      ("stream", "kf: read the samples from standard input (the session's log format)")
      ("monitor-interval", po::value(&o.monitor_interval)->default_value(10.0),
       "kf: seconds of data between monitor lines (and live-table refreshes on a terminal)")
      ("attitude", po::value(&o.attitude)->default_value(CalibratorOptions::AttitudeUpdates::Every,
       "every"), "kf: table-attitude updates: every (dwell) | first (dwell) | none (zero velocity "
       "only; body frame = accelerometer triad)")
      ("no-position", "kf: no known-position updates")
      ("no-zero-velocity", "kf: no zero-velocity updates at rest")
      ("terms", po::value(&o.terms),
       ("kf: extended blocks on or off beyond the sensor profile's, e.g. k2,-lever_arm: " +
        extended_terms_help() + "; vertical_velocity; or a family's name").c_str())
      ("prior-scale", po::value(&o.prior_scale)->default_value(kDefaultPriorScale),
       "kf: prior sigma of each coefficient = this x the largest magnitude of its family's "
       "range in the sensor profile")
      ("lever-arm-reference", po::value(&o.lever_arm_reference),
       "kf: x | y | z: that accelerometer's inner lever arm fixed at zero (the IMU reference "
       "point at its proof mass)")
      ("no-motion-zero-velocity", "kf: no zero-velocity updates while the table turns")
      ("no-table-angles", "kf: ignore the log's table-angle columns (attitude from the plan)")
      ("base", po::value(&o.base)->default_value("estimated"),
       "kf: the table base's attitude: estimated (3 states) | known (the plan's: not estimated)")
      ("motion", po::value(&o.motion)->default_value("data"),
       "kf: the motion the filter linearizes along: data (the plan's turns as the log shows "
       "them: start-time offset, smoothed, lagging or overshooting turns) | plan (the plan's "
       "commanded trapezoids)")
      ("passes", po::value(&o.passes)->default_value(1),
       "kf: passes over the log, each from the previous pass's coefficients (large errors: MEMS); "
       "0: automatic, another pass while the last ran beyond its linear range (at most 3)")
      ("static-from", po::value(&o.static_from)->default_value(CalibratorOptions::StaticFrom::Plan,
       "plan"), "kf: where the static dwells are: plan (its timing, shifted by the session's "
       "time_offset) | data (detected; the k-th static interval is the plan's k-th dwell)")
      ("static-window", po::value(&o.static_window)->default_value(1.0),
       "kf, --static-from data: trailing window of the detector [s]")
      ("static-min", po::value(&o.static_min)->default_value(3.0),
       "kf, --static-from data: shortest static interval taken for a dwell [s]")
      ("static-rate-threshold", po::value(&o.static_rate)->default_value(3.0),
       "kf, --static-from data: a mean rate above this is motion [deg/s]")
      ("on-bad-sample", po::value(&o.on_bad_sample)->default_value(OnBadSample::Stop, "stop"),
       "kf: stop | skip (NaN, saturated, time going backwards; each reported)");
  // clang-format on
  add_table_free_options(d, o);
}

// Options given that the chosen method does not use: refused by name.
void check_method_options(const po::variables_map& vm, CalibrateOptions& o) {
  static const std::vector<std::string> closed_form_only = {"stage1", "model", "channels",
                                                            "arw",    "vrw",   "min-dwell"};
  // clang-format off
  static const std::vector<std::string> kf_only = {
      "stream", "monitor", "monitor-interval", "attitude", "no-position", "no-zero-velocity",
      "terms", "prior-scale", "lever-arm-reference", "no-motion-zero-velocity", "no-table-angles",
      "passes", "motion", "base", "static-from", "static-window", "static-min", "static-rate-threshold",
      "on-bad-sample"};
  // clang-format on
  if (o.cross_asymmetry && o.method != Method::RateTable)
    throw UsageError("--cross-asymmetry acts in --method rate-table only, not in --method " +
                     name_of(o.method));
  if (o.gyro_drift && o.method != Method::RateTable)
    throw UsageError("--gyro-drift acts in --method rate-table only, not in --method " +
                     name_of(o.method));
  if (o.keep_unsteady && o.method != Method::RateTable)
    throw UsageError("--keep-unsteady-rests acts in --method rate-table only, not in --method " +
                     name_of(o.method));
  misalignment_frame_option(o);  // the table methods only; a known name
  check_table_free_options(vm, o, {closed_form_only, kf_only, {"table-sigma"}});
  if (o.method == Method::TableFree || o.method == Method::SixFace) return;
  if (o.method == Method::RateTable) {
    for (const auto& list : {closed_form_only, kf_only})
      for (const auto& name : list)
        if (vm.count(name) && !vm[name].defaulted() && name != "on-bad-sample")
          throw UsageError("--" + name + " is not an option of --method rate-table");
  }
  const bool kf = o.method == Method::Kf;
  for (const auto& name : kf ? closed_form_only : kf_only)
    if (vm.count(name) && !vm[name].defaulted() &&
        !(o.method == Method::RateTable && name == "on-bad-sample"))
      throw UsageError("--" + name + " acts in --method " + (kf ? "closed-form" : "kf") +
                       " only, not in --method " + name_of(o.method));
  if (!(o.table_sigma > 0.0 && o.table_sigma < 3600.0))
    throw UsageError("--table-sigma must be above 0 and below 3600 arcsec");
  if (!(o.arw >= 0.0 && o.vrw >= 0.0 && o.arw < 1e6 && o.vrw < 1e9))
    throw UsageError("--arw and --vrw must be positive numbers");
  if (!(o.min_dwell > 0.0 && o.monitor_interval > 0.0 && o.prior_scale > 0.0 &&
        o.prior_scale < 1e6))
    throw UsageError("--min-dwell, --monitor-interval and --prior-scale must be positive");
  check_kf_values(o);
}

namespace {
// One session named twice (two paths to it, a copied folder, a copied log) would count as two
// independent units in the summary: refused before any calibration, naming both.
void refuse_repeated_sessions(const std::vector<std::string>& sessions) {
  std::vector<DataSet> sets;
  for (const auto& path : sessions) {
    DataSet set{path, {{"session", path}}};
    try {
      set.files = session_inputs(Session::load(path, Session::PlanNeed::Optional));
    } catch (const std::exception&) {
      // A session that does not load fails in its own row; its path is still compared.
    }
    sets.push_back(set);
  }
  try {
    refuse_duplicate_data(sets);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("batch: ") + e.what());
  }
}
}  // namespace

int calibrate_batch(const CalibrateOptions& o, const std::vector<std::string>& sessions,
                    const std::string& out_dir, unsigned jobs) {
  refuse_repeated_sessions(sessions);
  std::filesystem::create_directories(out_dir);
  const auto stems = result_stems(sessions);
  const auto t0 = std::chrono::steady_clock::now();
  jobs = std::max(1u, std::min<unsigned>(jobs, static_cast<unsigned>(sessions.size())));
  const auto rows = run_batch(
      sessions, jobs,
      [&](std::size_t i) {
        const std::string stem = out_dir + "/" + stems[i];
        return calibrate_session(o, sessions[i], stem + ".json",
                                 o.method == Method::Kf ? stem + ".monitor.jsonl" : "", false,
                                 false);
      },
      &g_stop,
      [&](std::size_t i, const SessionSummary& row) {
        std::fprintf(stderr, "[%zu/%zu] %s: %s%s%s\n", i + 1, sessions.size(), sessions[i].c_str(),
                     row.status.c_str(), row.message.empty() ? "" : ": ", row.message.c_str());
      });
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const std::string summary = out_dir + "/summary.csv";
  write_summary_csv(summary, rows);
  std::printf("Batch calibration (%s) of %zu sessions on %u threads, %.2f s\n\n",
              name_of(o.method).c_str(), sessions.size(), jobs, seconds);
  std::printf("%-24s %-9s %9s %9s %10s %12s %12s  %s\n", "result", "status", "samples", "data [s]",
              "NIS/dof", "converged [s]", "max|err|/sig", "session");
  int bad = 0;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const SessionSummary& r = rows[i];
    auto opt = [](const std::optional<double>& v, const char* f) {
      return v ? fmt(f, *v) : std::string("-");
    };
    std::printf("%-24s %-9s %9zu %9.1f %10s %12s %12s  %s\n", (stems[i] + ".json").c_str(),
                r.status.c_str(), r.samples, r.duration, opt(r.nis_per_dof, "%.3f").c_str(),
                opt(r.converged_at, "%.1f").c_str(), opt(r.max_error_over_sigma, "%.2f").c_str(),
                r.session.c_str());
    if (r.status != "ok") ++bad;
  }
  std::printf("\nSummary table written to %s\n", summary.c_str());
  if (bad == 0) return 0;
  std::fprintf(stderr, "sinscal calibrate: error: %d of %zu sessions not ok (see %s)\n", bad,
               sessions.size(), summary.c_str());
  return g_stop ? kInterrupted : kDataError;
}

}  // namespace

int cmd_calibrate(const std::vector<std::string>& args) {
  po::options_description d("sinscal calibrate options");
  CalibrateOptions o;
  std::vector<std::string> session_paths;
  std::string session_list, out_path, monitor_path;
  unsigned jobs = 0;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("session", po::value(&session_paths)->composing(),
       "session.ini of the recording; or a directory: its session.ini, else every subdirectory "
       "holding one (batch). Repeatable (batch)")
      ("session-list", po::value(&session_list),
       "batch: a file naming one session (session.ini or directory) per line")
      ("out", po::value(&out_path)->required(),
       "result JSON to write; in a batch, the directory of the results and summary.csv")
      ("jobs", po::value(&jobs)->default_value(0),
       "batch: sessions calibrated at once (0: one per processor core)")
      ("monitor", po::value(&monitor_path),
       "kf: write a JSON line of estimates and sigmas here (a batch writes RESULT.monitor.jsonl "
       "beside each result)");
  // clang-format on
  add_options(d, o);
  const auto vm = parse(
      args, d,
      "Usage: sinscal calibrate --session DIR/session.ini --method "
      "closed-form|kf|table-free|six-face|rate-table "
      "--out result.json\n"
      "       sinscal calibrate --session DIR_OF_SESSIONS | --session-list FILE [--session ...] "
      "--out OUT_DIR\n"
      "Estimates the calibration coefficients with their sigma. closed-form: the 24 base\n"
      "coefficients from the static dwells; the paper's method exactly:\n"
      "  --stage1 point --model uncoupled --channels north,east\n"
      "kf: the error-state Kalman filter, with the extended terms the sensor profile declares;\n"
      "--stream reads the samples from standard input as they arrive.\n"
      "table-free: a hand-held session (no plan needed): static poses found in the data, both\n"
      "triads from gravity's magnitude and the turns between poses, the raw-count view.\n"
      "six-face: the six faces and three known turns, labelled in the log ([six_face]).\n"
      "rate-table: the plan's constant-rate segments and static positions, from their means.\n"
      "Batch (several sessions): OUT_DIR/NAME.json per session and OUT_DIR/summary.csv.");
  if (!vm) return 0;
  o.stream = vm->count("stream") > 0;
  o.force = vm->count("force") > 0;
  o.no_position = vm->count("no-position") > 0;
  o.no_motion_zero_velocity = vm->count("no-motion-zero-velocity") > 0;
  o.no_table_angles = vm->count("no-table-angles") > 0;
  o.no_zero_velocity = vm->count("no-zero-velocity") > 0;
  check_method_options(*vm, o);
  if (o.method == Method::Kf) install_stop_handlers();  // Ctrl-C: stop, finish, write
  // One session.ini given as a file: a single run. Anything naming a folder of sessions, a
  // list, or several sessions: a batch.
  if (session_paths.empty() && session_list.empty())
    throw UsageError("give --session (or --session-list)");
  std::vector<std::string> sessions;
  bool batch = !session_list.empty() || session_paths.size() > 1;
  for (const auto& p : session_paths) {
    const auto found = find_sessions(p);
    batch |=
        found.size() > 1 || (std::filesystem::is_directory(p) &&
                             !std::filesystem::exists(std::filesystem::path(p) / "session.ini"));
    sessions.insert(sessions.end(), found.begin(), found.end());
  }
  if (!session_list.empty()) {
    const auto listed = read_session_list(session_list);
    sessions.insert(sessions.end(), listed.begin(), listed.end());
  }
  if (batch) {
    if (o.stream) throw UsageError("--stream reads one session from standard input, not a batch");
    if (!monitor_path.empty())
      throw UsageError("--monitor names one file; a batch writes OUT_DIR/NAME.monitor.jsonl");
    return calibrate_batch(o, sessions, out_path,
                           jobs > 0 ? jobs : std::max(1u, std::thread::hardware_concurrency()));
  }
  const SessionSummary row = calibrate_session(o, sessions.front(), out_path, monitor_path, true,
                                               o.method == Method::Kf && isatty(fileno(stderr)));
  if (row.status == "ok") return 0;
  std::fprintf(stderr, "sinscal calibrate: %s%s (the estimates up to there are written)\n",
               row.status == "interrupted" ? "" : "error: ", row.message.c_str());
  return row.status == "interrupted" ? kInterrupted : kDataError;
}

}  // namespace sinscal::cli
