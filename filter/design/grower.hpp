// Plan design's incremental covariance pass (filter/design/search.hpp): a genome's pass that
// further turns extend without running its beginning again. Shared by the search and the
// information library of the design bound (filter/design/bound.hpp).
#pragma once

#include <Eigen/Dense>
#include <memory>

#include "filter/design/search.hpp"

namespace sinscal {

// What a search evaluation needs beside the genome.
struct Context {
  const CalibratorOptions& options;
  const TableSpec& table;
  const Site& site;
  const SearchOptions& search;
  double limit = 1e300;  // s: plans longer than this are not kept
};

// A covariance pass over a genome's plan that can be extended by further turns: the filter is
// kept unfinished after the plan's last sample; an extension copies it and runs the new turn
// and dwell only (the samples before are the same in the longer plan).
class Grower {
 public:
  Grower(const PlanGenome& genome, const Context& c);
  Grower extended(const TurnChoice& turn, const Context& c) const;
  Excess score(const Context& c) const;
  /// The covariance of the coefficient states after the plan (finished), in the layout's order.
  Eigen::MatrixXd coefficient_covariance() const;
  /// The same with the table base's states after the coefficients' (with a base).
  Eigen::MatrixXd coefficient_and_base_covariance() const;
  const StateLayout& layout() const { return kf_->layout(); }
  const PlanGenome& genome() const { return g_; }
  double duration() const { return duration_; }

 private:
  void run(const Plan& plan, const Context& c);
  PlanGenome g_;
  std::shared_ptr<Calibrator> kf_;  // not shared while it runs: extended() copies it first
  std::size_t pushed_ = 0;
  double duration_ = 0.0;
};

}  // namespace sinscal
