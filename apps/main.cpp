// sinscal command-line tool: the command dispatch and the exit codes of errors. Each command
// parses its options, calls the library and prints (apps/cmd_*.cpp); no algorithm lives here.
#include <iostream>
#include <string>
#include <vector>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "report/provenance.hpp"

namespace {
const char* kUsage =
    "sinscal: calibration of strapdown inertial navigation systems\n"
    "Usage: sinscal COMMAND [options]   (sinscal COMMAND --help for the options)\n"
    "Commands:\n"
    "  simulate   simulate a calibration session on a two-axis table\n"
    "  navigate   navigate through the static dwells of a session, report navigation errors\n"
    "  calibrate  estimate the calibration coefficients of a session or a batch of sessions\n"
    "             (closed-form method, Kalman filter, or table-free for hand-held sessions)\n"
    "  compare    two results side by side, difference over its sigma\n"
    "  export     a result as the compensation a firmware applies (JSON, YAML, C header)\n"
    "  plot-convergence\n"
    "             estimates and sigmas over time from a Kalman monitor file, to PNG (gnuplot)\n"
    "  diagnose   what the calibrated model misses on a table session: the effect, its\n"
    "             magnitude and the gain of adding it (model discovery)\n"
    "  allan      Allan deviation of a static record or pose, fitted noise terms, plot\n"
    "  design     the accuracy a plan will give, predicted without data (table, targets)\n"
    "  thermal    thermal calibration from a chamber's soaks: coefficients against temperature\n"
    "  report     the calibration certificate of a result: one HTML page (and PDF)\n";
}  // namespace

int main(int argc, char** argv) {
  using namespace sinscal::cli;
  if (argc < 2 || std::string(argv[1]) == "--help" || std::string(argv[1]) == "-h") {
    std::cout << kUsage;
    return argc < 2 ? kUsageError : 0;
  }
  const std::string command = argv[1];
  const std::vector<std::string> args(argv + 2, argv + argc);
  g_command_line = sinscal::shell_command_line(std::vector<std::string>(argv, argv + argc));
  try {
    if (command == "simulate") return cmd_simulate(args);
    if (command == "navigate") return cmd_navigate(args);
    if (command == "calibrate") return cmd_calibrate(args);
    if (command == "compare") return cmd_compare(args);
    if (command == "export") return cmd_export(args);
    if (command == "plot-convergence") return cmd_plot_convergence(args);
    if (command == "diagnose") return cmd_diagnose(args);
    if (command == "allan") return cmd_allan(args);
    if (command == "design") return cmd_design(args);
    if (command == "thermal") return cmd_thermal(args);
    if (command == "report") return cmd_report(args);
    std::cerr << "sinscal: unknown command '" << command << "'\n" << kUsage;
    return kUsageError;
  } catch (const po::error& e) {
    std::cerr << "sinscal " << command << ": " << e.what() << " (see sinscal " << command
              << " --help)\n";
    return kUsageError;
  } catch (const UsageError& e) {
    std::cerr << "sinscal " << command << ": " << e.what() << "\n";
    return kUsageError;
  } catch (const std::exception& e) {
    std::cerr << "sinscal " << command << ": error: " << e.what() << "\n";
    return kDataError;
  }
}
