// sinscal design: the options of the command and the parts its two modes share (one plan's
// prediction in cmd_design.cpp, the plan search in design_optimize.cpp).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "filter/design/prediction.hpp"
#include "models/sensor_profile.hpp"
#include "report/design_output.hpp"
#include "rig/table_spec.hpp"

namespace sinscal::cli {

struct DesignCliOptions {
  std::string plan, sensor, table, out, terms, targets;
  std::string misalignment_frame;  // table | triad | empty (by the attitude updates)
  std::vector<std::string> compare, require;
  double rate_hz = 50.0, table_sigma = 0.0, prior_scale = kDefaultPriorScale;
  CalibratorOptions::AttitudeUpdates attitude = CalibratorOptions::AttitudeUpdates::Every;
  bool optimize = false;
  double budget_s = 0.0, search_rate_hz = 20.0;
  int beam = 4;
  int structure_moves = 2000;  // --optimize with a budget: passes of the structure moves (0: none)
  int anneal = 0;      // --optimize with a budget: iterations of the simulated annealing (0: none)
  int robustness = 0;  // seeds per perturbation (0: none)
};

/// The options `calibrate --method kf` would run a session with, from the profile and table.
CalibratorOptions design_options(const DesignCliOptions& o, const SensorProfile& profile,
                                 const TableSpec* table);
/// A plan beyond the table is bad input: throws naming the segments and figures.
void check_table(const Plan& plan, const TableSpec& table, double margin);
/// Sigma targets: `--targets` (a file with [targets], or "family = value unit; ..."), else the
/// profile's.
std::map<std::string, double> design_targets(const DesignCliOptions& o,
                                             const SensorProfile& profile);
/// design.json and sigma.jsonl into `dir` (`extra` merged into design.json).
void write_design_files(const std::string& dir, const PlanPrediction& p, const DesignInputs& in,
                        const nlohmann::ordered_json& extra = {});

/// design --optimize.
int design_optimize(const DesignCliOptions& o);

}  // namespace sinscal::cli
