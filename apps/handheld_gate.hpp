// The plausibility gate of a hand-held session, the same for `calibrate --method table-free`
// (apps/calibrate_table_free.cpp) and `diagnose` (apps/diagnose_handheld.cpp): the rests before
// the fit (check_handheld), the fit's parts after it (check_handheld_fit,
// docs/methods/table-free.md).
#pragma once

#include "filter/plausibility/rest_plausibility.hpp"
#include "filter/table_free/handheld_run.hpp"
#include "rig/session.hpp"

namespace sinscal::cli {

/// Runs the table-free calibration of `session` through the gate: a failed check throws
/// PlausibilityError (exit 2) unless `force`; the checks, passed or forced, are in `gate`, the
/// fit's bounds per stage in `bounds` (when given).
TableFreeRun gated_table_free_run(const Session& session, TableFreeRunOptions options, bool force,
                                  PlausibilityReport& gate, HandheldFitBounds* bounds = nullptr);

}  // namespace sinscal::cli
