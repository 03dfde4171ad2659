// Plan design, third part: a lower bound on what any plan of the search's segments can reach in
// a given table time, from a convex relaxation (optimal experimental design over a library of
// segments whose durations are the unknowns). docs/methods/design.md "The bound".
#pragma once

#include <Eigen/Dense>
#include <map>
#include <string>
#include <vector>

#include "filter/design/search.hpp"
#include "models/units.hpp"

namespace sinscal {

/// The information of the segments a plan is made of, about the coefficient states, each
/// scaled by its target (by its prior sigma when its family has none): in these units the
/// diagonal of the inverse of the summed information is (sigma / target)^2.
struct InformationLibrary {
  struct Segment {
    std::string name;             // e.g. "o3 +x 90" (a turn from orientation 3), "o3 static"
    double duration = 0.0;        // s of table time it takes
    Eigen::MatrixXd information;  // scaled, symmetric positive semi-definite
    int from = 0;                 // the orientation (index) it starts at
    int to = 0;                   // the orientation it ends at (from, for a rest)
    int axis = -1;                // 0..5 (+x -x +y -y +z -z) for a turn; -1 for a rest
    int quarters = 0;             // the turn's angle in quarter turns (1 or 2)
  };
  std::vector<Segment> segments;
  Eigen::MatrixXd prior;  // the prior's information, scaled
  // coefficient_catalog() index of each state; -1 for the three of the rotation shared by every
  // dwell's attitude (a nuisance, last, in units of its prior sigma, never targeted)
  std::vector<int> catalog;
  std::vector<bool> targeted;  // the state's family has a target
  int orientations = 0;        // distinct static orientations in the library
  int start = 0;               // the orientation of the search's first start (body x up)
  double cpu_s = 0.0;          // CPU it took to build
};

/// The filter whose information bounds the calibration's: the same coefficients (in the frame
/// the calibration reports: the accelerometer triad's in the triad frame), the attitude known at
/// every update of every dwell (`kOracleAttitudeSigma`) relative to a rotation shared by all
/// dwells (the table base's states, a nuisance), no bias wander states. Every measurement of
/// `options` is one of it and it knows the navigation errors at each dwell up to that rotation,
/// so its information is at least the calibration's and adds up over segments.
constexpr double kOracleAttitudeSigma = 1e-3 * units::arcsec;
CalibratorOptions oracle_options(const CalibratorOptions& options);

/// The library on `table` at `site`: every orientation reachable by 90 deg turns about the body
/// axes from the search's first start (24), at each every turn of the search's space (6 axes,
/// 90 and 180 deg) followed by the shortest dwell, and one second at rest. Each segment's
/// information is the oracle filter's increase over it. Throws std::invalid_argument for no
/// targets.
InformationLibrary information_library(const CalibratorOptions& options, const TableSpec& table,
                                       const Site& site,
                                       const std::map<std::string, double>& targets,
                                       double rate_hz = 20.0);

/// The relaxation's solution at a budget: min over segment times t >= 0, sum t = budget, of the
/// worst (sigma / target)^2 over the targeted coefficients with information
/// prior + sum t_j I_j / d_j. Solved by a multiplicative algorithm (Silvey, Titterington and
/// Torsney 1978) on the smoothed maximum, stopped when the squared ratios' gap is within
/// `tolerance` (relative) or after `max_iterations`; `lower` is certified by the equivalence
/// theorem's duality gap (valid whatever the iterate), `upper` is the relaxed design reached.
struct DesignBound {
  double budget_s = 0.0;
  double lower = 0.0;  // worst sigma / target: no plan of the library's segments does better
  double upper = 0.0;  // the relaxed design's worst sigma / target
  std::string family;  // the family of the relaxed design's worst coefficient
  int iterations = 0;
  std::vector<double> time_s;  // the relaxed design's time per segment
};
/// With `decide` > 0 it also stops as soon as the bound is above `decide` or the relaxed design
/// below it (all the bisection for the time needs).
DesignBound relaxed_bound(const InformationLibrary& library, double budget_s,
                          double tolerance = 0.02, int max_iterations = 20000, double decide = 0.0);

/// A table time below which no plan of the library's segments meets every target (certified:
/// the bound's `lower` exceeds 1 there), by bisection to `resolution_s`.
double bound_time_for_targets(const InformationLibrary& library, double resolution_s = 5.0,
                              double max_s = 20000.0);

}  // namespace sinscal
