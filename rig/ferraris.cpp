#include "rig/ferraris.hpp"

#include <cmath>
#include <random>
#include <sstream>
#include <stdexcept>

#include "models/attitude.hpp"
#include "models/config.hpp"

namespace sinscal {

namespace {

const char* const kFaces[6] = {"x_p", "x_a", "y_p", "y_a", "z_p", "z_a"};
const char* const kTurns[3] = {"x_rot", "y_rot", "z_rot"};

// C_b_n with body direction `up_b` pointing up (NED: -D) at heading `psi` about the vertical.
Eigen::Matrix3d attitude_with_up(const Eigen::Vector3d& up_b, double psi) {
  const Eigen::Vector3d up_n(0.0, 0.0, -1.0);
  const Eigen::Vector3d u = up_b.normalized();
  Eigen::Matrix3d C = Eigen::Matrix3d::Identity();
  const Eigen::Vector3d axis = u.cross(up_n);
  const double s = axis.norm(), c = u.dot(up_n);
  if (s > 1e-12)
    C = rotation(axis / s, std::atan2(s, c));
  else if (c < 0.0)
    C = rotation(Eigen::Vector3d::UnitX(), M_PI);
  return rotation(up_n, psi) * C;
}

struct Builder {
  std::vector<MotionSegment> segments;
  double t = 0.0;
  Eigen::Matrix3d C = Eigen::Matrix3d::Identity();
  void rest(double duration) {
    MotionSegment s;
    s.t0 = t;
    s.t1 = t + duration;
    s.C_b_n_start = C;
    segments.push_back(s);
    t = s.t1;
  }
  // A rest with the hand's tremor: every half `period` s the unit turns from its present small
  // offset (about the rest's attitude) to a new one drawn afresh (each component 1-sigma
  // `amplitude`), so the offset is stationary and the rest ends where the tremor left it, as a
  // hand's does (not back at its start: the rest's mean rate carries the net turn).
  template <class Rng>
  void tremor_rest(double duration, double amplitude, double period, Rng& rng) {
    if (!(amplitude > 0.0)) {
      rest(duration);
      return;
    }
    std::normal_distribution<double> normal(0.0, 1.0);
    const double half = 0.5 * period;
    const auto steps = static_cast<int>(std::floor(duration / half));
    const Eigen::Matrix3d C0 = C;
    for (int c = 0; c < steps; ++c) {
      const Eigen::Vector3d target(amplitude * normal(rng), amplitude * normal(rng),
                                   amplitude * normal(rng));
      // Body-axis rotation from the present attitude to C0 exp(target) (C_b_n: body to nav).
      const Eigen::Vector3d r = rotvec_from_dcm(C.transpose() * C0 * dcm_from_rotvec(target));
      MotionSegment s;
      s.t0 = t;
      s.t1 = t + half;
      s.C_b_n_start = C;
      if (r.norm() > 0.0) {
        s.axis_b = r.normalized();
        s.beta =
            TrapezoidProfile::by_duration(r.norm(), half, 8.0 * r.norm() / (half * half) + 1e-12);
      }
      segments.push_back(s);
      t = s.t1;
      C = s.C_b_n_end();
    }
    if (duration > steps * half) rest(duration - steps * half);
  }
  void move_to(const Eigen::Matrix3d& target, double duration) {
    const Eigen::Vector3d r = rotvec_from_dcm(target * C.transpose());
    MotionSegment s;
    s.t0 = t;
    s.t1 = t + duration;
    s.C_b_n_start = C;
    if (r.norm() > 0.0) {
      s.axis_n = r.normalized();
      s.alpha =
          TrapezoidProfile::by_duration(r.norm(), duration, 6.0 * r.norm() / (duration * duration));
    }
    segments.push_back(s);
    t = s.t1;
    C = target;
  }
};

}  // namespace

FerrarisDeclaration read_ferraris_declaration(const IniFile& ini) {
  ini.check_keys("six_face", {"faces", "turns", "turn_angle", "turn_accuracy", "face_accuracy",
                              "min_rest", "turn_edge", "rest_correlation"});
  FerrarisDeclaration d;
  auto labels = [&](const char* key, std::size_t n, auto& out) {
    const std::string k = std::string("six_face.") + key;
    if (!ini.has(k)) return;
    std::istringstream in(ini.get_string(k));
    std::vector<std::string> v;
    for (std::string w; in >> w;) v.push_back(w);
    if (v.size() != n)
      throw ConfigError(ini.where(k) + "needs " + std::to_string(n) + " labels, found " +
                        std::to_string(v.size()));
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (v[i] == v[j]) throw ConfigError(ini.where(k) + "label '" + v[i] + "' given twice");
    for (std::size_t i = 0; i < n; ++i) out[i] = v[i];
  };
  labels("faces", 6, d.faces);
  labels("turns", 3, d.turns);
  for (const auto& f : d.faces)
    for (const auto& t : d.turns)
      if (f == t) throw ConfigError(ini.path() + ": label '" + f + "' is both a face and a turn");
  auto angle = [&](const char* key, double def, double lo, double hi) {
    const std::string k = std::string("six_face.") + key;
    const double v = ini.get_quantity(k, QuantityKind::Angle, "deg", def);
    if (!(std::abs(v) > lo && std::abs(v) <= hi))
      throw ConfigError(ini.where(k) + "must be within " + std::to_string(lo / units::deg) +
                        " and " + std::to_string(hi / units::deg) + " deg");
    return v;
  };
  d.turn_angle = angle("turn_angle", d.turn_angle, 10.0 * units::deg, 3600.0 * units::deg);
  d.turn_accuracy = angle("turn_accuracy", d.turn_accuracy, 0.0, 45.0 * units::deg);
  d.face_accuracy = angle("face_accuracy", d.face_accuracy, 0.0, 20.0 * units::deg);
  auto seconds = [&](const char* key, double def) {
    const std::string k = std::string("six_face.") + key;
    const double v = ini.get_quantity(k, QuantityKind::Time, "s", def);
    if (!(v > 0.0 && v <= 3600.0))
      throw ConfigError(ini.where(k) + "must be above 0 and at most 3600 s");
    return v;
  };
  d.min_rest = seconds("min_rest", d.min_rest);
  d.turn_edge = seconds("turn_edge", d.turn_edge);
  d.rest_correlation = seconds("rest_correlation", d.rest_correlation);
  return d;
}

std::string FerrarisSession::label_at(double t) const {
  for (const auto& p : parts)
    if (t > p.t_start && t <= p.t_end) return p.label;
  return "";
}

FerrarisSession ferraris_session(const Site& site, const FerrarisOptions& o, std::uint64_t seed) {
  if (!(o.rest > 0.0 && o.move > 0.0 && o.pause > o.label_margin && o.turn > 0.0 &&
        o.label_margin >= 0.0 && o.face_tilt >= 0.0 && o.turn_angle_error >= 0.0))
    throw std::invalid_argument("ferraris_session: durations and errors must be positive");
  std::mt19937_64 rng(seed);
  // The tremor from its own stream: the session's placements and turns do not depend on it.
  std::mt19937_64 tremor_rng(seed ^ 0x7265'6d6f'7274ULL);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> heading(-M_PI, M_PI);
  auto tilted = [&](int axis, double sign) {
    Eigen::Vector3d u = sign * Eigen::Vector3d::Unit(axis);
    u(static_cast<Eigen::Index>((axis + 1) % 3)) += o.face_tilt * normal(rng);
    u(static_cast<Eigen::Index>((axis + 2) % 3)) += o.face_tilt * normal(rng);
    return u.normalized();
  };
  Builder b;
  std::vector<LabelledPart> parts;
  b.C = attitude_with_up(tilted(0, 1.0), heading(rng));
  b.rest(2.0);
  for (int k = 0; k < 6; ++k) {
    b.move_to(attitude_with_up(tilted(k / 2, k % 2 ? -1.0 : 1.0), heading(rng)), o.move);
    parts.push_back({kFaces[k], b.t, b.t + o.rest});
    b.tremor_rest(o.rest, o.tremor, o.tremor_period, tremor_rng);
  }
  const Eigen::Vector3d up_n(0.0, 0.0, -1.0);
  for (int j = 0; j < 3; ++j) {
    b.move_to(attitude_with_up(tilted(j, 1.0), heading(rng)), o.move);
    b.rest(o.pause);
    // The turn: about the vertical by the declared angle plus the hand's error, while the axis
    // leans out and back in the body (a body-axis rotation there and back: uneven rates).
    const double angle = o.turn_angle + o.turn_angle_error * normal(rng);
    Eigen::Vector3d lean = Eigen::Vector3d::Unit((j + 1) % 3) * normal(rng) +
                           Eigen::Vector3d::Unit((j + 2) % 3) * normal(rng);
    if (lean.norm() < 1e-9) lean = Eigen::Vector3d::Unit((j + 1) % 3);
    const double half = 0.5 * o.turn;
    const double t0 = b.t;
    for (int h = 0; h < 2; ++h) {
      MotionSegment s;
      s.t0 = b.t;
      s.t1 = b.t + half;
      s.C_b_n_start = b.C;
      s.axis_n = up_n;
      s.alpha =
          TrapezoidProfile::by_duration(0.5 * angle, half, 8.0 * std::abs(angle) / (half * half));
      s.axis_b = lean.normalized();
      s.beta = TrapezoidProfile::by_duration(h == 0 ? o.wobble : -o.wobble, half,
                                             8.0 * o.wobble / (half * half) + 1e-9);
      b.segments.push_back(s);
      b.t = s.t1;
      b.C = s.C_b_n_end();
    }
    parts.push_back({kTurns[j], t0 - o.label_margin, b.t + o.label_margin});
    b.rest(o.pause);
  }
  FerrarisSession out{Motion(site, std::move(b.segments), {}), std::move(parts)};
  return out;
}

}  // namespace sinscal
