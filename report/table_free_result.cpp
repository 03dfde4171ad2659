#include "report/table_free_result.hpp"

#include <cmath>

#include "models/units.hpp"

namespace sinscal {

namespace {

nlohmann::ordered_json vec(const Eigen::Vector3d& v, double per_unit = 1.0) {
  return nlohmann::ordered_json::array({v(0) / per_unit, v(1) / per_unit, v(2) / per_unit});
}

nlohmann::ordered_json fit_part_json(const TableFreeFitPart& f) {
  return {{"chi2", f.chi2},
          {"residuals", f.residuals},
          {"dof", f.dof},
          {"chi2_per_dof", f.chi2_per_dof()},
          {"sigma_scale", f.sigma_scale},
          {"wander", f.wander}};
}

nlohmann::ordered_json stage(const TableFreeStage& s) {
  return {{"iterations", s.iterations},
          {"converged", s.converged},
          {"chi2", s.chi2},
          {"residuals", s.residuals},
          {"parameters", s.parameters}};
}

const char* kAxis[3] = {"x", "y", "z"};

}  // namespace

ResultCoefficients result_coefficients(const TableFreeRun& run) {
  ResultCoefficients out;
  for (const auto& c : run.result.coefficients) {
    const CoefficientInfo& info = coefficient_info(c.name);
    ResultCoefficient r =
        c.fixed_by_convention ? ResultCoefficient{} : result_coefficient(info, c.value, c.sigma);
    r.unit = info.unit;
    r.fixed_by_convention = c.fixed_by_convention;
    out[c.name] = r;
  }
  return out;
}

std::vector<RawEntry> raw_entries(const TableFreeRun& run) {
  std::vector<RawEntry> out;
  if (!run.result.has_raw) return out;
  auto triad = [&](const std::string& name, bool counts, const RawTriadView& v,
                   const Eigen::Vector3d& s0, const Eigen::Vector3d& o0,
                   const std::array<int, 3>& log_axis, const std::string& si_unit) {
    if (!counts) return;
    // By the sensors' own axes: body axis i is log axis log_axis[i] (a sign in the log's axis
    // map makes the body sensitivity negative; the sensor's own is its magnitude).
    std::array<int, 3> body{0, 1, 2};
    for (int i = 0; i < 3; ++i) body[static_cast<std::size_t>(log_axis[i])] = i;
    for (int a = 0; a < 3; ++a) {
      const int i = body[static_cast<std::size_t>(a)];
      out.push_back({name + ".sensitivity." + kAxis[a], std::abs(v.sensitivity(i)),
                     v.sensitivity_sigma(i), std::abs(s0(i)), "counts/(" + si_unit + ")", true});
    }
    for (int a = 0; a < 3; ++a) {
      const int i = body[static_cast<std::size_t>(a)];
      out.push_back(
          {name + ".offset." + kAxis[a], v.offset(i), v.offset_sigma(i), o0(i), "counts", true});
    }
    for (int a = 0; a < 3; ++a) {
      const int i = body[static_cast<std::size_t>(a)];
      out.push_back({name + ".row_norm." + kAxis[a], v.row_norm(i), 0.0, std::abs(s0(i)),
                     "counts/(" + si_unit + ")", false});
    }
  };
  triad("accel", run.accel_counts, run.result.accel_raw, run.nominal.accel_sensitivity,
        run.nominal.accel_offset, run.accel_log_axis, "m/s^2");
  triad("gyro", run.gyro_counts, run.result.gyro_raw, run.nominal.gyro_sensitivity,
        run.nominal.gyro_offset, run.gyro_log_axis, "rad/s");
  return out;
}

nlohmann::ordered_json result_sections(const TableFreeRun& run) {
  const TableFreeResult& r = run.result;
  nlohmann::ordered_json d;
  nlohmann::ordered_json fixed = nlohmann::ordered_json::array();
  for (const auto& c : r.coefficients)
    if (c.fixed_by_convention) fixed.push_back(c.name);
  nlohmann::ordered_json m = {
      {"name", "table-free"},
      {"body_frame", "accelerometer triad"},
      {"fixed_by_convention", fixed},
      {"solver",
       "Ceres (Levenberg-Marquardt); the noise model completed per part from its residuals, "
       "re-estimated until it settles: the static poses' means with a bias wander per triad "
       "(fit_parts wander, SI), the turns by a variance factor (sigma_scale^2); the covariance "
       "is the completed model's, the parts' chi2 against the white noise alone"},
      {"converged", r.converged},
      {"step_over_sigma", r.step_over_sigma},
      {"variance_rounds", r.variance_rounds},
      {"variance_settled", r.variance_settled},
      {"termination", r.termination},
      {"iterations", r.iterations},
      {"chi2", r.chi2},
      {"dof", r.dof},
      {"chi2_per_dof", r.chi2_per_dof},
      {"fit_parts",
       {{"accel_poses", fit_part_json(r.accel_fit)},
        {"gyro_poses", fit_part_json(r.gyro_rest_fit)},
        {"turns", fit_part_json(r.turn_fit)}}},
      {"gravity", {{"value", r.gravity}, {"unit", "m/s^2"}, {"from", run.gravity_from}}}};
  if (run.has_site)
    m["site"] = {{"latitude_deg", run.site.lat_rad / units::deg},
                 {"longitude_deg", run.site.lon_rad / units::deg},
                 {"height_m", run.site.h_m}};
  m["earth_rate"] = run.has_site ? "vertical part modelled, horizontal part as noise"
                                 : "as noise of unknown direction (no site)";
  m["starting_values"] = run.result.has_raw ? "the log's nominal conversion of its raw counts"
                                            : "zero (the log's readings as they are)";
  m["edge_trim_s"] = run.options.edge_trim;
  m["min_pose_s"] = run.options.min_pose;
  m["min_poses"] = run.options.min_poses;
  m["stages"] = {{"accelerometers", stage(r.accel_stage)},
                 {"gyros", stage(r.gyro_stage)},
                 {"joint", stage(r.joint_stage)}};
  d["method"] = m;
  d["data"] = {{"log", run.log}, {"samples", run.samples}, {"duration_s", run.duration}};

  // The detector's noise is in its readings' units (counts for raw logs).
  const Eigen::Vector3d sa = run.nominal.accel_sensitivity.cwiseAbs();
  const Eigen::Vector3d sg = run.nominal.gyro_sensitivity.cwiseAbs();
  const PoseDetection& det = run.detection;
  d["pose_detection"] = {
      {"window_s", run.detector.window},
      {"min_duration_s", run.detector.min_duration},
      {"gyro", run.detector.use_gyro},
      {"poses_found", det.poses.size()},
      {"threshold", det.threshold},
      {"noise",
       {{"accel_m_per_s2", vec(det.accel_noise_variance.cwiseSqrt().cwiseQuotient(sa))},
        {"gyro_deg_per_s",
         vec(det.gyro_noise_variance.cwiseSqrt().cwiseQuotient(sg), units::deg_per_s)}}}};

  nlohmann::ordered_json poses = nlohmann::ordered_json::array();
  for (const auto& h : run.poses) {
    const Pose& p = h.pose;
    nlohmann::ordered_json e = {{"pose", p.index},
                                {"t_start", p.t_start},
                                {"t_end", p.t_end},
                                {"duration_s", p.duration()},
                                {"readings", p.count},
                                {"specific_force_m_per_s2", vec(h.accel_mean)},
                                {"rate_deg_per_s", vec(h.gyro_mean, units::deg_per_s)},
                                {"accel_std_m_per_s2", vec(h.accel_std)},
                                {"gyro_std_deg_per_s", vec(h.gyro_std, units::deg_per_s)}};
    for (const auto& f : r.poses)
      if (f.index == p.index)
        e["fit"] = {{"t_start", f.t_start},
                    {"t_end", f.t_end},
                    {"readings", f.count},
                    {"gravity_error_m_per_s2", f.gravity_error},
                    {"accel_rms_m_per_s2", f.accel_rms},
                    {"gyro_rms_deg_per_s", f.gyro_rms / units::deg_per_s},
                    {"turn_error_deg", f.turn_error / units::deg}};
    poses.push_back(e);
  }
  d["poses"] = poses;
  d["noise"] = {{"accel_m_per_s2", vec(r.accel_noise)},
                {"gyro_deg_per_s", vec(r.gyro_noise, units::deg_per_s)}};

  const auto raw = raw_entries(run);
  if (!raw.empty()) {
    nlohmann::ordered_json v = nlohmann::ordered_json::object();
    for (const auto& e : raw) {
      nlohmann::ordered_json x = {{"value", e.value}};
      if (e.has_sigma) x["sigma"] = e.sigma;
      x["unit"] = e.unit;
      x["nominal"] = e.nominal;
      v[e.name] = x;
    }
    d["raw"] = v;
  }

  if (!run.validations.empty()) {
    nlohmann::ordered_json vs = nlohmann::ordered_json::array();
    for (const auto& v : run.validations) {
      auto pair = [](double nominal, double calibrated, double per_unit) {
        return nlohmann::ordered_json{{"nominal", nominal / per_unit},
                                      {"calibrated", calibrated / per_unit}};
      };
      nlohmann::ordered_json per_pose = nlohmann::ordered_json::array();
      for (const auto& p : v.poses)
        per_pose.push_back(
            {{"pose", p.index},
             {"t_start", p.t_start},
             {"t_end", p.t_end},
             {"gravity_error_m_per_s2",
              pair(p.gravity_error_nominal, p.gravity_error_calibrated, 1.0)},
             {"rate_deg_per_s", pair(p.rate_nominal, p.rate_calibrated, units::deg_per_s)}});
      nlohmann::ordered_json per_turn = nlohmann::ordered_json::array();
      for (const auto& t : v.turns)
        per_turn.push_back({{"from_pose", t.from},
                            {"angle_deg", t.angle / units::deg},
                            {"error_deg", pair(t.error_nominal, t.error_calibrated, units::deg)}});
      vs.push_back(
          {{"session", v.session},
           {"name", v.name},
           {"samples", v.samples},
           {"duration_s", v.duration},
           {"poses", v.poses.size()},
           {"turns", v.turns.size()},
           {"gravity_error_rms_m_per_s2",
            pair(v.gravity_rms_nominal, v.gravity_rms_calibrated, 1.0)},
           {"rate_at_rest_rms_deg_per_s",
            pair(v.rate_rms_nominal, v.rate_rms_calibrated, units::deg_per_s)},
           {"turn_error_rms_deg", pair(v.turn_rms_nominal, v.turn_rms_calibrated, units::deg)},
           {"per_pose", per_pose},
           {"per_turn", per_turn}});
    }
    d["validation"] = vs;
  }
  return d;
}

}  // namespace sinscal
