// Result files of the rate-table and tumble calibration (docs/formats.md, "Rate-table result"):
// the catalog's coefficients in the result schema, and a "rate_table" section with the segments'
// means, the fit's chi2, what the segments do not determine and the terms outside the catalog
// (gyro K2 across rates, accelerometer K3).
#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "filter/rate_table/rate_table.hpp"
#include "report/result.hpp"

namespace sinscal {

ResultCoefficients result_coefficients(const RateTableResult& r);
nlohmann::ordered_json result_sections(const RateTableResult& r,
                                       const std::vector<RateSegment>& segments);
/// The terminal table: each coefficient (with the truth when given), the fit, the segments.
std::string rate_table_text(const RateTableResult& r, const std::vector<RateSegment>& segments,
                            const ResultCoefficients& truth);

}  // namespace sinscal
