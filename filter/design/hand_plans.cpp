#include "filter/design/hand_plans.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

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
  std::snprintf(buf, sizeof buf, "%.3f", s);
  return buf;
}

// The plan's text with its dwells times `factor` (at least `min_dwell`).
std::string scaled_text(const Plan& plan, double factor, double min_dwell,
                        const std::string& name) {
  auto dwell = [&](double d) { return seconds(std::max(min_dwell, factor * d)); };
  std::istringstream in(plan.text);
  std::ostringstream out;
  out << "# " << name << ": " << plan.name
      << " with its dwells scaled by sinscal design --optimize (moves and turns unchanged).\n";
  std::string line, section;
  std::size_t orientation = 0;
  while (std::getline(in, line)) {
    const std::string t = trimmed(line);
    if (!t.empty() && t.front() == '[') {
      section = t;
      if (section.rfind("[orientation.", 0) == 0) ++orientation;
      out << line << '\n';
      if (section == "[rotations]") {
        out << "pauses =";
        for (const auto& step : plan.steps) out << ' ' << dwell(step.pause);
        out << " s\n";
      }
      continue;
    }
    const std::string key = key_of(t);
    if (section == "[plan]" && key == "name")
      out << "name = " << name << '\n';
    else if (section == "[start]" && key == "dwell")
      out << "dwell = " << dwell(plan.start_dwell) << " s\n";
    else if (section.rfind("[orientation.", 0) == 0 && key == "dwell")
      out << "dwell = " << dwell(plan.orientations[orientation - 1].dwell) << " s\n";
    else if (section == "[rotations]" && (key == "pause" || key == "pauses"))
      continue;
    else
      out << line << '\n';
  }
  return out.str();
}

double duration_of(const Plan& p) { return build_motion(p, p.site).duration(); }

}  // namespace

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
