// The same data given twice (a chamber listing one soak twice, a batch naming one session by two
// paths, a copied log): found by the files' resolved paths (through links) and by the logs'
// SHA-256, so that one data set is never fitted as two independent ones.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace sinscal {

/// One data set: its name (as the user gave it) and its files (role, path). Roles ending in
/// "log" are the data; every other role (session, plan, sensor profile) is compared by path only
/// when it is "session" (soaks share a plan and a profile).
struct DataSet {
  std::string name;
  std::vector<std::pair<std::string, std::string>> files;
};

/// Throws std::invalid_argument naming both data sets and the file when two sets have the same
/// session file or a log in common: the same resolved file, or two files with the same bytes
/// (sizes compared first; SHA-256 only of logs of equal size).
void refuse_duplicate_data(const std::vector<DataSet>& sets);

}  // namespace sinscal
