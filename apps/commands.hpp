// The sinscal commands, one file each.
#pragma once

#include <string>
#include <vector>

namespace sinscal::cli {

int cmd_simulate(const std::vector<std::string>& args);
int cmd_navigate(const std::vector<std::string>& args);
int cmd_calibrate(const std::vector<std::string>& args);
int cmd_compare(const std::vector<std::string>& args);
int cmd_plot_convergence(const std::vector<std::string>& args);
int cmd_diagnose(const std::vector<std::string>& args);
int cmd_allan(const std::vector<std::string>& args);
int cmd_design(const std::vector<std::string>& args);
int cmd_export(const std::vector<std::string>& args);
int cmd_thermal(const std::vector<std::string>& args);
int cmd_report(const std::vector<std::string>& args);

}  // namespace sinscal::cli
