// The table diagnosis' rounds (filter/diagnosis/diagnosis_table.cpp): a dwell finding the
// held-out data refuse while the model still lacks a significant effect of the turns is judged
// again once that effect is in the model, instead of ending the diagnosis.
#include <catch2/catch.hpp>
#include <cstdio>

#include "diagnosis_cases.hpp"

using namespace sinscal;
using namespace sinscal::test;

namespace {

// The family's profile line with magnitudes drawn in [lo, hi] detection sigmas (SI), as the
// matrix writes it (tests/test_diagnosis_matrix.cpp).
ProfileLine hidden_line(const std::string& family, double lo_si, double hi_si) {
  const CoefficientFamily& info = coefficient_family_info(family);
  const auto dot = info.profile_key.find('.');
  char b[160];
  std::snprintf(b, sizeof b, "%s = %.6g %.6g %s", info.profile_key.substr(dot + 1).c_str(),
                lo_si / info.si_per_unit(), hi_si / info.si_per_unit(), info.unit().c_str());
  return {info.profile_key.substr(0, dot), b};
}

}  // namespace

TEST_CASE(
    "Rounds: a drift the held-out turns refuse before the turns' asymmetry joins the model is "
    "named after it",
    "[diagnosis][table][rounds][long]") {
  // Issue 33, the matrix's pair cell seed8 MEMS gyro.bias_drift + gyro.scale_asym at 5-10
  // detection sigmas (the matrix's detection sigmas on seed8 MEMS, SINSCAL_MATRIX_VERBOSE prints
  // them). Round 1 takes the drift (the dwells first); with the asymmetry not yet in the filter's
  // model the drift's held-out turns refused it, which ended the diagnosis with nothing named on
  // 7 of 30 seeds. The rounds now judge the turns' candidate next and the drift again with it in
  // the model. Two seeds of the matrix's cell that ended so (52001: held-out turns 207.9 -> 249.6
  // with the drift alone; 52024: 145.3 -> 201.7; docs/measured/matrix-thermal.md): with the
  // refusal ending the diagnosis neither is named; both must be.
  const double drift_sigma = 1.011e-7, asym_sigma = 1.107e-4;
  const std::vector<ProfileLine> lines = {
      hidden_line("gyro.bias_drift", 5.0 * drift_sigma, 10.0 * drift_sigma),
      hidden_line("gyro.scale_asym", 5.0 * asym_sigma, 10.0 * asym_sigma)};
  const std::vector<std::uint64_t> seeds = {52001, 52024};
  int right = 0;
  std::string misses;
  for (const auto seed : seeds) {
    const HiddenCase c = hidden_case("rounds_pair", "seed8.ini", "mems.ini", lines, seed, 20.0);
    const DiagnosisOutcome o = diagnose_hidden(c, {"gyro.bias_drift", "gyro.scale_asym"});
    const bool ok = o.first_right && o.all_named && o.false_names.empty();
    right += ok ? 1 : 0;
    if (ok) continue;
    misses += "; seed " + std::to_string(seed) + ": " + o.story;
    for (const auto& r : o.result.rejected)
      misses += " (refused " + r.finding.family + ": " + r.reason + ")";
  }
  INFO("both named, a hidden family first, nothing else named: " << right << " of " << seeds.size()
                                                                 << misses);
  CHECK(right == static_cast<int>(seeds.size()));
}
