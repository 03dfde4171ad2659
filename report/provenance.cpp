#include "report/provenance.hpp"

#include <cctype>
#include <ctime>
#include <filesystem>

#include "report/sha256.hpp"

namespace sinscal {

std::string sinscal_version() { return SINSCAL_VERSION; }

std::string utc_timestamp() {
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return b;
}

std::string shell_command_line(const std::vector<std::string>& argv) {
  std::string out;
  for (const auto& a : argv) {
    bool plain = !a.empty();
    for (char c : a)
      plain &= std::isalnum(static_cast<unsigned char>(c)) != 0 ||
               std::string("-_./=:,+@%").find(c) != std::string::npos;
    if (!out.empty()) out += ' ';
    if (plain) {
      out += a;
      continue;
    }
    out += '\'';
    for (char c : a) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    out += '\'';
  }
  return out;
}

nlohmann::ordered_json provenance_section(const ProvenanceInput& in) {
  namespace fs = std::filesystem;
  nlohmann::ordered_json p;
  p["sinscal_version"] = sinscal_version();
  p["date_utc"] = utc_timestamp();
  p["command_line"] = in.command_line;
  std::error_code ec;
  p["working_directory"] = fs::current_path(ec).string();
  if (!in.session.empty()) {
    p["session"] = {{"file", in.session}, {"name", in.session_name}};
    if (!in.sensor_profile.empty())
      p["sensor_profile"] = {{"file", in.sensor_profile}, {"name", in.sensor_profile_name}};
  }
  nlohmann::ordered_json files = nlohmann::ordered_json::array();
  for (const auto& [role, path] : in.files) {
    if (path.empty()) continue;
    if (in.stdin_log && role.find("log") != std::string::npos) {
      files.push_back({{"role", role}, {"file", "<stdin>"}, {"sha256", nullptr}});
      continue;
    }
    if (!fs::exists(path, ec)) {  // e.g. a truth file the session names but does not have
      files.push_back({{"role", role}, {"file", path}, {"sha256", nullptr}});
      continue;
    }
    std::uintmax_t bytes = 0;
    const std::string hash = sha256_file(path, &bytes);
    files.push_back({{"role", role}, {"file", path}, {"bytes", bytes}, {"sha256", hash}});
  }
  p["inputs"] = files;
  if (!in.monitor.empty()) p["monitor"] = in.monitor;
  return p;
}

}  // namespace sinscal
