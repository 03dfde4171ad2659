#include "apps/cli.hpp"

#include <signal.h>  // sigaction: Ctrl-C ends a streaming run with its results written

#include <cctype>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "report/output.hpp"

namespace sinscal::cli {

namespace {
// Whether `arg` holds '%' letters-digits-underscores '%' (a Boost.Program_options placeholder).
bool has_placeholder(const std::string& arg) {
  for (std::size_t open = arg.find('%'); open != std::string::npos;) {
    std::size_t k = open + 1;
    while (k < arg.size() && (std::isalnum(static_cast<unsigned char>(arg[k])) || arg[k] == '_'))
      ++k;
    if (k < arg.size() && arg[k] == '%' && k > open + 1) return true;
    open = arg.find('%', open + 1);
  }
  return false;
}
}  // namespace

std::optional<po::variables_map> parse(const std::vector<std::string>& args,
                                       const po::options_description& desc,
                                       const std::string& usage,
                                       const po::positional_options_description* positional) {
  // Boost.Program_options substitutes user text into its error messages and loops forever when
  // that text contains one of its placeholders ("%value%", "%option%", ...): an argument may
  // hold a '%' (a file "50%.csv"), not a '%word%'.
  for (std::size_t i = 0; i < args.size(); ++i)
    if (has_placeholder(args[i]))
      throw UsageError("argument " + std::to_string(i + 1) +
                       " contains a '%name%' placeholder, which sinscal does not accept in "
                       "arguments");
  po::variables_map vm;
  po::command_line_parser parser(args);
  parser.options(desc);
  if (positional) parser.positional(*positional);
  po::store(parser.run(), vm);
  if (vm.count("help")) {
    std::cout << usage << "\n" << desc << "\n";
    return std::nullopt;
  }
  po::notify(vm);
  return vm;
}

void refuse_overwrite(const std::vector<std::pair<std::string, std::string>>& inputs,
                      const std::vector<std::pair<std::string, std::string>>& outputs) {
  try {
    check_outputs(inputs, outputs);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
}

std::vector<std::pair<std::string, std::string>> session_inputs(const Session& s) {
  std::vector<std::pair<std::string, std::string>> in = {{"session", s.path},
                                                         {"plan", s.plan.path},
                                                         {"sensor profile", s.sensor_file},
                                                         {"truth", s.truth_file}};
  const LogFormat& log = s.log;
  if (log.split()) {
    in.emplace_back("accelerometer log", log.accel_file);
    in.emplace_back("gyro log", log.gyro_file);
  } else if (!log.segments.empty()) {
    for (const auto& seg : log.segments) in.emplace_back("log", seg.file);
  } else {
    in.emplace_back("log", log.file);
  }
  return in;
}

std::string six_face_where(const Session& session) {
  return session.log.file + " (session " + session.path + "): ";
}

std::string fmt(const char* format, double v) {
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

std::atomic<bool> g_stop{false};
std::string g_command_line;
namespace {
extern "C" void on_stop_signal(int) { g_stop.store(true); }
}  // namespace

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a read blocked on standard input returns
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

namespace {
// "the argument for option '--method' must be closed-form | kf, not 'x'" (the value shown
// without control characters, never through Boost's placeholder substitution).
po::error_with_option_name invalid(const std::string& value, const std::string& accepted) {
  std::string shown;
  for (char c : value.substr(0, 80)) shown += static_cast<unsigned char>(c) < 0x20 ? '?' : c;
  return po::error_with_option_name("the argument for option '%canonical_option%' must be " +
                                    accepted + ", not '" + shown + "'");
}

template <class E>
void choose(boost::any& v, const std::vector<std::string>& values,
            const std::vector<std::pair<const char*, E>>& names) {
  po::validators::check_first_occurrence(v);
  const std::string& s = po::validators::get_single_string(values);
  std::string known;
  for (const auto& [name, value] : names) {
    if (s == name) {
      v = boost::any(value);
      return;
    }
    known += (known.empty() ? "" : " | ") + std::string(name);
  }
  throw invalid(s, known);
}
}  // namespace

void validate(boost::any& v, const std::vector<std::string>& values, Method*, int) {
  choose<Method>(v, values,
                 {{"closed-form", Method::ClosedForm},
                  {"kf", Method::Kf},
                  {"table-free", Method::TableFree},
                  {"six-face", Method::SixFace},
                  {"rate-table", Method::RateTable}});
}
void validate(boost::any& v, const std::vector<std::string>& values, OnBadSample*, int) {
  choose<OnBadSample>(v, values, {{"stop", OnBadSample::Stop}, {"skip", OnBadSample::Skip}});
}
void validate(boost::any& v, const std::vector<std::string>& values, Vertical*, int) {
  choose<Vertical>(v, values, {{"free", Vertical::Free}, {"held", Vertical::Held}});
}

std::string name_of(Method m) {
  return m == Method::Kf          ? "kf"
         : m == Method::TableFree ? "table-free"
         : m == Method::SixFace   ? "six-face"
         : m == Method::RateTable ? "rate-table"
                                  : "closed-form";
}
std::string name_of(Stage1Method m) { return m == Stage1Method::Point ? "point" : "fit"; }
std::string name_of(ErrorModelKind m) {
  return m == ErrorModelKind::Uncoupled ? "uncoupled" : "coupled";
}
std::string name_of(const ChannelSet& c) {
  std::string out;
  for (const auto& [on, name] :
       {std::pair{c.north, "north"}, std::pair{c.east, "east"}, std::pair{c.vertical, "vertical"},
        std::pair{c.heading, "heading"}})
    if (on) out += (out.empty() ? "" : ",") + std::string(name);
  return out;
}

void apply_table_free_settings(const TableFreeSettings& session, const po::variables_map& vm,
                               PoseDetectorOptions& detector, double* edge_trim) {
  auto on_line = [&](const char* name) { return vm.count(name) && !vm[name].defaulted(); };
  if (session.pose_window && !on_line("pose-window")) detector.window = *session.pose_window;
  if (session.min_pose && !on_line("min-pose")) detector.min_duration = *session.min_pose;
  if (session.pose_accel_only && !on_line("pose-accel-only"))
    detector.use_gyro = !*session.pose_accel_only;
  if (edge_trim && session.edge_trim && !on_line("edge-trim")) *edge_trim = *session.edge_trim;
}

}  // namespace sinscal::cli

namespace sinscal {

using cli::choose;
namespace po = boost::program_options;

void validate(boost::any& v, const std::vector<std::string>& values,
              CalibratorOptions::AttitudeUpdates*, int) {
  using A = CalibratorOptions::AttitudeUpdates;
  choose<A>(v, values, {{"every", A::Every}, {"first", A::First}, {"none", A::None}});
}
void validate(boost::any& v, const std::vector<std::string>& values, CalibratorOptions::StaticFrom*,
              int) {
  using S = CalibratorOptions::StaticFrom;
  choose<S>(v, values, {{"plan", S::Plan}, {"data", S::Data}});
}
void validate(boost::any& v, const std::vector<std::string>& values, Stage1Method*, int) {
  choose<Stage1Method>(v, values, {{"fit", Stage1Method::Fit}, {"point", Stage1Method::Point}});
}
void validate(boost::any& v, const std::vector<std::string>& values, ErrorModelKind*, int) {
  choose<ErrorModelKind>(
      v, values, {{"coupled", ErrorModelKind::Coupled}, {"uncoupled", ErrorModelKind::Uncoupled}});
}
void validate(boost::any& v, const std::vector<std::string>& values, ChannelSet*, int) {
  po::validators::check_first_occurrence(v);
  const std::string& list = po::validators::get_single_string(values);
  ChannelSet c{false, false, false, false};
  std::stringstream cs(list);
  for (std::string name; std::getline(cs, name, ',');) {
    bool* flag = name == "north"      ? &c.north
                 : name == "east"     ? &c.east
                 : name == "vertical" ? &c.vertical
                 : name == "heading"  ? &c.heading
                                      : nullptr;
    if (!flag) throw cli::invalid(name, "channels among north, east, vertical, heading");
    *flag = true;
  }
  if (!c.north || !c.east) throw cli::invalid(list, "a list with at least north,east");
  v = boost::any(c);
}

}  // namespace sinscal
