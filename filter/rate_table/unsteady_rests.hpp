// Rests whose outputs are not stationary (issue 34, APOPHIS board 3's last rest): a static
// segment of a rate-table or tumble session whose output changes level within it, tested against
// the log's rest noise (the other rests' scatter and autocorrelation time), is not a rest. When
// its mean also disagrees with the fit of all segments it is left out of the estimate and named;
// the run refuses when leaving it out would leave a coefficient undetermined.
// docs/methods/rate-table.md, "Rests that are not rests".
#pragma once

#include <string>
#include <vector>

#include "filter/rate_table/rate_table.hpp"

namespace sinscal {

/// Each static segment's largest level change within it (one output, the most significant),
/// listed when beyond the chi-square quantile at 1 - alpha over every split, output and rest
/// tested: the chi2 gain of two levels over one, in the noise of the log's other rests (their
/// readings-weighted variance and autocorrelation time per output). A log with one rest tests
/// nothing.
std::vector<UnsteadyRest> unsteady_rests(const std::vector<RateReading>& readings,
                                         const std::vector<RateSegment>& segments,
                                         const std::vector<SegmentMean>& means,
                                         double alpha = 0.01);

/// rate_table_calibrate with the rests that are not rests checked: a listed rest whose means, in
/// the log's rest noise, disagree with the fit of the other segments (the deleted-rest chi2 of
/// its triad's coefficients beyond the chi-square quantile at 1 - alpha / listed rests) is left
/// out (unless `keep`) and the fit redone without it; the others are kept, said so (a rest whose
/// check's refits fail is kept unchecked, said so). The result's
/// `unsteady` holds them all. Throws RateTableError naming the rest when leaving it out would
/// leave a coefficient of the full fit undetermined.
RateTableResult rate_table_calibrate_rests(const std::vector<RateReading>& readings,
                                           const std::vector<RateSegment>& segments,
                                           const std::vector<SegmentMean>& means, const Site& site,
                                           double gravity, const RateTableOptions& options,
                                           bool keep, double alpha = 0.01);

/// The plan's segments less those `r` left out: the segments of its means and residuals.
std::vector<RateSegment> fitted_segments(const std::vector<RateSegment>& segments,
                                         const RateTableResult& r);

}  // namespace sinscal
