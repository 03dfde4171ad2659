#include "filter/design/hand_plans.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>

namespace sinscal {

namespace {

std::string trimmed(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r") - a + 1);
}

std::string key_of(const std::string& line) {
  const auto eq = line.find('=');
  return eq == std::string::npos ? "" : trimmed(line.substr(0, eq));
}

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", s);
  return buf;
}

// The plan's text with the dwells `d` (start dwell then pauses, or the orientations' dwells).
std::string dwells_text(const Plan& plan, const std::vector<double>& d, const std::string& name) {
  std::size_t next = plan.type == Plan::Type::Rotations ? 1 : 0;
  std::istringstream in(plan.text);
  std::ostringstream out;
  const std::string note = "# " + name + ": dwells set by sinscal design --optimize";
  if (plan.text.rfind(note, 0) != 0) out << note << " (moves and turns unchanged).\n";
  std::string line, section;
  while (std::getline(in, line)) {
    const std::string t = trimmed(line);
    if (!t.empty() && t.front() == '[') {
      section = t;
      out << line << '\n';
      if (section == "[rotations]") {
        out << "pauses =";
        for (std::size_t i = 1; i < d.size(); ++i) out << ' ' << seconds(d[i]);
        out << " s\n";
      }
      continue;
    }
    const std::string key = key_of(t);
    if (section == "[plan]" && key == "name")
      out << "name = " << name << '\n';
    else if (section == "[start]" && key == "dwell")
      out << "dwell = " << seconds(d[0]) << " s\n";
    else if (section.rfind("[orientation.", 0) == 0 && key == "dwell")
      out << "dwell = " << seconds(d[next++]) << " s\n";
    else if (section == "[rotations]" && (key == "pause" || key == "pauses"))
      continue;
    else
      out << line << '\n';
  }
  return out.str();
}

std::string scaled_text(const Plan& plan, double factor, double min_dwell,
                        const std::string& name) {
  std::vector<double> d = plan_dwells(plan);
  for (double& x : d) x = std::max(min_dwell, factor * x);
  return dwells_text(plan, d, name);
}

double duration_of(const Plan& p) { return build_motion(p, p.site).duration(); }

}  // namespace

std::vector<double> plan_dwells(const Plan& plan) {
  std::vector<double> d;
  if (plan.type == Plan::Type::Rotations) {
    d.push_back(plan.start_dwell);
    for (const auto& s : plan.steps) d.push_back(s.pause);
  } else {
    for (const auto& o : plan.orientations) d.push_back(o.dwell);
  }
  return d;
}

Plan with_dwells(const Plan& plan, const std::vector<double>& dwells) {
  if (dwells.size() != plan_dwells(plan).size())
    throw std::invalid_argument(plan.path + ": with_dwells: not one duration per dwell");
  return Plan::parse(plan.path, dwells_text(plan, dwells, plan.name));
}

Plan renamed(const Plan& plan, const std::string& name) {
  return Plan::parse(plan.path, dwells_text(plan, plan_dwells(plan), name));
}

std::vector<Plan> searched_plans_in(const std::string& dir) {
  std::vector<std::string> paths;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    if (e.is_regular_file() && name.rfind("searched-", 0) == 0 && e.path().extension() == ".ini")
      paths.push_back(e.path().string());
  }
  std::sort(paths.begin(), paths.end());
  std::vector<Plan> out;
  out.reserve(paths.size());
  for (const std::string& p : paths) out.push_back(Plan::load(p));
  return out;
}

std::optional<Plan> dwell_scaled(const Plan& plan, double duration, double min_dwell) {
  if (plan.text.find("repeat") != std::string::npos) return std::nullopt;
  for (const auto& s : plan.steps)
    if (!(s.pause > 0.0)) return std::nullopt;
  char suffix[64];
  std::snprintf(suffix, sizeof suffix, "-%.0fs", duration);
  const std::string name = plan.name + suffix;
  auto at = [&](double f) { return Plan::parse(plan.path, scaled_text(plan, f, min_dwell, name)); };
  double lo = 0.0, hi = 1.0;
  if (duration_of(at(lo)) > duration) return std::nullopt;
  while (duration_of(at(hi)) < duration) hi *= 2.0;
  while (hi - lo > 1e-6 * hi) {
    const double mid = 0.5 * (lo + hi);
    (duration_of(at(mid)) <= duration ? lo : hi) = mid;
  }
  return at(lo);
}

}  // namespace sinscal
