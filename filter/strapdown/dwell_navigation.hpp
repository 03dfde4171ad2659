// Navigation through the static dwells of a plan: in each dwell the navigator starts from the
// plan's known attitude, zero velocity and the known position, and its errors against those are
// reported over the dwell (the input of the paper's stage 1).
#pragma once

#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "filter/strapdown/strapdown.hpp"
#include "rig/imu_sample.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

/// The data do not fit the plan (a dwell outside the log, for example).
class PlanMismatch : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct DwellNavOptions {
  StrapdownOptions strapdown;
  double output_interval = 1.0;   // s between output rows (0: every sample)
  double time_offset = 0.0;       // s: log time at which the plan starts
  std::string input = "the log";  // the log's name in messages (its file)
};

struct DwellNavRow {
  int dwell = 0;
  const PlanDwell* info = nullptr;
  double t_log = 0.0;                 // s, log time of the row
  NavError error;                     // error.t: time since the dwell's navigation started
  const ImuSample* sample = nullptr;  // the sample the row ends with (null: the dwell's start)
};

struct DwellNavSummary {
  PlanDwell dwell;
  std::size_t samples = 0;
  NavError final_error;
};

class DwellNavigation {
 public:
  DwellNavigation(std::vector<PlanDwell> dwells, const Site& site, const DwellNavOptions& options);
  /// Reads all samples; `sink` gets every output row. Throws PlanMismatch if the log does not
  /// cover every dwell; the summaries of the dwells finished before stay available.
  void run(SampleSource& source, const std::function<void(const DwellNavRow&)>& sink);
  const std::vector<DwellNavSummary>& summaries() const { return summaries_; }

 private:
  std::vector<PlanDwell> dwells_;
  Site site_;
  DwellNavOptions options_;
  std::vector<DwellNavSummary> summaries_;
};

}  // namespace sinscal
