#include "report/design_output.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

double in_unit(const std::string& family, double si) {
  return si / coefficient_family_info(family).si_per_unit();
}

std::string fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, v);
  return buf;
}

}  // namespace

nlohmann::ordered_json design_json(const PlanPrediction& p, const DesignInputs& in) {
  nlohmann::ordered_json j;
  j["format"] = "sinscal design 1";
  j["plan"] = {{"file", in.plan}, {"name", in.plan_name}, {"duration_s", p.duration}};
  j["sensor"] = {{"file", in.sensor}, {"name", in.sensor_name}};
  j["table"] = {{"file", in.table},
                {"name", in.table_name},
                {"attitude_accuracy_arcsec", in.attitude_sigma / units::arcsec}};
  j["ideal_imu_rate_hz"] = in.rate_hz;
  j["misalignment_frame"] = misalignment_frame_name(p.run.misalignment_frame);
  j["states"] = p.run.states;
  j["meets_targets"] = p.meets_targets();
  const auto last = p.last_to_reach();
  j["targets_reached_at_s"] = last ? nlohmann::ordered_json(last->second) : nullptr;
  j["last_family_to_reach"] = last ? nlohmann::ordered_json(last->first) : nullptr;
  nlohmann::ordered_json fams = nlohmann::ordered_json::array();
  for (const auto& f : p.families) {
    const std::string unit = coefficient_family_info(f.family).unit();
    fams.push_back({{"family", f.family},
                    {"unit", unit},
                    {"target", f.target > 0.0 ? nlohmann::ordered_json(in_unit(f.family, f.target))
                                              : nlohmann::ordered_json(nullptr)},
                    {"predicted_sigma", in_unit(f.family, f.worst_sigma)},
                    {"worst_coefficient", f.worst},
                    {"meets_target", f.meets_target()},
                    {"reached_at_s", f.reached_at ? nlohmann::ordered_json(*f.reached_at)
                                                  : nlohmann::ordered_json(nullptr)},
                    {"observed", f.observed}});
  }
  j["families"] = fams;
  nlohmann::ordered_json coefs = nlohmann::ordered_json::array();
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    const CoefficientEstimate& e = p.run.estimates[i];
    if (e.status != CoefficientEstimate::Status::Estimated) continue;
    coefs.push_back({{"name", cat[i].name},
                     {"unit", cat[i].unit},
                     {"prior_sigma", e.prior_sigma / cat[i].si_per_unit},
                     {"predicted_sigma", e.sigma / cat[i].si_per_unit},
                     {"observed", e.observed()}});
  }
  j["coefficients"] = coefs;
  nlohmann::ordered_json dirs = nlohmann::ordered_json::array();
  for (const auto& d : p.run.unobservable_directions)
    dirs.push_back({{"combination", d.text()}, {"remaining_variance_ratio", d.remaining}});
  j["unobservable_combinations"] = dirs;
  j["cpu_s"] = in.cpu_seconds;
  return j;
}

std::string design_tables(const PlanPrediction& p, const DesignInputs& in) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line,
                "Predicted accuracy of plan %s (%.1f s) for %s on %s (%.2f arcsec per dwell), "
                "without data\n\n",
                in.plan_name.c_str(), p.duration, in.sensor_name.c_str(), in.table_name.c_str(),
                in.attitude_sigma / units::arcsec);
  out += line;
  // Predicted sigmas and targets compare in this frame (a target's own frame is the user's).
  out += "Misalignment frame: " + misalignment_frame_name(p.run.misalignment_frame) +
         (p.run.converted_to_triad_frame ? " (converted from the table frame)" : "") +
         ": sigmas and targets are compared in it\n\n";
  std::snprintf(line, sizeof line, "%-22s %-9s %12s %12s  %-24s %10s\n", "family", "unit", "target",
                "predicted", "(worst coefficient)", "reached at");
  out += line;
  for (const auto& f : p.families) {
    const std::string unit = coefficient_family_info(f.family).unit();
    const std::string target = f.target > 0.0 ? fmt("%.4g", in_unit(f.family, f.target)) : "-";
    std::string reached = f.target <= 0.0 ? "-"
                          : f.reached_at  ? fmt("%.0f s", *f.reached_at)
                                          : "not reached";
    if (!f.observed) reached += " (not observed)";
    std::snprintf(line, sizeof line, "%-22s %-9s %12s %12.4g  %-24s %10s\n", f.family.c_str(),
                  unit.c_str(), target.c_str(), in_unit(f.family, f.worst_sigma), f.worst.c_str(),
                  reached.c_str());
    out += line;
  }
  const auto last = p.last_to_reach();
  if (last)
    std::snprintf(line, sizeof line, "\nEvery target met at %.0f s of %.0f s (the last: %s).\n",
                  last->second, p.duration, last->first.c_str());
  else
    std::snprintf(line, sizeof line, "\nNot every target is met by this plan.\n");
  out += line;
  if (!p.run.unobservable_directions.empty()) {
    out += "Combinations the plan does not observe (prior-normalized):\n";
    for (const auto& d : p.run.unobservable_directions)
      out += "  " + d.text() + fmt("  (%.2f of the prior variance left)\n", d.remaining);
  }
  return out;
}

std::string advice_table(const std::vector<SeparationAdvice>& advice) {
  if (advice.empty()) return "";
  const bool turns = advice.front().kind == "turn";
  std::string out =
      turns ? "\nFamilies the plan does not observe, and the turn that separates each best:\n"
            : "\nFamilies the plan does not observe, and the orientation that separates each "
              "best:\n";
  for (const auto& a : advice) {
    const std::string unit = coefficient_family_info(a.family).unit();
    out += "  " + a.family + ": sigma " + fmt("%.4g", in_unit(a.family, a.sigma_before)) + " " +
           unit + " (prior " + fmt("%.4g", in_unit(a.family, a.prior)) + ")";
    if (a.turn.empty())
      out += turns ? "; no single turn about a body axis improves it\n"
                   : "; no added orientation improves it (static dwells cannot: it needs turns)\n";
    else
      out += "; append " + a.turn + ": " + fmt("%.4g", in_unit(a.family, a.sigma_after)) + " " +
             unit + (a.observed_after ? " (observed)" : " (still not observed)") + "\n";
  }
  return out;
}

nlohmann::ordered_json advice_json(const std::vector<SeparationAdvice>& advice) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const auto& a : advice) {
    const auto text =
        a.turn.empty() ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(a.turn);
    const bool turn = a.kind == "turn";
    list.push_back({{"family", a.family},
                    {"unit", coefficient_family_info(a.family).unit()},
                    {"predicted_sigma", in_unit(a.family, a.sigma_before)},
                    {"prior_sigma", in_unit(a.family, a.prior)},
                    {"append_kind", a.kind},
                    {"turn", turn ? text : nlohmann::ordered_json(nullptr)},
                    {"orientation", turn ? nlohmann::ordered_json(nullptr) : text},
                    {"predicted_sigma_with_turn", in_unit(a.family, a.sigma_after)},
                    {"observed_with_turn", a.observed_after}});
  }
  return list;
}

namespace {

const FamilyPrediction& family_of(const PlanPrediction& p, const std::string& family) {
  for (const auto& f : p.families)
    if (f.family == family) return f;
  throw std::logic_error("design: no prediction for " + family);
}

}  // namespace

std::string required_table(const std::vector<std::string>& required, const PlanPrediction& p,
                           const std::map<std::string, double>& targets) {
  std::string out = "\nRequired families (target: half the prior sigma, or the given target):\n";
  for (const auto& family : required) {
    const FamilyPrediction& f = family_of(p, family);
    char line[200];
    const std::string unit = coefficient_family_info(family).unit();
    std::snprintf(line, sizeof line, "  %-20s sigma %.4g %s, target %.4g %s: %s\n", family.c_str(),
                  in_unit(family, f.worst_sigma), unit.c_str(), in_unit(family, targets.at(family)),
                  unit.c_str(),
                  f.observed ? "determined" : "NOT determined (in a combination the plan misses)");
    out += line;
  }
  return out;
}

nlohmann::ordered_json required_json(const std::vector<std::string>& required,
                                     const PlanPrediction& p,
                                     const std::map<std::string, double>& targets) {
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const auto& family : required) {
    const FamilyPrediction& f = family_of(p, family);
    list.push_back({{"family", family},
                    {"unit", coefficient_family_info(family).unit()},
                    {"target", in_unit(family, targets.at(family))},
                    {"predicted_sigma", in_unit(family, f.worst_sigma)},
                    {"observed", f.observed}});
  }
  return list;
}

std::string robustness_table(const std::vector<RobustnessRow>& rows, int seeds, double rate_hz) {
  if (rows.empty()) return "";
  std::string out =
      fmt("\nRobustness: RMS of error / predicted sigma per family over %.0f", seeds) +
      fmt(" simulated sessions at %.0f Hz (1: as predicted)\n", rate_hz);
  char cell[64];
  std::snprintf(cell, sizeof cell, "%-30s", "");
  out += cell;
  for (const auto& [family, r] : rows.front().rms_ratio) {
    std::string shortname = family;
    for (const char* prefix : {"gyro.", "accel."})
      if (shortname.rfind(prefix, 0) == 0)
        shortname = (prefix[0] == 'g' ? "g." : "a.") + shortname.substr(std::string(prefix).size());
    std::snprintf(cell, sizeof cell, " %11.11s", shortname.c_str());
    out += cell;
  }
  out += "\n";
  for (const auto& row : rows) {
    std::snprintf(cell, sizeof cell, "%-30.30s", row.perturbation.c_str());
    out += cell;
    for (const auto& [family, r] : rows.front().rms_ratio) {
      const auto it = row.rms_ratio.find(family);
      std::snprintf(cell, sizeof cell, " %11.2f", it == row.rms_ratio.end() ? 0.0 : it->second);
      out += cell;
    }
    out += "\n";
  }
  return out;
}

nlohmann::ordered_json robustness_json(const std::vector<RobustnessRow>& rows, int seeds,
                                       double rate_hz) {
  nlohmann::ordered_json j = {{"seeds", seeds}, {"rate_hz", rate_hz}};
  nlohmann::ordered_json list = nlohmann::ordered_json::array();
  for (const auto& row : rows) {
    nlohmann::ordered_json fams = nlohmann::ordered_json::object();
    for (const auto& [family, r] : row.rms_ratio) fams[family] = r;
    list.push_back({{"perturbation", row.perturbation},
                    {"rms_error_over_sigma", fams},
                    {"worst_family", row.worst_family},
                    {"worst", row.worst}});
  }
  j["runs"] = list;
  return j;
}

}  // namespace sinscal
