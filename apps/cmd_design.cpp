// sinscal design: the accuracy a plan will give, predicted without data (the Kalman filter's
// covariance over the plan's truth motion, filter/design/prediction.hpp), on a table described by
// config/tables/*.ini; writes design.json and the sigmas over time.
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "filter/design/prediction.hpp"
#include "models/units.hpp"
#include "report/design_output.hpp"
#include "report/monitor.hpp"
#include "report/output.hpp"
#include "rig/table_spec.hpp"

namespace sinscal::cli {

namespace {

struct DesignCliOptions {
  std::string plan, sensor, table, out, terms;
  double rate_hz = 50.0, table_sigma = 0.0, prior_scale = kDefaultPriorScale;
  CalibratorOptions::AttitudeUpdates attitude = CalibratorOptions::AttitudeUpdates::Every;
};

// The options `calibrate --method kf` would run the session with, from the profile and table.
CalibratorOptions design_options(const DesignCliOptions& o, const SensorProfile& profile,
                                 const TableSpec* table) {
  CalibratorOptions ko = calibrator_options_from_profile(profile, o.prior_scale);
  ko.attitude_sigma = o.table_sigma > 0.0 ? o.table_sigma * units::arcsec
                      : table             ? table->attitude_sigma
                                          : kDefaultTableAttitudeSigma;
  ko.attitude = o.attitude;
  if (table) ko.zero_velocity_in_motion = table->reference_on_axes;
  try {
    apply_terms(ko.layout, o.terms);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--terms: ") + e.what());
  }
  return ko;
}

void check_table(const Plan& plan, const TableSpec& table, double margin) {
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

}  // namespace

int cmd_design(const std::vector<std::string>& args) {
  po::options_description d("sinscal design options");
  DesignCliOptions o;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("plan", po::value(&o.plan)->required(), "plan INI (config/plans/*.ini) with its [site]")
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
      ("terms", po::value(&o.terms), "extended terms on top of the profile's, as calibrate")
      ("prior-scale", po::value(&o.prior_scale)->default_value(kDefaultPriorScale),
       "prior sigma = this times the profile's largest coefficient magnitude");
  // clang-format on
  const auto vm = parse(
      args, d,
      "Usage: sinscal design --plan P --sensor S [--table T] [--out DIR]\n"
      "The accuracy the plan will give, without data: the Kalman filter of calibrate --method kf\n"
      "run over the plan's truth motion with an ideal IMU. Prints each family's predicted sigma\n"
      "against the profile's target and when it is reached, and the combinations the plan\n"
      "cannot observe.");
  if (!vm) return 0;
  if (!(o.rate_hz >= 1.0 && o.rate_hz <= 10000.0))
    throw UsageError("--rate must be within 1 and 10000 Hz");
  if (vm->count("table-sigma") && !(o.table_sigma > 0.0 && o.table_sigma < 3600.0))
    throw UsageError("--table-sigma must be above 0 and below 3600 arcsec");
  if (!(o.prior_scale > 0.0 && o.prior_scale < 1e6))
    throw UsageError("--prior-scale must be above 0 and below 1e6");
  const Plan plan = Plan::load(o.plan);
  if (!plan.has_site)
    throw UsageError(o.plan + ": the plan has no [site]: design needs the latitude and height");
  const SensorProfile profile = SensorProfile::load(o.sensor);
  std::optional<TableSpec> table;
  if (!o.table.empty()) table = TableSpec::load(o.table);
  const CalibratorOptions ko = design_options(o, profile, table ? &*table : nullptr);
  if (table) check_table(plan, *table, ko.static_margin);
  if (!o.out.empty()) std::filesystem::create_directories(o.out);
  const std::string json_path = o.out.empty() ? "" : o.out + "/design.json";
  const std::string sigma_path = o.out.empty() ? "" : o.out + "/sigma.jsonl";
  if (!o.out.empty())
    check_outputs({{"plan", o.plan}, {"sensor", o.sensor}, {"table", o.table}},
                  {{"design.json", json_path}, {"sigma.jsonl", sigma_path}});
  DesignOptions design;
  design.rate_hz = o.rate_hz;
  const std::clock_t c0 = std::clock();
  const PlanPrediction p = predict_plan(plan, ko, profile.sigma_targets, design);
  DesignInputs in{o.plan,
                  o.sensor,
                  o.table,
                  plan.name,
                  profile.name,
                  table ? table->name : std::string("a table of 2-3 arcsec"),
                  ko.attitude_sigma,
                  o.rate_hz,
                  static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC};
  std::cout << design_tables(p, in);
  if (!o.out.empty()) {
    write_atomically(sigma_path, [&](std::ostream& s) {
      for (const auto& r : p.history) s << monitor_line(r) << "\n";
    });
    write_atomically(json_path, [&](std::ostream& s) { s << design_json(p, in).dump(2) << "\n"; });
    std::cout << "Wrote " << json_path << " and " << sigma_path
              << " (sigmas over time; sinscal plot-convergence draws it)\n";
  }
  return 0;
}

}  // namespace sinscal::cli
