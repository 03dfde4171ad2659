#include "report/six_face_result.hpp"

#include <cmath>
#include <cstdio>

#include "models/units.hpp"

namespace sinscal {

namespace {

const CoefficientInfo& info_of(const std::string& name) {
  for (const auto& c : coefficient_catalog())
    if (c.name == name) return c;
  throw std::logic_error("six-face result: no coefficient " + name);
}

// Counts per SI unit along each sensor's own axis (the row norm of I + diag(k) + M over the
// nominal scale) and the offset in counts, for a triad logged in counts with identity axes.
nlohmann::ordered_json raw_view(const TriadErrors& t, const TriadColumns& c, const char* unit) {
  const bool identity =
      c.axis == std::array<int, 3>{0, 1, 2} && c.sign == std::array<double, 3>{1.0, 1.0, 1.0};
  if (!c.counts || !identity) return nullptr;
  const Eigen::Matrix3d A = t.linear();
  nlohmann::ordered_json j;
  for (int i = 0; i < 3; ++i) {
    const std::string axis(1, static_cast<char>('x' + i));
    j["sensitivity." + axis] = A.row(i).norm() / c.scale;
    j["offset." + axis] = c.offset + t.bias(i) / c.scale;
  }
  j["unit"] = std::string("counts per ") + unit + "; counts";
  return j;
}

}  // namespace

ResultCoefficients result_coefficients(const SixFaceResult& r) {
  ResultCoefficients out;
  for (const auto& c : r.coefficients) {
    out[c.name] = result_coefficient(info_of(c.name), c.value, c.sigma);
  }
  return out;
}

nlohmann::ordered_json result_sections(const SixFaceResult& r, const SixFaceOptions& o,
                                       const LogFormat& log) {
  nlohmann::ordered_json faces = nlohmann::ordered_json::array(),
                         turns = nlohmann::ordered_json::array();
  for (const auto& f : r.faces)
    faces.push_back(
        {{"label", f.label},
         {"duration_s", f.duration},
         {"tilt_deg", {f.tilt(0) / units::deg, f.tilt(1) / units::deg}},
         {"tilt_sigma_deg", {f.tilt_sigma(0) / units::deg, f.tilt_sigma(1) / units::deg}},
         {"gravity_error_mps2", f.gravity_error}});
  for (const auto& t : r.turns)
    turns.push_back({{"label", t.label},
                     {"duration_s", t.duration},
                     {"angle_deg", t.angle / units::deg},
                     {"axis_body", {t.axis(0), t.axis(1), t.axis(2)}}});
  return {{"method",
           {{"name", "six-face"},
            {"frame", "the box's faces (every misalignment estimated)"},
            {"gravity_mps2", r.gravity},
            {"turn_angle_deg", o.declared.turn_angle / units::deg},
            {"turn_accuracy_deg", o.declared.turn_accuracy / units::deg},
            {"face_accuracy_deg", o.declared.face_accuracy / units::deg},
            {"earth_rate_not_modelled_deg_per_h", r.earth_rate_bound / units::deg * 3600.0},
            {"accel_chi2", r.accel_chi2},
            {"accel_dof", r.accel_dof}}},
          {"faces", faces},
          {"turns", turns},
          {"not_determined", r.undetermined},
          {"raw_counts",
           {{"accel", raw_view(r.model.accel, log.accel, "m/s^2")},
            {"gyro", raw_view(r.model.gyro, log.gyro, "rad/s")}}}};
}

std::string six_face_table(const SixFaceResult& r, const ResultCoefficients& truth) {
  std::string out;
  char line[256];
  std::snprintf(line, sizeof line, "%-24s %14s %12s  %-8s%s\n", "coefficient", "value", "sigma",
                "unit", truth.empty() ? "" : "   error/sigma");
  out += line;
  const ResultCoefficients rc = result_coefficients(r);
  for (const auto& c : r.coefficients) {
    const ResultCoefficient& x = rc.at(c.name);
    std::snprintf(line, sizeof line, "%-24s %14.6g %12.4g  %-8s", c.name.c_str(), x.value, *x.sigma,
                  x.unit.c_str());
    out += line;
    const auto t = truth.find(c.name);
    if (t != truth.end()) {
      std::snprintf(line, sizeof line, " %8.2f", (x.value - t->second.value) / *x.sigma);
      out += line;
    }
    out += "\n";
  }
  out += "\nFaces (placement tilt estimated, deg):\n";
  for (const auto& f : r.faces) {
    std::snprintf(line, sizeof line, "  %-8s %6.2f s  tilt %7.3f %7.3f (sigma %.3f %.3f)\n",
                  f.label.c_str(), f.duration, f.tilt(0) / units::deg, f.tilt(1) / units::deg,
                  f.tilt_sigma(0) / units::deg, f.tilt_sigma(1) / units::deg);
    out += line;
  }
  out += "Turns (calibrated angle about the turn's axis):\n";
  for (const auto& t : r.turns) {
    std::snprintf(line, sizeof line, "  %-8s %6.2f s  %9.3f deg\n", t.label.c_str(), t.duration,
                  t.angle / units::deg);
    out += line;
  }
  out += "Not determined by six faces and three turns:\n";
  for (const auto& u : r.undetermined) out += "  - " + u + "\n";
  return out;
}

}  // namespace sinscal
