// What every command of the sinscal tool shares: exit codes, usage errors, option parsing with
// enum-like options validated once (Boost.Program_options validators), the stop signal.
#pragma once

#include <atomic>
#include <boost/program_options.hpp>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "filter/closed_form/closed_form.hpp"
#include "filter/kalman/kalman_calibrator.hpp"
#include "filter/table_free/pose_detector.hpp"
#include "rig/session.hpp"

namespace sinscal::cli {

namespace po = boost::program_options;

constexpr int kUsageError = 1;
constexpr int kDataError = 2;
constexpr int kDisagree = 3;       // compare: the results differ beyond the given tolerance
constexpr int kPartial = 4;        // report: the HTML page written, the PDF not
constexpr int kTargetsNotMet = 5;  // design --optimize: no plan found meets every target
constexpr int kInterrupted = 130;  // SIGINT / SIGTERM: stopped, what was computed written

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Parses a command's options; prints the usage and returns nullopt for --help.
std::optional<po::variables_map> parse(
    const std::vector<std::string>& args, const po::options_description& desc,
    const std::string& usage, const po::positional_options_description* positional = nullptr);

/// Refuses (a usage error naming both) an output that is one of the inputs or another output.
void refuse_overwrite(const std::vector<std::pair<std::string, std::string>>& inputs,
                      const std::vector<std::pair<std::string, std::string>>& outputs);
/// Every file a session reads (session.ini, plan, sensor profile, truth, the log's files).
std::vector<std::pair<std::string, std::string>> session_inputs(const Session& session);
/// The session's [table_free] options where the command line does not give them: --pose-window,
/// --min-pose and --pose-accel-only into `detector`, --edge-trim into `edge_trim` (if not null).
void apply_table_free_settings(const TableFreeSettings& session, const po::variables_map& vm,
                               PoseDetectorOptions& detector, double* edge_trim);

/// "LOG (session S): ", the prefix that names a six-face session's files in its errors.
std::string six_face_where(const Session& session);

/// printf-style formatting of one number.
std::string fmt(const char* format, double v);

/// Set by SIGINT / SIGTERM once install_stop_handlers() ran: a calibration stops reading,
/// finishes and writes its results.
extern std::atomic<bool> g_stop;
/// The command line of this run as a shell would take it back (set by main; results record it).
extern std::string g_command_line;
void install_stop_handlers();

/// An option whose value is one of a few names (--method kf): the names and their values.
template <class E>
struct Choice {
  E value;
};

/// Calibration method of `calibrate`.
enum class Method { ClosedForm, Kf, TableFree, SixFace, RateTable };
/// What a bad sample does.
enum class OnBadSample { Stop, Skip };
/// The vertical channel of `navigate`.
enum class Vertical { Free, Held };

// Validators (found by argument-dependent lookup, so in the namespace of each type): an unknown
// name is a usage error naming the accepted ones.
void validate(boost::any& v, const std::vector<std::string>& values, Method*, int);
void validate(boost::any& v, const std::vector<std::string>& values, OnBadSample*, int);
void validate(boost::any& v, const std::vector<std::string>& values, Vertical*, int);

}  // namespace sinscal::cli

namespace sinscal {
void validate(boost::any& v, const std::vector<std::string>& values,
              CalibratorOptions::AttitudeUpdates*, int);
void validate(boost::any& v, const std::vector<std::string>& values, CalibratorOptions::StaticFrom*,
              int);
void validate(boost::any& v, const std::vector<std::string>& values, Stage1Method*, int);
void validate(boost::any& v, const std::vector<std::string>& values, ErrorModelKind*, int);
void validate(boost::any& v, const std::vector<std::string>& values, ChannelSet*, int);
namespace cli {
std::string name_of(Method m);
std::string name_of(Stage1Method m);
std::string name_of(ErrorModelKind m);
std::string name_of(const ChannelSet& c);
}  // namespace cli
}  // namespace sinscal
