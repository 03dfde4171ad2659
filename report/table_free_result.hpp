// Result files of the table-free calibration (docs/formats.md, "Table-free result"): the
// coefficients in the result schema of the other methods, and its sections (method, data, pose
// detection, poses, noise, the raw-count view, validation records).
#pragma once

#include <nlohmann/json.hpp>

#include "filter/table_free/handheld_run.hpp"
#include "report/result.hpp"

namespace sinscal {

/// The 24 base coefficients (accelerometer-triad frame; the three fixed by it marked so).
ResultCoefficients result_coefficients(const TableFreeRun& run);
/// The sections after "coefficients".
nlohmann::ordered_json result_sections(const TableFreeRun& run);

/// The raw-count view of one triad as its result entries, by the sensors' own (log) axes:
/// "accel.sensitivity.x" (counts per SI unit), "accel.offset.x" (counts), "accel.row_norm.x".
/// Empty for a triad not logged in counts.
struct RawEntry {
  std::string name;
  double value = 0.0;
  double sigma = 0.0;  // row norms: 0 (none given)
  double nominal = 0.0;
  std::string unit;
  bool has_sigma = true;
};
std::vector<RawEntry> raw_entries(const TableFreeRun& run);

}  // namespace sinscal
