// sinscal design: the accuracy a plan will give, predicted without data (the Kalman filter's
// covariance over the plan's truth motion, filter/design/prediction.hpp), on a table described by
// config/tables/*.ini; with --optimize, the search for the shortest plan that meets the targets
// (design_optimize.cpp).
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>

#include "apps/commands.hpp"
#include "apps/design.hpp"
#include "filter/design/advice.hpp"
#include "filter/design/robustness.hpp"
#include "models/config.hpp"
#include "models/units.hpp"
#include "report/monitor.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

CalibratorOptions design_options(const DesignCliOptions& o, const SensorProfile& profile,
                                 const TableSpec* table) {
  CalibratorOptions ko = calibrator_options_from_profile(profile, o.prior_scale);
  ko.attitude_sigma = o.table_sigma > 0.0 ? o.table_sigma * units::arcsec
                      : table             ? table->attitude_sigma
                                          : kDefaultTableAttitudeSigma;
  ko.attitude = o.attitude;
  if (!o.misalignment_frame.empty()) try {
      ko.misalignment_frame = parse_misalignment_frame(o.misalignment_frame);
      reported_frame(ko);  // the table frame needs attitude updates
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--misalignment-frame: ") + e.what());
    }
  if (table) ko.zero_velocity_in_motion = table->reference_on_axes;
  try {
    apply_terms(ko.layout, o.terms);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--terms: ") + e.what());
  }
  return ko;
}

void check_table(const Plan& plan, const TableSpec& table, double margin) {
  if (plan.table.axes > table.axes)
    throw ConfigError(plan.path + ": a plan for a three-axis table ([table] axes = 3), and " +
                      table.path + " has " + std::to_string(table.axes) + " axes");
  const auto violations = check_against_table(build_motion(plan, plan.site), table, margin);
  if (violations.empty()) return;
  std::string msg = plan.path + ": the plan asks more than the table " + table.path + " gives:";
  constexpr std::size_t kShown = 5;
  for (std::size_t i = 0; i < violations.size() && i < kShown; ++i) {
    char line[320];
    std::snprintf(line, sizeof line, "\n  motion segment %d (t = %.1f s): %s",
                  violations[i].segment, violations[i].t0, violations[i].what.c_str());
    msg += line;
  }
  if (violations.size() > kShown)
    msg += "\n  and " + std::to_string(violations.size() - kShown) + " more";
  throw std::runtime_error(msg);
}

std::map<std::string, double> design_targets(const DesignCliOptions& o,
                                             const SensorProfile& profile) {
  if (o.targets.empty()) return profile.sigma_targets;
  std::error_code ec;
  if (std::filesystem::is_regular_file(o.targets, ec))
    return read_sigma_targets(IniFile(o.targets));
  // Inline targets hold "family = value unit"; without '=' the text names a file.
  if (o.targets.find('=') == std::string::npos) {
    if (std::filesystem::exists(o.targets, ec))
      throw UsageError("--targets " + o.targets + ": not a regular file");
    throw UsageError("--targets " + o.targets +
                     ": no such file (inline targets read \"family = value unit; ...\")");
  }
  std::string text = "[targets]\n";
  for (char c : o.targets) text += c == ';' ? '\n' : c;
  try {
    return read_sigma_targets(IniFile("--targets", text));
  } catch (const ConfigError& e) {
    // "--targets:3: ..." names the INI line: the user wrote items separated by ';'.
    std::string msg = e.what();
    int line = 0;
    if (std::sscanf(msg.c_str(), "--targets:%d:", &line) == 1 && line > 1)
      msg = "--targets, item " + std::to_string(line - 1) + msg.substr(msg.find(':', 10));
    throw ConfigError(msg);
  }
}

void write_design_files(const std::string& dir, const PlanPrediction& p, const DesignInputs& in,
                        const nlohmann::ordered_json& extra) {
  const std::string json_path = dir + "/design.json", sigma_path = dir + "/sigma.jsonl";
  write_atomically(sigma_path, [&](std::ostream& s) {
    for (const auto& r : p.history) s << monitor_line(r) << "\n";
  });
  nlohmann::ordered_json j = design_json(p, in);
  for (const auto& [k, v] : extra.items()) j[k] = v;
  write_atomically(json_path, [&](std::ostream& s) { s << j.dump(2) << "\n"; });
  std::cout << "Wrote " << json_path << " and " << sigma_path
            << " (sigmas over time; sinscal plot-convergence draws it)\n";
}

namespace {

void check_design_options(const DesignCliOptions& o, const po::variables_map& vm) {
  if (!(o.rate_hz >= 1.0 && o.rate_hz <= 10000.0))
    throw UsageError("--rate must be within 1 and 10000 Hz");
  if (!(o.search_rate_hz >= 1.0 && o.search_rate_hz <= 1000.0))
    throw UsageError("--search-rate must be within 1 and 1000 Hz");
  if (vm.count("table-sigma") && !(o.table_sigma > 0.0 && o.table_sigma < 3600.0))
    throw UsageError("--table-sigma must be above 0 and below 3600 arcsec");
  if (!(o.prior_scale > 0.0 && o.prior_scale < 1e6))
    throw UsageError("--prior-scale must be above 0 and below 1e6");
  if (!(o.budget_s >= 0.0 && o.budget_s <= 86400.0))
    throw UsageError("--budget-s must be within 0 and 86400 s");
  if (!(o.beam >= 1 && o.beam <= 64)) throw UsageError("--beam must be within 1 and 64");
  if (!(o.structure_moves >= 0 && o.structure_moves <= 100000))
    throw UsageError("--structure-moves must be within 0 and 100000 passes");
  if (!(o.anneal >= 0 && o.anneal <= 1000000))
    throw UsageError("--anneal must be within 0 and 1000000 iterations");
  if (o.robustness != 0 && !(o.robustness >= 2 && o.robustness <= 1000))
    throw UsageError("--robustness must be within 2 and 1000 seeds");
  if (o.optimize && (o.table.empty() || o.out.empty()))
    throw UsageError("--optimize needs --table (the limits to search within) and --out");
  auto given = [&](const char* key) { return vm.count(key) && !vm[key].defaulted(); };
  if (!o.optimize &&
      (given("budget-s") || given("compare") || given("targets") || given("beam") ||
       given("search-rate") || given("require") || given("structure-moves") || given("anneal")))
    throw UsageError(
        "--budget-s, --compare, --targets, --require, --beam, --search-rate, "
        "--structure-moves and --anneal belong to --optimize");
  if (given("targets") && o.targets.find_first_not_of(" \t;") == std::string::npos)
    throw UsageError("--targets is empty: give \"family = value unit; ...\" or a file");
}

int design_one(const DesignCliOptions& o) {
  const Plan plan = Plan::load(o.plan);
  if (!plan.has_site)
    throw UsageError(o.plan + ": the plan has no [site]: design needs the latitude and height");
  const SensorProfile profile = SensorProfile::load(o.sensor);
  std::optional<TableSpec> table;
  if (!o.table.empty()) table = TableSpec::load(o.table);
  const CalibratorOptions ko = design_options(o, profile, table ? &*table : nullptr);
  if (table) check_table(plan, *table, ko.static_margin);
  if (!o.out.empty()) {
    std::filesystem::create_directories(o.out);
    check_outputs(
        {{"plan", o.plan}, {"sensor", o.sensor}, {"table", o.table}},
        {{"design.json", o.out + "/design.json"}, {"sigma.jsonl", o.out + "/sigma.jsonl"}});
  }
  DesignOptions design;
  design.rate_hz = o.rate_hz;
  const std::clock_t c0 = std::clock();
  const PlanPrediction p = predict_plan(plan, ko, profile.sigma_targets, design);
  const DesignInputs in{o.plan,
                        o.sensor,
                        o.table,
                        plan.name,
                        profile.name,
                        table ? table->name : std::string("a table of 2-3 arcsec"),
                        ko.attitude_sigma,
                        o.rate_hz,
                        static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC};
  std::cout << design_tables(p, in);
  nlohmann::ordered_json extra;
  const auto advice = separation_advice(plan, ko, p, std::min(o.rate_hz, 20.0));
  std::cout << advice_table(advice);
  if (!advice.empty()) extra["separation_advice"] = advice_json(advice);
  if (o.robustness > 0) {
    const auto rows =
        robustness(plan, profile, ko, standard_perturbations(), o.robustness, o.rate_hz);
    std::cout << robustness_table(rows, o.robustness, o.rate_hz);
    extra["robustness"] = robustness_json(rows, o.robustness, o.rate_hz);
  }
  if (!o.out.empty()) write_design_files(o.out, p, in, extra);
  return 0;
}

}  // namespace

int cmd_design(const std::vector<std::string>& args) {
  po::options_description d("sinscal design options");
  DesignCliOptions o;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("plan", po::value(&o.plan)->required(),
       "plan INI (config/plans/*.ini) with its [site]; with --optimize the reference plan: its "
       "site, and the plan the search is compared with")
      ("sensor", po::value(&o.sensor)->required(),
       "sensor profile (config/sensors/*.ini): noise, priors, extended families, [targets]")
      ("table", po::value(&o.table),
       "table description (config/tables/*.ini): limits the plan must keep, attitude accuracy, "
       "reference point on the axes")
      ("out", po::value(&o.out), "directory to write design.json and sigma.jsonl into")
      ("rate", po::value(&o.rate_hz)->default_value(50.0),
       "sample rate of the ideal IMU the covariance is run with [Hz]; the sigmas depend on it by "
       "well under 1 % from 20 Hz up")
      ("table-sigma", po::value(&o.table_sigma),
       "table attitude error per orientation and axis [arcsec] (default: the table's, else 2.5)")
      ("attitude", po::value(&o.attitude)->default_value(CalibratorOptions::AttitudeUpdates::Every,
       "every"), "table-attitude updates, as calibrate --method kf: every | first | none")
      ("misalignment-frame", po::value(&o.misalignment_frame),
       "the frame of the predicted misalignments, as calibrate: table (with attitude updates, "
       "the default) | triad (the accelerometer triad as the body frame; the default with "
       "--attitude none)")
      ("terms", po::value(&o.terms), "extended terms on top of the profile's, as calibrate")
      ("prior-scale", po::value(&o.prior_scale)->default_value(kDefaultPriorScale),
       "prior sigma = this times the profile's largest coefficient magnitude")
      ("robustness", po::value(&o.robustness)->default_value(0),
       "N simulated sessions per perturbation (the table 2x worse, the reference point 50 mm off "
       "the axes, the noise 2x): RMS of error / predicted sigma per family")
      ("optimize", "search for the shortest plan on the table whose sigmas meet every target "
       "(writes DIR/optimized.ini)")
      ("targets", po::value(&o.targets),
       "--optimize: sigma targets, a file with [targets] or \"family = value unit; ...\" "
       "(default: the profile's [targets])")
      ("require", po::value(&o.require)->multitoken(),
       "--optimize: families the plan must determine (sigma at most half the prior), e.g. "
       "accel.lever_arm time_delay; without --targets the search targets these only")
      ("budget-s", po::value(&o.budget_s)->default_value(0.0),
       "--optimize: the best plan no longer than this [s] (0: the shortest that meets)")
      ("compare", po::value(&o.compare)->multitoken(),
       "--optimize: further plans to compare with (besides --plan)")
      ("beam", po::value(&o.beam)->default_value(4), "--optimize: plans kept per step")
      ("structure-moves", po::value(&o.structure_moves)->default_value(2000),
       "--optimize with --budget-s: covariance passes the structure moves may spend (turns "
       "split, inserted, removed, changed; 0: none)")
      ("anneal", po::value(&o.anneal)->default_value(0),
       "--optimize with --budget-s: iterations of simulated annealing over the same moves from "
       "the search's plan (about one covariance pass each; 0: none)")
      ("search-rate", po::value(&o.search_rate_hz)->default_value(20.0),
       "--optimize: ideal IMU rate of the search's passes [Hz] (the result is confirmed at "
       "--rate)");
  // clang-format on
  const auto vm = parse(
      args, d,
      "Usage: sinscal design --plan P --sensor S [--table T] [--out DIR]\n"
      "       sinscal design --optimize --plan REF --sensor S --table T --out DIR\n"
      "         [--targets T] [--require FAMILY ...] [--budget-s N] [--compare P2 ...]\n"
      "The accuracy the plan will give, without data: the Kalman filter of calibrate --method kf\n"
      "run over the plan's truth motion with an ideal IMU. Prints each family's predicted sigma\n"
      "against the profile's target and when it is reached, and the combinations the plan\n"
      "cannot observe. --optimize searches rotation plans at the table's limits.");
  if (!vm) return 0;
  o.optimize = vm->count("optimize") > 0;
  check_design_options(o, *vm);
  return o.optimize ? design_optimize(o) : design_one(o);
}

}  // namespace sinscal::cli
