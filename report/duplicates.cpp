#include "report/duplicates.hpp"

#include <filesystem>
#include <map>
#include <stdexcept>

#include "report/sha256.hpp"

namespace sinscal {

namespace fs = std::filesystem;

namespace {

bool is_log(const std::string& role) {
  return role.size() >= 3 && role.compare(role.size() - 3, 3, "log") == 0;
}

struct File {
  std::size_t set = 0;
  std::string role, path;
  fs::path id;
  std::uintmax_t bytes = 0;
  bool exists = false;
};

fs::path resolved(const std::string& path) {
  std::error_code ec;
  const fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
  return ec ? fs::absolute(path).lexically_normal() : p;
}

// Why `a` and `b` are the same data, or empty.
std::string sameness(const File& a, const File& b, std::map<std::string, std::string>& hashes) {
  std::error_code ec;
  if (a.id == b.id || (a.exists && b.exists && fs::equivalent(a.path, b.path, ec)))
    return "the same file";
  if (!is_log(a.role) || !is_log(b.role) || !a.exists || !b.exists || a.bytes != b.bytes) return "";
  auto hash = [&](const File& f) -> const std::string& {
    auto it = hashes.find(f.id.string());
    if (it == hashes.end()) it = hashes.emplace(f.id.string(), sha256_file(f.path)).first;
    return it->second;
  };
  const std::string& h = hash(a);
  return h == hash(b) ? "the same bytes (SHA-256 " + h + ")" : "";
}

std::vector<File> compared_files(const std::vector<DataSet>& sets) {
  std::vector<File> files;
  for (std::size_t s = 0; s < sets.size(); ++s)
    for (const auto& [role, path] : sets[s].files) {
      if (path.empty() || path == "-" || path == "<stdin>") continue;
      if (role != "session" && !is_log(role)) continue;
      File f{s, role, path, resolved(path)};
      std::error_code ec;
      f.exists = fs::is_regular_file(path, ec);
      if (f.exists) f.bytes = fs::file_size(path, ec);
      files.push_back(f);
    }
  return files;
}

}  // namespace

void refuse_duplicate_data(const std::vector<DataSet>& sets) {
  const std::vector<File> files = compared_files(sets);
  std::map<std::string, std::string> hashes;
  for (std::size_t i = 0; i < files.size(); ++i)
    for (std::size_t j = i + 1; j < files.size(); ++j) {
      const File& a = files[i];
      const File& b = files[j];
      if (a.set == b.set || (a.role == "session") != (b.role == "session")) continue;
      const std::string why = sameness(a, b, hashes);
      if (why.empty()) continue;
      throw std::invalid_argument(sets[b.set].name + " and " + sets[a.set].name +
                                  " are the same data: their " + b.role + " " + b.path + " and " +
                                  a.role + " " + a.path + " are " + why +
                                  "; one data set given twice would be fitted as two "
                                  "independent ones");
    }
}

}  // namespace sinscal
