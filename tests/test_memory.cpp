// Streaming in constant memory: the peak resident memory of `sinscal calibrate --method kf` on a
// log ten times longer stays within 10 % of the short log's. Measured on the real program, in a
// child process (peak RSS from wait4), streaming from standard input and reading the file.
// Not meaningful under AddressSanitizer (its quarantine grows with every allocation): left to
// the Release build (.ci/run).
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <catch2/catch.hpp>
#include <filesystem>

#include "helpers.hpp"
#include "rig/session.hpp"

extern char** environ;

using namespace sinscal;

namespace {

// Runs the program with standard input from `stdin_path` (empty: /dev/null) and its output
// discarded; returns {exit status, peak resident set in kB}.
std::pair<int, long> run_measured(const std::vector<std::string>& args,
                                  const std::string& stdin_path) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(
      &actions, 0, stdin_path.empty() ? "/dev/null" : stdin_path.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
  std::vector<char*> argv;
  for (const auto& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  REQUIRE(err == 0);
  int status = 0;
  rusage usage{};
  REQUIRE(wait4(pid, &status, 0, &usage) == pid);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, usage.ru_maxrss};
}

std::string session_with_length(const std::string& name, const std::string& plan_text) {
  const std::string dir = test::temp_dir(name);
  test::write_file(dir + "/rot19.ini", plan_text);
  SessionSimulation spec;
  spec.plan_path = dir + "/rot19.ini";
  spec.data_sensor_path = test::source_path("config/sensors/nav-fog-extended.ini");
  spec.seed = 7;
  return simulate_session(dir + "/session", spec).session_path;
}

}  // namespace

TEST_CASE("Kalman streaming peak memory: a 10x longer log within 10 % (peak memory)",
          "[long][kalman][memory]") {
  const Plan base = test::load_plan("rot19.ini");
  // rot19 lasts 70 + 18 (9 + 20) = 592 s; with a 700 s start and 281 s pauses, 5920 s.
  std::string text = base.text;
  auto replace = [&](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    text.replace(at, from.size(), to);
  };
  replace("dwell = 70 s", "dwell = 700 s");
  replace("pause = 20 s", "pause = 281 s");
  const std::string short_session = session_with_length("memory_short", base.text);
  const std::string long_session = session_with_length("memory_long", text);
  REQUIRE(Plan::parse("long", text).type == Plan::Type::Rotations);

  const std::string bin = SINSCAL_BINARY;
  for (const bool stream : {true, false}) {
    long peak[2] = {0, 0};
    int k = 0;
    for (const auto& session : {short_session, long_session}) {
      const std::string dir = std::filesystem::path(session).parent_path().string();
      std::vector<std::string> args = {bin,
                                       "calibrate",
                                       "--method",
                                       "kf",
                                       "--session",
                                       session,
                                       "--out",
                                       dir + "/r.json",
                                       "--monitor",
                                       dir + "/m.jsonl",
                                       "--monitor-interval",
                                       "10"};
      if (stream) args.push_back("--stream");
      const auto [status, kb] = run_measured(args, stream ? dir + "/imu.csv" : "");
      REQUIRE(status == 0);
      peak[k++] = kb;
    }
    CAPTURE(stream, peak[0], peak[1]);
    CHECK(static_cast<double>(peak[1]) <= 1.10 * static_cast<double>(peak[0]));
  }
  // The long log was really processed: its monitor has (at least) ten times the lines.
  const auto lines = [](const std::string& session) {
    std::ifstream in(std::filesystem::path(session).parent_path() / "m.jsonl");
    int n = 0;
    for (std::string l; std::getline(in, l);) ++n;
    return n;
  };
  CHECK(lines(long_session) >= 10 * lines(short_session));
  std::filesystem::remove_all(std::filesystem::path(long_session).parent_path());
}
