#include "report/result.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/output.hpp"

namespace sinscal {

ResultCoefficient result_coefficient(const CoefficientInfo& info, double value_si,
                                     double sigma_si) {
  ResultCoefficient c;
  c.value = value_si / info.si_per_unit;
  c.sigma = sigma_si / info.si_per_unit;
  c.unit = info.unit;
  return c;
}

ResultCoefficients result_coefficients(const std::vector<CoefficientEstimate>& est) {
  ResultCoefficients out;
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size() && i < est.size(); ++i) {
    if (est[i].status == CoefficientEstimate::Status::Off) continue;
    const bool fixed = est[i].status == CoefficientEstimate::Status::FixedByConvention;
    ResultCoefficient c =
        fixed ? ResultCoefficient{} : result_coefficient(cat[i], est[i].value, est[i].sigma);
    c.unit = cat[i].unit;
    c.fixed_by_convention = fixed;
    if (!fixed) c.observable = est[i].observed();
    out[cat[i].name] = c;
  }
  return out;
}

ResultCoefficients result_coefficients(const KalmanRun& run) {
  return result_coefficients(run.estimates);
}

ResultCoefficients result_coefficients(const Stage2Result& stage2) {
  ResultCoefficients out;
  const auto& cat = coefficient_catalog();
  for (std::size_t k = 0; k < stage2.parameters.size(); ++k) {
    const auto i = static_cast<std::size_t>(stage2.parameters[k]);
    const auto j = static_cast<Eigen::Index>(k);
    ResultCoefficient c;
    c.unit = cat[i].unit;
    c.observable = stage2.observable[k];
    if (c.observable) {
      c.value = stage2.theta(j) / cat[i].si_per_unit;
      c.sigma = std::sqrt(stage2.cov(j, j)) / cat[i].si_per_unit;
    }
    out[cat[i].name] = c;
  }
  return out;
}

ResultCoefficients result_coefficients(const ClosedFormReport& r) {
  return result_coefficients(r.stage2);
}

namespace {
// A stage-2 solution relative to the table turned into the triad frame: the coefficients the
// conversion mixes with one the data did not determine are not determined either.
ResultCoefficients triad_frame_coefficients(const Stage2Result& s) {
  const auto& cat = coefficient_catalog();
  const auto n = static_cast<Eigen::Index>(s.parameters.size());
  Eigen::VectorXd values = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(cat.size()));
  Eigen::MatrixXd P = s.cov.topLeftCorner(n, n);
  std::vector<int> unknown;
  for (Eigen::Index k = 0; k < n; ++k) {
    const int c = s.parameters[static_cast<std::size_t>(k)];
    if (s.observable[static_cast<std::size_t>(k)]) {
      values(c) = s.theta(k);
      continue;
    }
    unknown.push_back(c);
    P.row(k).setZero();
    P.col(k).setZero();
  }
  const TriadFrameEstimate t = to_accel_triad_frame(values, P, s.parameters);
  const Eigen::MatrixXd& J = t.jacobian;
  ResultCoefficients out;
  for (std::size_t i = 0; i < t.catalog.size(); ++i) {
    const auto c = static_cast<std::size_t>(t.catalog[i]);
    const auto ii = static_cast<Eigen::Index>(i);
    ResultCoefficient rc = result_coefficient(cat[c], t.values(t.catalog[i]),
                                              std::sqrt(std::max(0.0, t.covariance(ii, ii))));
    for (int u : unknown)
      if (std::abs(J(t.catalog[i], u)) > 1e-12) rc.observable = false;
    out[cat[c].name] = rc;
  }
  for (int c : triad_fixed_coefficients()) {
    ResultCoefficient rc;
    rc.unit = cat[static_cast<std::size_t>(c)].unit;
    rc.fixed_by_convention = true;
    out[cat[static_cast<std::size_t>(c)].name] = rc;
  }
  return out;
}
}  // namespace

ResultCoefficients result_coefficients(const ClosedFormReport& r, MisalignmentFrame frame) {
  return frame == MisalignmentFrame::Triad ? triad_frame_coefficients(r.stage2)
                                           : result_coefficients(r.stage2);
}

namespace {
const char* attitude_name(CalibratorOptions::AttitudeUpdates a) {
  switch (a) {
    case CalibratorOptions::AttitudeUpdates::Every:
      return "every dwell";
    case CalibratorOptions::AttitudeUpdates::First:
      return "first dwell";
    case CalibratorOptions::AttitudeUpdates::None:
      break;
  }
  return "none";
}

nlohmann::ordered_json kalman_method(const KalmanRun& r) {
  const CalibratorOptions& o = r.options;
  nlohmann::ordered_json m = {
      {"name", "kf"},
      {"states", r.states},
      {"zero_velocity", o.zero_velocity},
      {"zero_velocity_in_motion", o.zero_velocity_in_motion},
      {"position", o.position},
      {"attitude", attitude_name(o.attitude)},
      {"base", o.base_attitude ? "estimated" : "known"},
      {"body_frame", r.accel_triad_frame ? "accelerometer triad" : "table"},
      {"static_from", r.detected ? "data" : "plan"},
      {"attitude_from", r.table_attitude_updates > 0 ? "table angles" : "plan"},
      {"update_interval_s", o.update_interval},
      {"prior_scale", o.prior_scale},
      {"table_sigma_arcsec", o.attitude_sigma / units::arcsec}};
  if (r.converted_to_triad_frame) m["body_frame_converted_from"] = "table";
  std::vector<std::string> fixed;
  for (int c : StateLayout::make(o.layout).fixed)
    fixed.push_back(coefficient_catalog()[static_cast<std::size_t>(c)].name);
  if (r.converted_to_triad_frame)
    for (int c : triad_fixed_coefficients())
      fixed.push_back(coefficient_catalog()[static_cast<std::size_t>(c)].name);
  if (!fixed.empty()) m["fixed_by_convention"] = fixed;
  if (!r.passes.empty()) m["passes"] = r.passes_requested;
  return m;
}

nlohmann::ordered_json angles_arcsec(const Eigen::Vector3d& v) {
  return {v.x() / units::arcsec, v.y() / units::arcsec, v.z() / units::arcsec};
}

// The table base and the IMU's mounting (docs/formats.md "installation").
nlohmann::ordered_json installation_section(const InstallationResult& in) {
  nlohmann::ordered_json j;
  nlohmann::ordered_json base = {{"estimated", in.base_estimated}};
  if (in.base_estimated) {
    base["level_north_arcsec"] = in.base_n.x() / units::arcsec;
    base["level_east_arcsec"] = in.base_n.y() / units::arcsec;
    base["heading_arcsec"] = in.base_n.z() / units::arcsec;
    base["sigma_arcsec"] = angles_arcsec(in.base_sigma_n);
  }
  if (in.base_known) base["known"] = true;  // --base known: the plan's, not estimated
  j["base"] = base;
  nlohmann::ordered_json mounting = {{"estimated", in.mounting_estimated}};
  if (in.mounting_estimated) {
    mounting["rotation_vector_arcsec"] = angles_arcsec(in.mounting_b);
    mounting["angle_deg"] = in.mounting_b.norm() / units::deg;
    mounting["sigma_arcsec"] = angles_arcsec(in.mounting_sigma_b);
    mounting["from"] = "polar decomposition of the accelerometer matrix";
  }
  j["mounting"] = mounting;
  if (in.alignment) {
    const Alignment& a = *in.alignment;
    nlohmann::ordered_json al = {
        {"valid", a.valid}, {"dwells", a.dwells}, {"applied", in.alignment_applied}};
    if (in.alignment_streamed) al["streamed"] = true;  // a stream's first dwells, held
    if (a.valid) {
      al["base_arcsec"] = angles_arcsec(a.base_n);
      al["base_sigma_arcsec"] = angles_arcsec(a.base_sigma_n);
      al["mounting_arcsec"] = angles_arcsec(a.mounting_b);
      al["mounting_sigma_arcsec"] = angles_arcsec(a.mounting_sigma_b);
    }
    j["alignment"] = al;
  }
  return j;
}

nlohmann::ordered_json kalman_convergence(const KalmanRun& r) {
  nlohmann::ordered_json conv = {{"targets", r.has_targets},
                                 {"converged", r.converged_at.has_value()}};
  if (r.converged_at) conv["converged_at_t"] = *r.converged_at;
  conv["above_target"] = r.above_target;
  conv["unobservable"] = r.unobservable;
  nlohmann::ordered_json dirs = nlohmann::ordered_json::array();
  for (const auto& d : r.unobservable_directions)
    dirs.push_back({{"direction", d.text()}, {"remaining_variance_ratio", d.remaining}});
  conv["unobservable_directions"] = dirs;
  return conv;
}
}  // namespace

nlohmann::ordered_json innovation_check_json(const InnovationCheck& c) {
  nlohmann::ordered_json channels = nlohmann::ordered_json::array();
  for (const auto& k : c.channels)
    channels.push_back({{"channel", k.channel},
                        {"updates", k.updates},
                        {"nis_per_dof", k.nis_per_dof},
                        {"nis_p", k.nis_p},
                        {"mean", k.mean},
                        {"ljung_box_q", k.ljung_box_q},
                        {"ljung_box_lags", k.lags},
                        {"ljung_box_p", k.ljung_box_p},
                        {"largest_autocorrelation", k.largest_autocorrelation},
                        {"largest_autocorrelation_lag", k.largest_lag},
                        {"sigma_bound", k.sigma_bound},
                        {"nis_holds", k.nis_holds},
                        {"white", k.white}});
  return {{"alpha", c.alpha},           {"tests", c.tests},     {"threshold", c.threshold},
          {"consistent", c.consistent}, {"verdict", c.verdict}, {"channels", channels}};
}

nlohmann::ordered_json result_sections(const KalmanRun& r) {
  nlohmann::ordered_json d;
  d["misalignment_frame"] = misalignment_frame_name(r.misalignment_frame);
  d["method"] = kalman_method(r);
  d["consistency"] = {{"nis_per_dof", r.nis_per_dof},
                      {"samples", r.samples},
                      {"innovations", innovation_check_json(r.innovations)}};
  d["convergence"] = kalman_convergence(r);
  d["installation"] = installation_section(r.installation);
  if (r.motion) {
    // The table's motion as the data show it against the plan's (docs/formats.md "motion").
    const DataMotion& m = *r.motion;
    nlohmann::ordered_json moves = nlohmann::ordered_json::array();
    for (const auto& v : m.moves)
      moves.push_back({{"move", v.move},
                       {"t_plan_s", v.t_plan},
                       {"follows_plan", v.follows},
                       {"largest_departure_deg", v.largest / units::deg},
                       {"mid_turn_shift_s", v.start_shift},
                       {"overshoot_deg", v.overshoot / units::deg},
                       {"data_begins_s", v.begins},
                       {"data_ends_s", v.ends},
                       {"gyro_turn_deg", v.turned / units::deg},
                       {"plan_turn_deg", v.plan_turned / units::deg}});
    d["motion"] = {{"summary", m.summary()},
                   {"session_time_offset_s", m.session_offset},
                   {"time_offset_s", m.time_offset},
                   {"offset_correlation", m.correlation},
                   {"follow_tolerance_deg", kFollowTolerance / units::deg},
                   {"departing_moves", m.departing()},
                   {"moves", moves}};
  }
  if (r.detected) {
    // Where the data were static against where the plan says: the log's timing, measured.
    nlohmann::ordered_json dwells = nlohmann::ordered_json::array();
    for (const auto& f : r.detected->intervals)
      dwells.push_back({{"dwell", f.dwell},
                        {"label", f.label},
                        {"t_start", f.t_start},
                        {"t_end", f.t_end},
                        {"plan_t_start", f.plan_t_start},
                        {"plan_t_end", f.plan_t_end}});
    d["static_from_data"] = {
        {"gyro_bound_deg_per_s", r.detected->gyro_bound / units::deg_per_s},
        {"accel_bound_ug", r.detected->accel_bound / units::ug},
        {"rate_threshold_deg_per_s", r.detected->rate_threshold / units::deg_per_s},
        {"window_s", r.options.detector.window},
        {"dwells", dwells}};
  }
  if (r.skipped > 0) d["skipped_samples"] = {{"count", r.skipped}, {"first", r.skipped_examples}};
  if (!r.diverged.empty()) d["diverged"] = {{"reason", r.diverged}, {"t", r.t_last}};
  if (!r.stopped.empty())
    d["stopped"] = {
        {"reason", r.stopped}, {"last_good_t", r.t_last}, {"interrupted", r.interrupted}};
  if (!r.passes.empty()) {
    nlohmann::ordered_json passes = nlohmann::ordered_json::array();
    for (const auto& p : r.passes) {
      nlohmann::ordered_json e = {{"pass", p.pass}, {"nis_per_dof", p.nis_per_dof}};
      if (p.largest_change_over_sigma)
        e["largest_change_over_sigma"] = *p.largest_change_over_sigma;
      e["linearization_share"] = p.linearization_share;
      passes.push_back(e);
    }
    d["passes"] = passes;
  }
  const PassLinearization& l = r.linearization;  // filter/kalman/pass_linearization.hpp
  d["linearization"] = {{"share", l.share},
                        {"coefficient", l.coefficient},
                        {"epsilon", l.epsilon},
                        {"epsilon_coefficient", l.epsilon_coefficient},
                        {"bound", kLinearizationShare}};
  return d;
}

namespace {
const char* kInputName[6] = {"df_n", "df_e", "df_d", "dw_n", "dw_e", "dw_d"};
}  // namespace

nlohmann::ordered_json result_sections(const ClosedFormReport& r, MisalignmentFrame frame) {
  const Stage1Options& s1 = r.stage1_options;
  nlohmann::ordered_json d;
  const bool triad = frame == MisalignmentFrame::Triad;
  d["misalignment_frame"] = misalignment_frame_name(triad ? frame : MisalignmentFrame::Table);
  d["method"] = {{"name", "closed-form"},
                 {"stage1", s1.method == Stage1Method::Fit ? "fit" : "point"},
                 {"model", s1.model == ErrorModelKind::Coupled ? "coupled" : "uncoupled"},
                 {"channels",
                  {{"north", s1.channels.north},
                   {"east", s1.channels.east},
                   {"vertical", s1.channels.vertical},
                   {"heading", s1.channels.heading}}},
                 {"arw_deg_per_sqrt_h", s1.arw / units::deg_per_sqrt_h},
                 {"vrw_ug_per_sqrt_hz", s1.vrw / units::ug_per_sqrt_hz},
                 {"table_sigma_arcsec", r.stage2_options.table.sigma / units::arcsec}};
  if (triad) {
    // Estimated relative to the table, converted after the estimation.
    d["method"]["body_frame"] = "accelerometer triad";
    d["method"]["body_frame_converted_from"] = "table";
    std::vector<std::string> fixed;
    for (int c : triad_fixed_coefficients())
      fixed.push_back(coefficient_catalog()[static_cast<std::size_t>(c)].name);
    d["method"]["fixed_by_convention"] = fixed;
  }
  nlohmann::ordered_json dwells = nlohmann::ordered_json::array();
  for (const auto& e : r.stage1) {
    nlohmann::ordered_json x = {
        {"dwell", e.dwell.index}, {"label", e.dwell.label}, {"duration_s", e.duration}};
    nlohmann::ordered_json inputs = nlohmann::ordered_json::object();
    for (int i = 0; i < 6; ++i) {
      if (!e.estimated[static_cast<std::size_t>(i)]) continue;
      const bool gyro = i >= 3;
      const double f = gyro ? units::deg_per_h : units::ug;
      inputs[kInputName[i]] = {{"value", e.u(i) / f},
                               {"sigma", std::sqrt(e.cov(i, i)) / f},
                               {"unit", gyro ? "deg/h" : "ug"}};
    }
    x["equivalent_inputs"] = inputs;
    if (s1.method == Stage1Method::Fit)
      x["residuals"] = {{"rms_velocity_m_per_s", e.rms_velocity},
                        {"rms_attitude_arcsec", e.rms_attitude / units::arcsec},
                        {"chi2_per_dof", e.chi2_per_dof}};
    dwells.push_back(x);
  }
  d["stage1"] = dwells;
  d["identifiability"] = {{"rank", r.stage2.rank},
                          {"parameters", r.stage2.parameters.size()},
                          {"unobservable_directions", r.stage2.unobservable_directions},
                          {"chi2_per_dof", r.stage2.chi2_per_dof},
                          {"dof", r.stage2.dof},
                          {"base_attitude_parameters", r.stage2.base_estimated ? 3 : 0}};
  d["installation"] = installation_section(r.installation);
  return d;
}

nlohmann::ordered_json coefficients_json(const ResultCoefficients& coefficients) {
  nlohmann::ordered_json c = nlohmann::ordered_json::object();
  for (const auto& info : coefficient_catalog()) {
    const auto it = coefficients.find(info.name);
    if (it == coefficients.end()) continue;
    nlohmann::ordered_json e = nlohmann::ordered_json::object();
    if (it->second.fixed_by_convention) {
      e["value"] = 0.0;
      e["fixed_by_convention"] = true;
    } else if (it->second.observable) {
      // A broken-down computation must never reach a result file as numbers (or nulls).
      if (!std::isfinite(it->second.value) ||
          (it->second.sigma && !std::isfinite(*it->second.sigma)))
        throw std::runtime_error("the estimate of " + info.name +
                                 " is not a finite number: the computation broke down (nothing "
                                 "written)");
      e["value"] = it->second.value;
      if (it->second.sigma) e["sigma"] = *it->second.sigma;
    } else {
      e["observable"] = false;
      if (it->second.sigma) e["sigma"] = *it->second.sigma;
    }
    e["unit"] = it->second.unit;
    c[info.name] = e;
  }
  return c;
}

void write_result_json(const std::string& path, const ResultCoefficients& coefficients,
                       const nlohmann::ordered_json& extra) {
  nlohmann::ordered_json j;
  j["coefficients"] = coefficients_json(coefficients);
  for (const auto& [key, value] : extra.items()) j[key] = value;
  write_atomically(path, [&](std::ostream& out) { out << j.dump(2) << "\n"; });
}

ResultCoefficients load_truth(const Session& session, bool accel_triad_frame,
                              const std::string& lever_arm_reference) {
  std::error_code ec;
  if (session.truth_file.empty() || !std::filesystem::exists(session.truth_file, ec)) return {};
  ResultCoefficients truth = read_result_json(session.truth_file);
  if (!accel_triad_frame && lever_arm_reference.empty()) return truth;
  ImuErrorModel m;
  for (const auto& [name, t] : truth) m.set(name, t.value);
  if (accel_triad_frame) m = in_accel_triad_frame(m);
  if (!lever_arm_reference.empty()) m = with_lever_arm_reference(m, lever_arm_reference[0] - 'x');
  for (const auto& [name, v] : m.coefficients()) truth[name].value = v;
  return truth;
}

std::optional<double> max_error_over_sigma(const ResultCoefficients& result,
                                           const ResultCoefficients& truth) {
  std::optional<double> worst;
  for (const auto& [name, c] : result) {
    const auto t = truth.find(name);
    if (t == truth.end() || !c.observable || c.fixed_by_convention || !c.sigma || !(*c.sigma > 0))
      continue;
    const double z = std::abs(c.value - t->second.value) / *c.sigma;
    if (!worst || z > *worst) worst = z;
  }
  return worst;
}

}  // namespace sinscal
