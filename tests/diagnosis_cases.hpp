// Hidden-effect cases of the table diagnosis, shared by its tests and its Monte Carlo matrix: a
// session simulated with effects its sensor profile lacks, diagnosed as `sinscal diagnose` does
// (closed form, then the dwells and the turns in one ranking), and the outcome scored strictly.
#pragma once

#include <algorithm>
#include <boost/math/distributions/binomial.hpp>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "filter/closed_form/closed_form.hpp"
#include "filter/diagnosis/diagnosis_table.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/diagnosis_report.hpp"
#include "rig/session.hpp"

namespace sinscal::test {

/// A profile line `key = ...` in `[section]`.
struct ProfileLine {
  std::string section, line;
  std::string key() const { return line.substr(0, line.find_first_of(" =")); }
};

/// `text` with every `key = ...` line of `[section]` removed.
inline std::string without_key(const std::string& text, const ProfileLine& p) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line, section;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] == '[') section = line.substr(1, line.find(']') - 1);
    const std::string key = line.substr(0, line.find_first_of(" ="));
    if (section == p.section && key == p.key()) continue;
    out << line << "\n";
  }
  return out.str();
}

/// `text` with `line` in `[section]` (the section appended when missing).
inline std::string with_line(std::string text, const ProfileLine& p) {
  text = without_key(text, p);
  const std::string header = "[" + p.section + "]\n";
  const auto at = text.find(header);
  if (at == std::string::npos) return text + "\n" + header + p.line + "\n";
  return text.insert(at + header.size(), p.line + "\n");
}

struct HiddenCase {
  Session session;
  ImuErrorModel truth;
  SensorProfile filter_profile;  // the session's profile: without the hidden effects
};

/// Simulates `plan` with the sensor profile `profile` plus `hidden` (their keys replaced), and
/// writes the session's profile without the hidden keys.
inline HiddenCase hidden_case(const std::string& name, const std::string& plan,
                              const std::string& profile, const std::vector<ProfileLine>& hidden,
                              std::uint64_t seed, double rate_hz) {
  const std::string dir = temp_dir(name);
  std::ifstream in(source_path("config/sensors/" + profile));
  std::stringstream text;
  text << in.rdbuf();
  std::string data = text.str(), filter = text.str();
  for (const auto& h : hidden) {
    data = with_line(data, h);
    filter = without_key(filter, h);
  }
  write_file(dir + "/data-sensor.ini", data);
  write_file(dir + "/filter-sensor.ini", filter);
  SessionSimulation spec;
  spec.plan_path = source_path("config/plans/" + plan);
  spec.data_sensor_path = dir + "/data-sensor.ini";
  spec.filter_sensor_path = dir + "/filter-sensor.ini";
  spec.name = name;
  spec.seed = seed;
  spec.rate_hz = rate_hz;
  const SimulatedSession sim = simulate_session(dir + "/session", spec);
  Session session = Session::load(sim.session_path);
  return {session, sim.truth, SensorProfile::load(session.sensor_file)};
}

struct DiagnosisOutcome {
  TableDiagnosis result;
  TableFinding first;
  std::string story;                     // every finding's title, in order
  bool first_right = false;              // a hidden family (or an ambiguous set holding one) first
  bool ambiguous_first = false;          // ... as an ambiguous set
  bool all_named = false;                // every hidden family in some finding (or its set)
  std::vector<std::string> false_names;  // findings whose set holds no hidden family
  int magnitudes_checked = 0;            // determined coefficients of hidden families named
  double worst_sigma = 0.0;              // their largest |estimate - truth| / sigma
};

/// The families of a finding: its own and its ambiguous set's.
inline std::vector<std::string> finding_set(const TableFinding& f) {
  std::vector<std::string> set = {f.family};
  set.insert(set.end(), f.ambiguous_with.begin(), f.ambiguous_with.end());
  return set;
}

/// The case's turn model and its closed-form calibration, as `sinscal diagnose` makes them (the
/// turns' filter unless `turns` is false).
struct CaseCalibration {
  TurnModel model;
  ClosedFormReport calibration;
};

inline CaseCalibration calibrate_case(const HiddenCase& c, bool turns = true) {
  const Stage1Options s1 = default_stage1(&c.filter_profile);
  const TableAttitudeError table{kDefaultTableAttitudeSigma};
  CaseCalibration out{turn_model_of(c.session, c.filter_profile, table.sigma), {}};
  out.model.run_filter = turns;
  const auto about = linearize(out.model, 0);
  out.calibration = run_closed_form(c.session, s1, table, !about, about ? &*about : nullptr);
  return out;
}

/// Diagnoses the case as `sinscal diagnose` does (the turns' test unless `turns` is false) and
/// scores it against the hidden families.
inline DiagnosisOutcome diagnose_hidden(const HiddenCase& c, const std::vector<std::string>& hidden,
                                        const std::vector<std::string>& prefer = {},
                                        bool turns = true) {
  CaseCalibration cc = calibrate_case(c, turns);
  const ClosedFormReport& calibration = cc.calibration;
  TableDiagnosisOptions o;
  o.dwells.prefer = prefer;
  DiagnosisOutcome out;
  out.result =
      diagnose_table(calibration.stage1, c.session.site, calibration.stage2_options, o, &cc.model);
  const auto is_hidden = [&](const std::string& f) {
    return std::find(hidden.begin(), hidden.end(), f) != hidden.end();
  };
  std::vector<std::string> named;
  ImuErrorModel truth = c.truth;
  const auto refs = truth.coefficient_refs();
  for (const auto& f : out.result.findings) {
    out.story +=
        (out.story.empty() ? "" : "; ") + finding_title(f) + " [" + finding_summary(f) + "]";
    const auto set = finding_set(f);
    named.insert(named.end(), set.begin(), set.end());
    if (std::none_of(set.begin(), set.end(), is_hidden)) out.false_names.push_back(f.family);
    if (!is_hidden(f.family)) continue;
    for (const auto& k : f.coefficients) {
      if (k.source.empty() || !(k.sigma > 0.0)) continue;
      ++out.magnitudes_checked;
      const double t = *refs[static_cast<std::size_t>(k.catalog)].second;
      out.worst_sigma = std::max(out.worst_sigma, std::abs(k.value - t) / k.sigma);
    }
    for (const auto& comb : f.combinations) {
      double t = 0.0;
      for (const auto& [k, w] : comb.weights) t += w * *refs[static_cast<std::size_t>(k)].second;
      ++out.magnitudes_checked;
      out.worst_sigma = std::max(out.worst_sigma, std::abs(comb.value - t) / comb.sigma);
    }
  }
  if (out.story.empty()) out.story = "nothing named";
  if (!out.result.findings.empty()) {
    out.first = out.result.findings.front();
    const auto set = finding_set(out.first);
    out.first_right = std::any_of(set.begin(), set.end(), is_hidden);
    out.ambiguous_first = !out.first.ambiguous_with.empty();
  }
  out.all_named = std::all_of(hidden.begin(), hidden.end(), [&](const std::string& h) {
    return std::find(named.begin(), named.end(), h) != named.end();
  });
  return out;
}

/// The most seeds of `n` a cell may miss in a short (CI) run when its true rate is the
/// acceptance's `rate` (issue 33: 95 %): the smallest k with P(misses > k) <= alpha under
/// binomial(n, 1 - rate). A cell at the acceptance rate fails such a run at most alpha of the time;
/// one far below it (a broken diagnosis) fails it.
inline int allowed_misses(int n, double rate = 0.95, double alpha = 0.01) {
  const boost::math::binomial misses(n, 1.0 - rate);
  for (int k = 0; k < n; ++k)
    if (boost::math::cdf(boost::math::complement(misses, k)) <= alpha) return k;
  return n;
}

}  // namespace sinscal::test
