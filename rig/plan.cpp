#include "rig/plan.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "models/config.hpp"
#include "models/units.hpp"

namespace sinscal {
namespace {

using Q = QuantityKind;

const double kMaxTurnAngle = 100.0 * 2.0 * M_PI;  // rad: a turn of at most 100 revolutions

std::string days(double seconds) {
  char b[40];
  std::snprintf(b, sizeof b, "%g", seconds / 86400.0);
  return b;
}

// N of a section [PREFIX.N]: digits only (no sign, no leading zero), 1 to 100,000,000. The
// message names the section's first key's line when it has keys.
int section_number(const IniFile& ini, const std::string& section, const std::string& prefix) {
  const std::string tail = section.substr(prefix.size());
  const bool digits =
      !tail.empty() && tail.size() <= 9 && tail[0] != '0' &&
      std::all_of(tail.begin(), tail.end(), [](char c) { return c >= '0' && c <= '9'; });
  const long n = digits ? std::stol(tail) : 0;  // at most 9 digits: no overflow
  if (!digits || n > 100000000) {
    std::string where = ini.path() + ": ";
    for (const auto& key : ini.keys())
      if (key.size() > section.size() && key.compare(0, section.size(), section) == 0 &&
          key[section.size()] == '.') {
        where = ini.path() + ":" + std::to_string(ini.line_of(key)) + ": ";
        break;
      }
    throw ConfigError(where + "section [" + section + "]: expected [" + prefix +
                      "N], N = 1, 2, ... (digits only, at most 100000000)");
  }
  return static_cast<int>(n);
}

// Plan angles: finite (the INI reader refuses NaN and inf) and within one turn either way.
double read_angle(const IniFile& ini, const std::string& key) {
  const double a = ini.get_quantity(key, Q::Angle, "deg");
  if (!(std::abs(a) <= 2.0 * M_PI))
    throw ConfigError(ini.where(key) + "must be within -360 and 360 deg");
  return a;
}

// heading (clockwise from North) or, in enu-rfu, yaw (counter-clockwise: heading = -yaw).
EulerAngles read_angles(const IniFile& ini, const std::string& s, AngleConvention convention) {
  EulerAngles e;
  const bool yaw = ini.has(s + ".yaw");
  if (yaw && convention != AngleConvention::EnuRfu)
    throw ConfigError(ini.where(s + ".yaw") +
                      "'yaw' is an angle of the enu-rfu convention; this plan's convention is " +
                      to_string(convention) + " (give 'heading')");
  if (yaw && ini.has(s + ".heading"))
    throw ConfigError(ini.where(s + ".yaw") +
                      "give either 'heading' (clockwise from North) or 'yaw' (counter-clockwise), "
                      "not both");
  if (yaw)
    e.heading = -read_angle(ini, s + ".yaw");
  else if (convention == AngleConvention::EnuRfu && !ini.has(s + ".heading"))
    throw ConfigError(ini.path() + ": [" + s +
                      "]: missing 'yaw' (counter-clockwise from North) or 'heading' (clockwise)");
  else
    e.heading = read_angle(ini, s + ".heading");
  e.pitch = read_angle(ini, s + ".pitch");
  e.roll = read_angle(ini, s + ".roll");
  return e;
}

// A static time (dwell, pause): finite, within the plan's duration limit; positive unless
// `zero_ok`.
double read_static_time(const IniFile& ini, const std::string& key, const PlanLimits& limits,
                        bool zero_ok) {
  const double t = ini.get_quantity(key, Q::Time, "s");
  if (zero_ok ? !(t >= 0.0) : !(t > 0.0))
    throw ConfigError(ini.where(key) + (zero_ok ? "must not be negative" : "must be positive"));
  if (!(t <= limits.max_duration))
    throw ConfigError(ini.where(key) + "longer than the plan limit of " +
                      days(limits.max_duration) + " days" + limits.hint());
  return t;
}

Eigen::Vector3d read_vector(const IniFile& ini, const std::string& key,
                            const Eigen::Vector3d& dflt) {
  if (!ini.has(key)) return dflt;
  std::istringstream in(ini.get_string(key));
  Eigen::Vector3d v;
  if (!(in >> v.x() >> v.y() >> v.z()) || v.norm() < 1e-9)
    throw ConfigError(ini.where(key) + "expected three numbers forming a non-zero vector");
  return v.normalized();
}

RotationStep parse_axis(const IniFile& ini, const std::string& key, const std::string& text) {
  RotationStep st;
  st.axis_name = text;
  const std::string name = text.size() < 2 ? std::string() : text.substr(1);
  const bool body = name == "x" || name == "y" || name == "z";
  const bool table = name == "outer" || name == "inner";
  if ((text[0] != '+' && text[0] != '-') || !(body || table))
    throw ConfigError(ini.where(key) + "axis '" + text +
                      "': expected +x, -x, +y, -y, +z, -z, +outer, -outer, +inner or -inner");
  const double sign = text[0] == '-' ? -1.0 : 1.0;
  if (body) {
    st.kind = RotationStep::Axis::Body;
    st.axis_b = sign * Eigen::Vector3d::Unit(name[0] - 'x');
  } else {
    st.kind = name == "outer" ? RotationStep::Axis::Outer : RotationStep::Axis::Inner;
    st.sign = sign;
  }
  return st;
}

// Checks a turn's angle and timing (given in SI by the caller). `where` names the file, line and
// key for messages.
void check_step(const std::string& where, double accel, const PlanLimits& limits,
                RotationStep& st) {
  if (!(st.angle > 0.0)) throw ConfigError(where + "the angle must be positive");
  if (!(st.angle <= kMaxTurnAngle))
    throw ConfigError(where + "the angle must be at most 100 turns (36000 deg)");
  if (st.duration > 0.0 && 4.0 * st.angle / accel > st.duration * st.duration)
    throw ConfigError(
        where + "acceleration too low to turn " + std::to_string(st.angle / units::deg) +
        " deg in " + std::to_string(st.duration) + " s (needs at least " +
        std::to_string(4.0 * st.angle / (st.duration * st.duration) / units::deg) + " deg/s^2)");
  const double turn = st.duration > 0.0
                          ? st.duration
                          : TrapezoidProfile::by_rate(st.angle, st.rate, accel).duration();
  if (!(turn <= limits.max_duration))
    throw ConfigError(where + "the turn lasts " + std::to_string(turn) +
                      " s, longer than the plan limit of " + days(limits.max_duration) + " days" +
                      limits.hint());
}

// A rate-table segment's angle from its rate and `hold` (time at the rate) or `revolutions`.
void set_constant_rate(double accel, RotationStep& st) {
  st.constant_rate = true;
  st.angle = st.revolutions > 0 ? 2.0 * M_PI * st.revolutions
                                : st.rate * st.hold + st.rate * st.rate / accel;
}

// Whole revolutions (1 to 100) of `key`: one value or `n` (0: any count) values.
std::vector<int> read_revolutions(const IniFile& ini, const std::string& key) {
  std::istringstream in(ini.get_string(key));
  std::vector<int> out;
  for (std::string w; in >> w;) {
    const bool digits = !w.empty() && w.size() <= 3 && std::all_of(w.begin(), w.end(), [](char c) {
      return c >= '0' && c <= '9';
    });
    const int n = digits ? std::stoi(w) : 0;
    if (n < 1 || n > 100)
      throw ConfigError(ini.where(key) + "'" + w + "': expected whole revolutions, 1 to 100");
    out.push_back(n);
  }
  if (out.empty()) throw ConfigError(ini.where(key) + "no revolutions given");
  return out;
}

// A [step.N] rate-table segment: `rate` with `hold` or `revolutions`, no angle.
void read_rate_segment(const IniFile& ini, const std::string& s, double accel,
                       const PlanLimits& limits, RotationStep& st) {
  const bool has_revs = ini.has(s + ".revolutions"), has_hold = ini.has(s + ".hold");
  if (has_revs == has_hold || !ini.has(s + ".rate") || ini.has(s + ".duration"))
    throw ConfigError(ini.path() + ": [" + s +
                      "]: a rate-table segment (no 'angle') needs 'rate' and exactly one of "
                      "'hold' (s at the rate) and 'revolutions', no 'duration'");
  st.rate = ini.get_quantity(s + ".rate", Q::AngularRate, "deg/s");
  if (!(st.rate > 0.0))
    throw ConfigError(ini.where(s + ".rate") + "must be positive (the sign is the axis')");
  if (has_revs) {
    const auto revs = read_revolutions(ini, s + ".revolutions");
    if (revs.size() != 1) throw ConfigError(ini.where(s + ".revolutions") + "expected one value");
    st.revolutions = revs.front();
  } else {
    st.hold = read_static_time(ini, s + ".hold", limits, false);
  }
  set_constant_rate(accel, st);
  check_step(ini.where(s + ".rate"), accel, limits, st);
  st.pause = ini.has(s + ".pause") ? read_static_time(ini, s + ".pause", limits, true) : 0.0;
}

// One [step.N] section.
void read_step_timing(const IniFile& ini, const std::string& s, double accel,
                      const PlanLimits& limits, RotationStep& st) {
  if (!ini.has(s + ".angle") && (ini.has(s + ".revolutions") || ini.has(s + ".hold")))
    return read_rate_segment(ini, s, accel, limits, st);
  if (ini.has(s + ".revolutions") || ini.has(s + ".hold"))
    throw ConfigError(ini.where(s + (ini.has(s + ".hold") ? ".hold" : ".revolutions")) +
                      "a turn with an 'angle' has no 'hold' or 'revolutions' (a rate-table "
                      "segment has no angle)");
  st.angle = ini.get_quantity(s + ".angle", Q::Angle, "deg");
  const bool has_duration = ini.has(s + ".duration"), has_rate = ini.has(s + ".rate");
  if (has_duration == has_rate)
    throw ConfigError(ini.path() + ": [" + s + "]: give exactly one of 'duration' and 'rate'");
  if (has_duration) {
    st.duration = ini.get_quantity(s + ".duration", Q::Time, "s");
    if (!(st.duration > 0.0)) throw ConfigError(ini.where(s + ".duration") + "must be positive");
  } else {
    st.rate = ini.get_quantity(s + ".rate", Q::AngularRate, "deg/s");
    if (!(st.rate > 0.0)) throw ConfigError(ini.where(s + ".rate") + "must be positive");
  }
  check_step(ini.where(s + (ini.has(s + ".angle") ? ".angle" : ".duration")), accel, limits, st);
  st.pause = ini.has(s + ".pause") ? read_static_time(ini, s + ".pause", limits, true) : 0.0;
}

// A per-turn value of [rotations]: `one` (a single value for every turn) or `list` (one value per
// turn, `n` of them). Empty when neither is given.
std::vector<double> per_turn(const IniFile& ini, const std::string& one, const std::string& list,
                             std::size_t n, Q kind, const std::string& unit) {
  const std::string k1 = "rotations." + one, kn = "rotations." + list;
  if (ini.has(k1) && ini.has(kn))
    throw ConfigError(ini.where(kn) + "give either '" + one + "' (one for every turn) or '" + list +
                      "' (one per turn), not both");
  if (ini.has(k1)) {
    const auto v = ini.get_quantities(k1, kind, unit);
    if (v.size() != 1)
      throw ConfigError(ini.where(k1) +
                        "expected one value for every turn; give one per turn as '" + list +
                        " = ...'");
    return std::vector<double>(n, v.front());
  }
  if (ini.has(kn)) {
    auto v = ini.get_quantities(kn, kind, unit);
    if (v.size() != n)
      throw ConfigError(ini.where(kn) + "expected " + std::to_string(n) +
                        " values, one per turn of 'axes', got " + std::to_string(v.size()));
    return v;
  }
  return {};
}

// The [rotations] section: turns listed by axis with per-turn or common timing.
void read_rotations_section(const IniFile& ini, Plan& p) {
  const PlanLimits& limits = p.limits;
  auto check_count = [&](std::size_t n, const char* what) {
    if (n > limits.max_entries)
      throw ConfigError(ini.path() + ": " + std::to_string(n) + " " + what +
                        ", more than the plan limit of " + std::to_string(limits.max_entries) +
                        limits.hint());
  };
  ini.check_keys("rotations", {"axes", "angle", "angles", "duration", "durations", "rate", "rates",
                               "pause", "pauses", "hold", "holds", "revolutions"});
  std::istringstream axes(ini.get_string("rotations.axes"));
  for (std::string a; axes >> a;) {
    check_count(p.steps.size() + 1, "turns");
    p.steps.push_back(parse_axis(ini, "rotations.axes", a));
  }
  const std::size_t n = p.steps.size();
  if (n == 0) throw ConfigError(ini.where("rotations.axes") + "no axes given");
  const auto angles = per_turn(ini, "angle", "angles", n, Q::Angle, "deg");
  const auto durations = per_turn(ini, "duration", "durations", n, Q::Time, "s");
  const auto rates = per_turn(ini, "rate", "rates", n, Q::AngularRate, "deg/s");
  const auto pauses = per_turn(ini, "pause", "pauses", n, Q::Time, "s");
  const auto holds = per_turn(ini, "hold", "holds", n, Q::Time, "s");
  std::vector<int> revolutions;
  if (ini.has("rotations.revolutions")) {
    revolutions = read_revolutions(ini, "rotations.revolutions");
    if (revolutions.size() == 1) revolutions.assign(n, revolutions.front());
    if (revolutions.size() != n)
      throw ConfigError(ini.where("rotations.revolutions") + "expected 1 or " + std::to_string(n) +
                        " values, one per turn of 'axes'");
  }
  const bool rate_table = !holds.empty() || !revolutions.empty();
  if (rate_table && (!angles.empty() || !durations.empty() || rates.empty() ||
                     (!holds.empty() && !revolutions.empty())))
    throw ConfigError(ini.path() +
                      ": [rotations]: rate-table segments need 'rate' (or 'rates') and "
                      "exactly one of 'hold' ('holds') and 'revolutions', no angle or "
                      "duration");
  if (angles.empty() && !rate_table)
    throw ConfigError(ini.path() +
                      ": [rotations]: missing 'angle' (or 'angles', one per turn; or 'hold' "
                      "or 'revolutions' for rate-table segments)");
  if (durations.empty() == rates.empty())
    throw ConfigError(ini.path() +
                      ": [rotations]: give exactly one of 'duration', 'durations', 'rate' "
                      "and 'rates'");
  auto key_of = [&](const char* one, const char* list) {
    return ini.has(std::string("rotations.") + one) ? std::string("rotations.") + one
                                                    : std::string("rotations.") + list;
  };
  const std::string timing_key =
      durations.empty() ? key_of("rate", "rates") : key_of("duration", "durations");
  for (std::size_t i = 0; i < n; ++i) {
    RotationStep& st = p.steps[i];
    const std::string turn = "turn " + std::to_string(i + 1) + " (" + st.axis_name + "): ";
    if (rate_table) {
      st.rate = rates[i];
      if (!(st.rate > 0.0) || !(holds.empty() || holds[i] > 0.0))
        throw ConfigError(ini.where(timing_key) + turn + "the rate and the hold must be positive");
      st.hold = holds.empty() ? 0.0 : holds[i];
      st.revolutions = revolutions.empty() ? 0 : revolutions[i];
      set_constant_rate(p.move_accel, st);
    } else if (!durations.empty()) {
      st.angle = angles[i];
      st.duration = durations[i];
      if (!(st.duration > 0.0))
        throw ConfigError(ini.where(timing_key) + turn + "the duration must be positive");
    } else {
      st.angle = angles[i];
      st.rate = rates[i];
      if (!(st.rate > 0.0))
        throw ConfigError(ini.where(timing_key) + turn + "the rate must be positive");
    }
    check_step(ini.where(rate_table ? timing_key : key_of("angle", "angles")) + turn, p.move_accel,
               limits, st);
    st.pause = pauses.empty() ? 0.0 : pauses[i];
    const std::string pause_key = key_of("pause", "pauses");
    if (!(st.pause >= 0.0))
      throw ConfigError(ini.where(pause_key) + turn + "the pause must not be negative");
    if (!(st.pause <= limits.max_duration))
      throw ConfigError(ini.where(pause_key) + turn +
                        "the pause is longer than the plan "
                        "limit of " +
                        days(limits.max_duration) + " days" + limits.hint());
  }
  if (!ini.sections_with_prefix("step.").empty())
    throw ConfigError(ini.path() +
                      ": give the rotations either as [rotations] axes or as [step.N], not both");
}

// A three-axis table's move from `from` to `to` starting at t: one turn about the rotation's
// eigen-axis (navigation frame) at the plan's move rate and acceleration.
MotionSegment eigen_axis_move(double t, const Eigen::Matrix3d& from, const Eigen::Matrix3d& to,
                              const Plan& plan) {
  const Eigen::Vector3d r = rotvec_from_dcm(to * from.transpose());
  MotionSegment m;
  m.t0 = t;
  m.C_b_n_start = from;
  if (r.norm() > 0.0) m.axis_n = r.normalized();
  m.alpha = TrapezoidProfile::by_rate(r.norm(), plan.move_rate, plan.move_accel);
  m.t1 = t + m.alpha.duration();
  return m;
}

// The table's dynamics and installation errors applied to the plan's motion.
void realize_errors(const TableErrors& errors, std::vector<MotionSegment>& segments,
                    std::vector<Dwell>& dwells) {
  if (errors.dynamics.any()) {
    // The table realizes each commanded profile with its dynamics.
    errors.dynamics.validate();
    for (auto& s : segments) {
      if (s.is_static()) continue;
      s.alpha = errors.dynamics.realize(s.alpha.commanded());
      s.beta = errors.dynamics.realize(s.beta.commanded());
      s.gamma = errors.dynamics.realize(s.gamma.commanded());
    }
  }
  if (errors.has_installation_errors()) {
    // C_b_n_true = R(base) C_b_n R(mounting): nav-fixed axes turn with the base, body-fixed axes
    // are seen from the mounted IMU.
    const Eigen::Matrix3d C_base = dcm_from_rotvec(errors.base_n());
    const Eigen::Matrix3d C_b_p = dcm_from_rotvec(errors.mounting_b);
    for (auto& s : segments) {
      s.C_b_n_start = C_base * s.C_b_n_start * C_b_p;
      s.axis_n = C_base * s.axis_n;
      s.axis_c_n = C_base * s.axis_c_n;
      s.axis_b = C_b_p.transpose() * s.axis_b;
    }
    for (auto& d : dwells) d.C_b_n_true = C_base * d.C_b_n_true * C_b_p;
  }
}

}  // namespace

Site read_site(const IniFile& ini) {
  Site site;
  site.lat_rad = ini.get_quantity("site.latitude", Q::Angle, "deg");
  site.lon_rad = ini.get_quantity("site.longitude", Q::Angle, "deg", 0.0);
  site.h_m = ini.get_quantity("site.height", Q::Length, "m", 0.0);
  auto check = [&](const std::string& key, const std::string& problem) {
    if (!problem.empty()) throw ConfigError(ini.where(key) + problem);
  };
  check("site.latitude", latitude_problem(site.lat_rad));
  check("site.longitude", longitude_problem(site.lon_rad));
  check("site.height", height_problem(site.h_m));
  return site;
}

Plan Plan::load(const std::string& path) {
  if (path.empty()) throw ConfigError("plan: no file name given");
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw ConfigError(path + ": is a directory, not a plan file");
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open plan file");
  std::stringstream buffer;
  buffer << in.rdbuf();
  return parse(path, buffer.str());
}

Plan Plan::parse(const std::string& path, const std::string& text) {
  const IniFile ini(path, text);
  Plan p;
  p.path = path;
  p.text = text;
  p.name = ini.get_string("plan.name", "plan");
  const std::string type = ini.get_string("plan.type");
  try {
    p.convention = parse_angle_convention(ini.get_string("plan.convention", "ned-frd"));
  } catch (const std::invalid_argument& e) {
    throw ConfigError(ini.where("plan.convention") + e.what());
  }
  ini.check_keys("plan", {"name", "description", "type", "convention", "move_rate",
                          "move_acceleration", "rotation_acceleration", "allow_large", "repeat"});
  p.limits =
      ini.get_bool("plan.allow_large", false) ? PlanLimits::raised() : PlanLimits::standard();
  const PlanLimits& limits = p.limits;
  if (ini.has("site.latitude")) {
    p.has_site = true;
    p.site = read_site(ini);
  } else if (ini.has("site.longitude") || ini.has("site.height")) {
    throw ConfigError(ini.where(ini.has("site.longitude") ? "site.longitude" : "site.height") +
                      "[site] without 'latitude'");
  }
  ini.check_keys("site", {"latitude", "longitude", "height"});
  // Table geometry; the default mounting makes table angles zero equal plan angles zero.
  p.table.outer_axis_n = read_vector(ini, "table.outer_axis", Eigen::Vector3d::UnitX());
  p.table.inner_axis_p = read_vector(ini, "table.inner_axis", -Eigen::Vector3d::UnitZ());
  p.table.C_b_p = C_b_n_from_euler(p.convention, EulerAngles{});
  p.table.axes = ini.get_int("table.axes", 2, 2, 3);
  ini.check_keys("table", {"outer_axis", "inner_axis", "axes"});
  auto check_count = [&](std::size_t n, const char* what) {
    if (n > limits.max_entries)
      throw ConfigError(ini.path() + ": " + std::to_string(n) + " " + what +
                        ", more than the plan limit of " + std::to_string(limits.max_entries) +
                        limits.hint());
  };
  // (yaw: enu-rfu only, which read_angles says)
  const std::vector<std::string> angle_keys = {"heading", "yaw", "pitch", "roll", "dwell"};

  if (type == "orientations") {
    p.type = Type::Orientations;
    p.move_rate = ini.get_quantity("plan.move_rate", Q::AngularRate, "deg/s");
    p.move_accel = ini.get_quantity("plan.move_acceleration", Q::AngularAcceleration, "deg/s^2");
    if (!(p.move_rate > 0.0) || !(p.move_accel > 0.0))
      throw ConfigError(ini.path() + ": [plan] move_rate and move_acceleration must be positive");
    const auto sections = ini.sections_with_prefix("orientation.");
    check_count(sections.size(), "orientations");
    std::vector<std::pair<int, PlanOrientation>> found;
    for (const auto& s : sections) {
      ini.check_keys(s, angle_keys);
      PlanOrientation o;
      const int n = section_number(ini, s, "orientation.");
      o.label = std::to_string(n);
      o.angles = read_angles(ini, s, p.convention);
      o.dwell = read_static_time(ini, s + ".dwell", limits, false);
      found.emplace_back(n, o);
    }
    std::sort(found.begin(), found.end(), [](auto& a, auto& b) { return a.first < b.first; });
    for (std::size_t i = 0; i < found.size(); ++i) {
      if (found[i].first != static_cast<int>(i) + 1)
        throw ConfigError(ini.path() + ": orientations must be numbered 1, 2, ... without gaps; " +
                          "missing [orientation." + std::to_string(i + 1) + "]");
      p.orientations.push_back(found[i].second);
    }
    if (p.orientations.empty()) throw ConfigError(ini.path() + ": no [orientation.N] sections");
    // Every orientation must be reachable by the table.
    const Table table(p.table);
    for (const auto& o : p.orientations) {
      try {
        table.angles_for(C_b_n_from_euler(p.convention, o.angles));
      } catch (const UnreachableOrientation& e) {
        throw ConfigError(ini.path() + ": [orientation." + o.label + "]: " + e.what());
      }
    }
  } else if (type == "rotations") {
    p.type = Type::Rotations;
    p.move_accel =
        ini.get_quantity("plan.rotation_acceleration", Q::AngularAcceleration, "deg/s^2");
    if (!(p.move_accel > 0.0))
      throw ConfigError(ini.where("plan.rotation_acceleration") + "must be positive");
    ini.check_keys("start", angle_keys);
    p.start = read_angles(ini, "start", p.convention);
    // 0: the log begins while the table already turns at the first segment's rate.
    p.start_dwell = ini.get_quantity("start.dwell", Q::Time, "s") == 0.0
                        ? 0.0
                        : read_static_time(ini, "start.dwell", limits, false);
    if (ini.has("rotations.axes")) {
      read_rotations_section(ini, p);
    } else {
      if (!ini.sections_with_prefix("rotations").empty())
        throw ConfigError(ini.path() + ": [rotations] needs 'axes'");
      const auto sections = ini.sections_with_prefix("step.");
      check_count(sections.size(), "turns");
      std::vector<std::pair<int, RotationStep>> found;
      for (const auto& s : sections) {
        ini.check_keys(s, {"axis", "angle", "duration", "rate", "pause", "hold", "revolutions"});
        RotationStep st = parse_axis(ini, s + ".axis", ini.get_string(s + ".axis"));
        read_step_timing(ini, s, p.move_accel, limits, st);
        found.emplace_back(section_number(ini, s, "step."), st);
      }
      std::sort(found.begin(), found.end(), [](auto& a, auto& b) { return a.first < b.first; });
      for (std::size_t i = 0; i < found.size(); ++i) {
        if (found[i].first != static_cast<int>(i) + 1)
          throw ConfigError(ini.path() + ": steps must be numbered 1, 2, ... without gaps; " +
                            "missing [step." + std::to_string(i + 1) + "]");
        p.steps.push_back(found[i].second);
      }
    }
    if (p.steps.empty()) throw ConfigError(ini.path() + ": a rotation plan needs rotations");
    if (!(p.start_dwell > 0.0) && !p.steps.front().constant_rate)
      throw ConfigError(ini.where("start.dwell") +
                        "0 only when the plan begins in a rate-table segment (its first turn "
                        "with 'hold' or 'revolutions'): a turn of known angle starts from a rest");
  } else {
    throw ConfigError(ini.where("plan.type") + "expected 'orientations' or 'rotations', got '" +
                      type + "'");
  }
  for (const auto& key : ini.keys()) {
    const std::string sec = key.substr(0, key.find('.'));
    static const std::vector<std::string> known = {"plan",  "site",      "table", "orientation",
                                                   "start", "rotations", "step"};
    if (std::find(known.begin(), known.end(), sec) == known.end())
      throw ConfigError(ini.where(key) + "unknown section");
  }
  // `repeat = N`: the orientations (the turns after the start dwell) run N times in a row, e.g.
  // while a thermal chamber ramps (labels of the k-th run get "#k" from the second on).
  const int repeat = ini.get_int("plan.repeat", 1, 1, 100000);
  const std::size_t entries =
      (p.type == Type::Orientations ? p.orientations.size() : p.steps.size()) *
      static_cast<std::size_t>(repeat);
  check_count(entries,
              p.type == Type::Orientations ? "orientations (repeated)" : "turns (repeated)");
  const auto one_orientations = p.orientations;
  const auto one_steps = p.steps;
  for (int k = 2; k <= repeat; ++k) {
    for (auto o : one_orientations) {
      o.label += "#" + std::to_string(k);
      p.orientations.push_back(o);
    }
    p.steps.insert(p.steps.end(), one_steps.begin(), one_steps.end());
  }
  // The whole plan's duration (dwells, moves, turns, pauses), as the motion has it.
  // (A plan without a start rest, [start] dwell = 0, is timed with a 1 s one taken off again.)
  Plan timed = p;
  if (p.type == Type::Rotations && !(p.start_dwell > 0.0)) timed.start_dwell = 1.0;
  const double total = build_motion(timed, Site{}).duration() - timed.start_dwell + p.start_dwell;
  if (!(total <= limits.max_duration))
    throw ConfigError(ini.path() + ": the plan lasts " + days(total) +
                      " days, longer than the plan limit of " + days(limits.max_duration) +
                      " days" + limits.hint());
  return p;
}

Motion build_motion(const Plan& plan, const Site& site, const TableErrors& errors) {
  std::mt19937_64 rng(errors.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto angle_error = [&] {
    return errors.angle_sigma > 0.0 ? errors.angle_sigma * normal(rng) : 0.0;
  };

  const Table nominal(plan.table);
  TableGeometry true_geometry = plan.table;
  if (errors.non_orthogonality != 0.0) {
    const Eigen::Vector3d lean = plan.table.inner_axis_p.cross(plan.table.outer_axis_n);
    if (lean.norm() > 1e-9)
      true_geometry.inner_axis_p =
          rotation(lean.normalized(), errors.non_orthogonality) * plan.table.inner_axis_p;
  }
  const Table truth(true_geometry);

  std::vector<MotionSegment> segments;
  std::vector<Dwell> dwells;
  double t = 0.0;
  // The table's axis angles along the motion (true, as its encoders read them), while the motion
  // is made of table moves.
  bool table_known = false;
  TableAngles table_now{};
  auto add_dwell = [&](const std::string& label, const Eigen::Matrix3d& known,
                       const Eigen::Matrix3d& actual, double duration) {
    MotionSegment s;
    s.t0 = t;
    s.t1 = t + duration;
    s.C_b_n_start = actual;
    s.has_table = table_known;
    s.outer0 = table_now.outer;
    s.inner0 = table_now.inner;
    segments.push_back(s);
    Dwell d;
    d.index = static_cast<int>(dwells.size()) + 1;
    d.label = label;
    d.t_start = t;
    d.t_end = s.t1;
    d.C_b_n_known = known;
    d.C_b_n_true = actual;
    dwells.push_back(d);
    t = s.t1;
  };

  if (plan.type == Plan::Type::Orientations) {
    TableAngles prev{};
    Eigen::Matrix3d actual = Eigen::Matrix3d::Identity();  // of the dwell before
    for (std::size_t i = 0; i < plan.orientations.size(); ++i) {
      const auto& o = plan.orientations[i];
      const Eigen::Matrix3d known = C_b_n_from_euler(plan.convention, o.angles);
      TableAngles cmd = nominal.angles_for(known);
      cmd.outer += angle_error();
      cmd.inner += angle_error();
      Eigen::Matrix3d commanded = truth.C_b_n(cmd);
      if (plan.table.axes == 3) {  // its three angles' errors: a small turn of the attitude
        const Eigen::Vector3d e(angle_error(), angle_error(), angle_error());
        commanded = dcm_from_rotvec(e) * known;
      }
      if (i > 0 && plan.table.axes == 3) {
        const MotionSegment m = eigen_axis_move(t, actual, commanded, plan);
        if (m.t1 > t) {
          segments.push_back(m);
          t = m.t1;
        }
      } else if (i > 0) {
        // Each axis takes the shorter way round; both start together.
        auto wrap = [](double a) { return std::remainder(a, 2.0 * M_PI); };
        MotionSegment m;
        m.t0 = t;
        m.C_b_n_start = actual;
        m.axis_n = truth.geometry().outer_axis_n;
        m.alpha = TrapezoidProfile::by_rate(wrap(cmd.outer - prev.outer), plan.move_rate,
                                            plan.move_accel);
        m.axis_b = truth.inner_axis_b();
        m.beta = TrapezoidProfile::by_rate(wrap(cmd.inner - prev.inner), plan.move_rate,
                                           plan.move_accel);
        m.t1 = t + std::max(m.alpha.duration(), m.beta.duration());
        m.has_table = true;
        m.outer0 = prev.outer;
        m.inner0 = prev.inner;
        if (m.t1 > t) {
          segments.push_back(m);
          t = m.t1;
        }
        // Continue from where the move really ends (wrapping aside, the same attitude).
        cmd.outer = prev.outer + m.alpha.angle();
        cmd.inner = prev.inner + m.beta.angle();
      }
      table_known = plan.table.axes == 2;
      table_now = cmd;
      Eigen::Vector3d wobble = Eigen::Vector3d::Zero();
      if (errors.attitude_sigma > 0.0)
        for (int k = 0; k < 3; ++k) wobble(k) = errors.attitude_sigma * normal(rng);
      const Eigen::Matrix3d target = dcm_from_rotvec(wobble) * commanded;
      if (i > 0 && segments.back().t1 > segments.back().t0) {
        // The table sets the dwell to its accuracy during the move (the gyros see the
        // correction, as on a real table): a small turn about a navigation-frame axis.
        MotionSegment& m = segments.back();
        const Eigen::Vector3d c = rotvec_from_dcm(target * m.C_b_n_end().transpose());
        if (c.norm() > 0.0) {
          m.axis_c_n = c.normalized();
          m.gamma = TrapezoidProfile::by_duration(c.norm(), m.t1 - m.t0, plan.move_accel);
        }
      }
      add_dwell(o.label, known, target, o.dwell);
      actual = target;
      prev = cmd;
    }
  } else {
    Eigen::Matrix3d known = C_b_n_from_euler(plan.convention, plan.start);
    Eigen::Vector3d start_error;
    const double start_sigma = errors.start_sigma >= 0.0     ? errors.start_sigma
                               : errors.attitude_sigma > 0.0 ? errors.attitude_sigma
                                                             : errors.angle_sigma;
    for (int k = 0; k < 3; ++k)
      start_error(k) = start_sigma > 0.0 ? start_sigma * normal(rng) : 0.0;
    Eigen::Matrix3d actual = dcm_from_rotvec(start_error) * known;
    try {  // table angles while the steps are table-axis turns from a reachable start
      table_now = truth.angles_for(actual);
      table_known = plan.table.axes == 2;
    } catch (const UnreachableOrientation&) {
      table_known = false;
    }
    // A plan that begins in its first rate-table segment has no start rest: no motion starts
    // from it (the rate-table method reads the segments' means alone, rate_segments).
    if (!(plan.start_dwell > 0.0))
      throw ConfigError(plan.path +
                        ": [start] dwell = 0 (the plan begins in its first rate-table segment): "
                        "only --method rate-table reads such a plan; the other methods need a "
                        "rest to start from");
    add_dwell("start", known, actual, plan.start_dwell);
    for (std::size_t i = 0; i < plan.steps.size(); ++i) {
      const RotationStep& st = plan.steps[i];
      MotionSegment m;
      m.t0 = t;
      m.C_b_n_start = actual;
      const double realized = st.angle + angle_error();
      const TrapezoidProfile profile =
          st.duration > 0.0 ? TrapezoidProfile::by_duration(realized, st.duration, plan.move_accel)
                            : TrapezoidProfile::by_rate(realized, st.rate, plan.move_accel);
      if (st.kind == RotationStep::Axis::Body) table_known = false;
      m.has_table = table_known;
      m.outer0 = table_now.outer;
      m.inner0 = table_now.inner;
      if (st.kind == RotationStep::Axis::Outer) {
        m.axis_n = st.sign * truth.geometry().outer_axis_n;
        m.alpha = profile;
        m.outer_sign = st.sign;
        table_now.outer += st.sign * realized;
        known = rotation(st.sign * nominal.geometry().outer_axis_n, st.angle) * known;
      } else {
        m.axis_b = st.kind == RotationStep::Axis::Body ? st.axis_b : st.sign * truth.inner_axis_b();
        m.beta = profile;
        m.inner_sign = st.sign;
        if (st.kind == RotationStep::Axis::Inner) table_now.inner += st.sign * realized;
        const Eigen::Vector3d nominal_axis =
            st.kind == RotationStep::Axis::Body ? st.axis_b : st.sign * nominal.inner_axis_b();
        known = known * rotation(nominal_axis, st.angle);
      }
      if (st.kind == RotationStep::Axis::Body && errors.attitude_sigma > 0.0 && st.pause > 0.0) {
        // The table sets the dwell after the turn to its accuracy, whatever the earlier dwells'
        // errors: the turn ends at R(w) known with an independent w, turning about a nav axis
        // by the small correction in the same time (the gyros see it).
        Eigen::Vector3d w;
        for (int k = 0; k < 3; ++k) w(k) = errors.attitude_sigma * normal(rng);
        const Eigen::Matrix3d nominal_end = m.C_b_n_end();
        const Eigen::Vector3d correction =
            rotvec_from_dcm(dcm_from_rotvec(w) * known * nominal_end.transpose());
        if (correction.norm() > 0.0) {
          m.axis_n = correction.normalized();
          m.alpha =
              TrapezoidProfile::by_duration(correction.norm(), profile.duration(), plan.move_accel);
        }
      }
      m.t1 = t + profile.duration();
      segments.push_back(m);
      t = m.t1;
      actual = m.C_b_n_end();
      if (st.pause > 0.0)
        add_dwell("after " + std::to_string(i + 1) + " (" + st.axis_name + ")", known, actual,
                  st.pause);
    }
  }
  realize_errors(errors, segments, dwells);
  return Motion(site, std::move(segments), std::move(dwells));
}

}  // namespace sinscal
