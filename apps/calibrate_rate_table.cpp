// sinscal calibrate --method rate-table: a session of rate-table segments and static positions
// (a tumble) calibrated from the segments' mean outputs (filter/rate_table/rate_table.hpp): the
// segments found in the log in the plan's order, the fit, its result file and table.
#include <cstdio>
#include <functional>
#include <iostream>

#include "apps/calibrate.hpp"
#include "filter/plausibility/plausibility.hpp"
#include "filter/rate_table/unsteady_rests.hpp"
#include "models/units.hpp"
#include "report/rate_table_result.hpp"

namespace sinscal::cli {

SessionSummary calibrate_rate_table_session(const CalibrateOptions& o,
                                            const std::string& session_path,
                                            const std::string& out_path, bool verbose) {
  const Session session = Session::load(session_path);
  refuse_overwrite(session_inputs(session), {{"--out", out_path}});
  RateTableOptions ro;
  ro.nominal_rate_hz = session.rate_hz;
  ro.table_sigma = o.table_sigma * units::arcsec;
  ro.cross_asymmetry = o.cross_asymmetry;
  ro.gyro_drift = o.gyro_drift;
  const auto all_segments = rate_segments(session.plan, session.site);
  // Bad readings (a NaN field, a damaged line) stop the run, or with --on-bad-sample skip are
  // left out of the means, counted and the first named.
  std::size_t skipped = 0;
  std::string first_skipped;
  std::function<void(const BadSampleError&)> on_skip;
  if (o.on_bad_sample == OnBadSample::Skip)
    on_skip = [&](const BadSampleError& e) {
      if (skipped++ == 0) first_skipped = e.what();
    };
  const auto readings = read_rate_readings(session.log, on_skip);
  if (skipped > 0 && verbose)
    std::fprintf(stderr, "Skipped %zu bad readings (--on-bad-sample skip), the first: %s\n",
                 skipped, first_skipped.c_str());
  std::vector<SegmentMean> means;
  try {
    means = find_segments(readings, all_segments, ro);
  } catch (const RateTableError& e) {
    throw RateTableError(session.log.file + ": " + e.what());
  }
  // Rests whose outputs are not stationary and whose means disagree: left out, named.
  RateTableResult r;
  try {
    r = rate_table_calibrate_rests(readings, all_segments, means, session.site, 0.0, ro,
                                   o.keep_unsteady);
  } catch (const RateTableError& e) {
    throw RateTableError(session.log.file + ": " + e.what());
  }
  const auto segments = fitted_segments(all_segments, r);
  // The fit's gate: refused (exit 2) unless --force, which records it in the result.
  PlausibilityReport gate;
  const PlausibilityLimits limits = PlausibilityLimits::from_profile(nullptr);
  gate.checks.push_back(check_rate_table_fit(r, limits, session.log.file));
  // The segment each failed triad misses most, in its own sigmas.
  for (const std::string& triad : failed_rate_table_triads(r, limits))
    gate.checks.back().detail += "; the " +
                                 std::string(triad == "gyro" ? "gyros'" : "accelerometers'") +
                                 " largest residual: " + largest_residual(r, segments, triad);
  enforce(gate, o.force);
  const ResultCoefficients coefficients = result_coefficients(r);
  auto sections = result_sections(r, segments);
  record_gate(sections, gate);
  record_provenance(sections, session);
  write_result_json(out_path, coefficients, sections);
  const ResultCoefficients truth = load_truth(session);
  SessionSummary row{session.path,
                     session.name,
                     out_path,
                     "ok",
                     "",
                     readings.size(),
                     static_cast<double>(readings.size()) / session.rate_hz,
                     std::nullopt,
                     std::nullopt,
                     max_error_over_sigma(coefficients, truth),
                     coefficients};
  if (!verbose) return row;
  std::printf("Rate-table calibration of %s: %zu readings, %zu segments from their means\n\n",
              session.name.c_str(), readings.size(), all_segments.size());
  std::cout << rate_table_text(r, segments, truth);
  std::printf("\nResult written to %s\n", out_path.c_str());
  return row;
}

}  // namespace sinscal::cli
