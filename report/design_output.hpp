// What `sinscal design` writes: design.json (docs/formats.md "Design file"), the predicted sigmas
// over plan time as a monitor file (sigma.jsonl, the format of `calibrate --monitor`, so
// `sinscal plot` draws it), and the terminal tables.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "filter/design/advice.hpp"
#include "filter/design/prediction.hpp"
#include "filter/design/robustness.hpp"

namespace sinscal {

/// Where the prediction came from (recorded in design.json and the table's title).
struct DesignInputs {
  std::string plan, sensor, table;  // paths ("" when no table file)
  std::string plan_name, sensor_name, table_name;
  double attitude_sigma = 0.0;  // rad, per dwell
  double rate_hz = 0.0;
  double cpu_seconds = 0.0;
};

nlohmann::ordered_json design_json(const PlanPrediction& p, const DesignInputs& in);
/// The family table (target, predicted worst sigma and its coefficient, when reached), the
/// coefficient table (prior, predicted sigma, observed) and the unobservable combinations.
std::string design_tables(const PlanPrediction& p, const DesignInputs& in);

/// The identifiability advice: per family the plan does not observe, the turn that separates it.
std::string advice_table(const std::vector<SeparationAdvice>& advice);
nlohmann::ordered_json advice_json(const std::vector<SeparationAdvice>& advice);
/// design --optimize --require: whether the plan found determines each required family (observed:
/// below prior / sqrt(2) and in no combination the plan cannot observe), from the confirming pass.
std::string required_table(const std::vector<std::string>& required, const PlanPrediction& p,
                           const std::map<std::string, double>& targets);
nlohmann::ordered_json required_json(const std::vector<std::string>& required,
                                     const PlanPrediction& p,
                                     const std::map<std::string, double>& targets);
/// The robustness runs as a table (a row per perturbation, a column per family) and as JSON.
std::string robustness_table(const std::vector<RobustnessRow>& rows, int seeds, double rate_hz);
nlohmann::ordered_json robustness_json(const std::vector<RobustnessRow>& rows, int seeds,
                                       double rate_hz);

}  // namespace sinscal
