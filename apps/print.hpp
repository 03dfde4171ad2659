// Printing of results on the terminal (the files are report/'s).
#pragma once

#include <map>
#include <string>

#include "filter/closed_form/closed_form.hpp"
#include "filter/kalman/kalman_run.hpp"
#include "filter/plausibility/rest_plausibility.hpp"
#include "filter/table_free/handheld_run.hpp"
#include "models/sensor_profile.hpp"
#include "report/result.hpp"

namespace sinscal::cli {

/// Coefficient, estimate, sigma, unit; truth, error and error/sigma when `truth` is not empty.
void print_coefficient_table(const ResultCoefficients& coefficients,
                             const ResultCoefficients& truth);
/// What a newcomer reads first: how far the estimates are from the truth (simulations), whether
/// and when every sigma reached its target (each one above it named), what the plan cannot
/// observe, the frame convention, skipped samples.
/// Against the truth (simulations): the largest |error| / sigma and how many are beyond 3.
void print_truth_verdict(const ResultCoefficients& coefficients, const ResultCoefficients& truth);
void print_kalman_verdicts(const KalmanRun& run, const SensorProfile& profile,
                           const ResultCoefficients& truth);
/// The filter's innovation tests: the verdict, and each channel's NIS per dof (p) and Ljung-Box
/// Q (p), failures marked.
void print_innovation_check(const InnovationCheck& check);
/// Live convergence table on a terminal (standard error): per family, the largest sigma against
/// its target.
void print_live_table(const MonitorRecord& record, const std::map<std::string, double>& targets);
/// Stage-1 inputs per dwell, identifiability, the static plan's limits, the paper's forms.
void print_closed_form(const ClosedFormReport& report, const ResultCoefficients& coefficients,
                       const ResultCoefficients& truth);

/// A table-free calibration: the data and the poses found, the fit (chi2/dof), the coefficients
/// with sigmas (and truth), the raw-count view, the validation records.
void print_table_free(const TableFreeRun& run, const HandheldFitBounds& bounds,
                      const ResultCoefficients& coefficients, const ResultCoefficients& truth);
/// An Allan analysis: the stretch analysed and the fitted noise terms per axis.
void print_allan(const AllanRun& run);

}  // namespace sinscal::cli
