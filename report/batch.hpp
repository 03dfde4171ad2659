// Batch calibration: the sessions a path or list names, unique result names, a thread pool that
// runs one calibration per session (a failure does not stop the others), the run-status rules and
// the summary table (summary.csv, docs/formats.md).
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "filter/kalman/kalman_run.hpp"
#include "report/result.hpp"

namespace sinscal {

/// The session.ini files a path names: the file itself; a directory holding session.ini; or a
/// directory whose subdirectories hold session.ini (sorted by name). Throws naming the path if it
/// names none.
std::vector<std::string> find_sessions(const std::string& path);
/// A list file: one path per line (session.ini or a directory, as find_sessions; relative to the
/// list's directory), '#' comments and blank lines ignored. Throws naming file and line.
std::vector<std::string> read_session_list(const std::string& list_path);
/// Result file stems for a batch: the session directory's name (or the file's stem), made unique
/// over the whole batch with -2, -3, ... (never two sessions on one file).
std::vector<std::string> result_stems(const std::vector<std::string>& sessions);

/// One row of a batch run's summary table.
struct SessionSummary {
  std::string session;  // session.ini
  std::string name;     // the session's name
  std::string result;   // result file written; empty if none
  std::string status;   // ok | stopped (bad input) | diverged | interrupted | failed (no result)
  std::string message;  // why, when not ok
  std::size_t samples = 0;
  double duration = 0.0;  // s of data
  std::optional<double> nis_per_dof;
  std::optional<double> converged_at;          // s (Kalman filter with sigma targets)
  std::optional<double> max_error_over_sigma;  // sessions with truth
  ResultCoefficients coefficients;
};

/// The status of a Kalman-filter run: interrupted, stopped (the input), diverged, or ok.
void set_status(const KalmanRun& run, SessionSummary& row);

/// The summary table as CSV (docs/formats.md): a row per session, the coefficients' values and
/// sigmas in the result files' units. Written atomically.
void write_summary_csv(const std::string& path, const std::vector<SessionSummary>& rows);

/// Runs `calibrate_one(i)` for every session on `jobs` threads. An exception makes that session's
/// row "failed" with the message; once `stop` is set, sessions not started are "interrupted".
/// `done(i, row)` is called (serialized) as each session ends.
std::vector<SessionSummary> run_batch(
    const std::vector<std::string>& sessions, unsigned jobs,
    const std::function<SessionSummary(std::size_t)>& calibrate_one,
    const std::atomic<bool>* stop = nullptr,
    const std::function<void(std::size_t, const SessionSummary&)>& done = nullptr);

}  // namespace sinscal
