#include "apophis_like.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <stdexcept>
#include <string>

#include "models/attitude.hpp"
#include "models/earth.hpp"
#include "models/units.hpp"

namespace sinscal::test {

namespace {

// The true motion on a fine grid: rate about the body (rad/s) and attitude, phase by phase.
struct Truth {
  std::vector<Eigen::Vector3d> omega_b;
  std::vector<Eigen::Matrix3d> C_b_n;
};

constexpr double kStep = 1e-3;  // s

void append_turn(const ApophisPhase& p, Eigen::Matrix3d& C, Truth& t) {
  const double ramp = p.rate / p.accel;
  const double total = 2.0 * ramp + p.hold;
  for (double s = 0.0; s < total; s += kStep) {
    const double r = s < ramp ? p.accel * s : (s > ramp + p.hold ? p.accel * (total - s) : p.rate);
    t.omega_b.push_back(r * p.axis_b);
    t.C_b_n.push_back(C);
    C = C * rotation(p.axis_b, r * kStep);
  }
}

Truth truth_of(const ApophisLike& spec) {
  Truth t;
  Eigen::Matrix3d C = spec.C_b_n_start;
  for (const auto& p : spec.phases) {
    if (p.rest > 0.0) {
      for (double s = 0.0; s < p.rest; s += kStep) {
        t.omega_b.push_back(Eigen::Vector3d::Zero());
        t.C_b_n.push_back(C);
      }
      continue;
    }
    append_turn(p, C, t);
  }
  return t;
}

}  // namespace

std::string write_apophis_like(const std::string& dir, const ApophisLike& spec) {
  const Truth truth = truth_of(spec);
  std::mt19937 rng(spec.seed);
  std::uniform_real_distribution<double> interval(1.0 / spec.max_hz, 1.0 / spec.min_hz);
  std::normal_distribution<double> unit(0.0, 1.0);
  std::bernoulli_distribution flip(spec.toggle_flip);
  const double gyro_white = spec.gyro_white > 0.0 ? spec.gyro_white : 0.05 * units::deg_per_s;
  const double accel_white = spec.accel_white > 0.0 ? spec.accel_white : 1e-3 * units::g0;
  const Eigen::Vector3d& gyro_bias = spec.gyro_bias;
  const Eigen::Vector3d& accel_bias = spec.accel_bias;
  const Eigen::Vector3d f_n(0.0, 0.0, -units::g0);
  std::ofstream log(dir + "/log.csv");
  log << (spec.time_column ? "t,ax,ay,az,gx,gy,gz\n" : "ax,ay,az,gx,gy,gz\n");
  bool high[3] = {false, false, false};
  for (double t = 0.0;; t += interval(rng)) {
    const auto k = static_cast<std::size_t>(t / kStep);
    if (k >= truth.omega_b.size()) break;
    Eigen::Vector3d w = truth.omega_b[k] + gyro_bias + spec.gyro_drift * t +
                        truth.C_b_n[k].transpose() * spec.omega_ie_n;
    Eigen::Vector3d f = truth.C_b_n[k].transpose() * f_n;
    w += spec.gyro_cross_asym * truth.omega_b[k].cwiseAbs();
    for (const auto& st : spec.steps)
      if (t >= st.from && t < st.to) {
        w += st.gyro;
        f += st.accel;
      }
    f += spec.accel_error * f + accel_bias;
    for (int i = 0; i < 3; ++i) {
      w(i) += gyro_white * unit(rng);
      f(i) += accel_white * unit(rng);
    }
    if (spec.toggling) {
      // The y level's draw first (the sequence of the default spec), then x's and z's if they
      // toggle.
      if (flip(rng)) high[1] = !high[1];
      for (const int i : {0, 2})
        if (spec.gyro_toggle(i) != 0.0 && flip(rng)) high[i] = !high[i];
      for (int i = 0; i < 3; ++i) w(i) += high[i] ? spec.gyro_toggle(i) : 0.0;
      f.y() += high[1] ? 0.018 * units::g0 : 0.0;
    }
    if (spec.time_column) {
      char stamp[40];
      std::snprintf(stamp, sizeof stamp, "%.6f,", t);
      log << stamp;
    }
    char line[200];
    std::snprintf(line, sizeof line, "%.7f,%.7f,%.7f,%.6f,%.6f,%.6f\n", f.x() / units::g0,
                  f.y() / units::g0, f.z() / units::g0, w.x() / units::deg_per_s,
                  w.y() / units::deg_per_s, w.z() / units::deg_per_s);
    log << line;
  }
  std::ofstream session(dir + "/session.ini");
  session << "[session]\nname = apophis-like\nrate = 15 Hz\n";
  if (!spec.plan_text.empty()) {
    std::ofstream(dir + "/plan.ini") << spec.plan_text;
    session << "plan = plan.ini\n";
  }
  if (!spec.sensor_text.empty()) {
    std::ofstream(dir + "/sensor.ini") << spec.sensor_text;
    session << "sensor = sensor.ini\n";
  }
  if (spec.plan_text.empty()) session << "\n[site]\ngravity = 9.80665 m/s^2\n";
  session << "\n[log]\nfile = log.csv\nformat = custom\nheader_lines = 1\ncolumns = "
          << (spec.time_column ? "t " : "")
          << "ax ay az gx gy gz\ngyro = rate\ngyro_unit = deg/s\naccel = rate\n"
             "accel_unit = g\n";
  return dir + "/session.ini";
}

std::string bmi160_profile_text() {
  return "[sensor]\nname = bmi160\n\n[gyro]\nbias = 0 3 deg/s\nscale = 0 40000 ppm\n"
         "misalignment = 0 3600 arcsec\ng_sensitivity = 0 0.1 deg/s/g\narw = 0.42 deg/sqrt(h)\n"
         "range = 2000 deg/s\n\n[accel]\nbias = 0 80 mg\nscale = 0 40000 ppm\n"
         "misalignment = 0 3600 arcsec\nvrw = 180 ug/sqrt(Hz)\nrange = 16 g\n";
}

namespace {
// The plan of apophis_rate_test(): its revolutions put the attitude at every segment where the
// generated one is.
const char* const kRateTestPlan =
    "[plan]\nname = apophis-like-rate-test\ntype = rotations\nconvention = ned-frd\n"
    "rotation_acceleration = 25 deg/s^2\n\n[site]\nlatitude = 28.6 deg\n\n"
    "[start]\nheading = 0 deg\npitch = 0 deg\nroll = 180 deg\ndwell = 30 s\n\n"
    "[rotations]\naxes = -z +z +y -y -x +x\nrate = 25 deg/s\nrevolutions = 3\n"
    "pauses = 0 30 0 30 0 30 s\n";

const char* const kZTurnsPlan =
    "[plan]\nname = apophis-like-rate\ntype = rotations\nconvention = ned-frd\n"
    "rotation_acceleration = 25 deg/s^2\n\n[site]\nlatitude = 28.6 deg\n\n"
    "[start]\nheading = 0 deg\npitch = 0 deg\nroll = 180 deg\ndwell = 8 s\n\n"
    "[rotations]\naxes = -z +z\nrate = 25 deg/s\nholds = 40 40 s\npauses = 0 15 s\n";
}  // namespace

ApophisLike apophis_rate_test() {
  ApophisLike spec;
  const double rate = 25.0 * units::deg_per_s, accel = 25.0 * units::deg_per_s;
  const double hold = 3.0 * 2.0 * M_PI / rate - rate / accel;
  spec.phases.push_back(rest_phase(30.0));
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ(), y = Eigen::Vector3d::UnitY(),
                        x = Eigen::Vector3d::UnitX();
  for (const Eigen::Vector3d& a :
       {Eigen::Vector3d(-z), z, y, Eigen::Vector3d(-y), Eigen::Vector3d(-x), x}) {
    spec.phases.push_back(turn_phase(a, rate, accel, hold));
    if (a == z || a == -y || a == x) spec.phases.push_back(rest_phase(30.0));
  }
  // Every gyro toggles (each its own level), runs of 10 readings on average at one level: the
  // means' autocorrelation time is about 7 readings (segments of 400-600 readings).
  spec.gyro_toggle.setConstant(1.02 * units::deg_per_s);
  spec.toggle_flip = 0.1;
  spec.gyro_white = 0.3 * units::deg_per_s;
  spec.plan_text = kRateTestPlan;
  spec.seed = 3;
  return spec;
}

ApophisLike apophis_rate_test_short() {
  ApophisLike spec = apophis_rate_test();
  for (auto& p : spec.phases)
    if (p.rest > 0.0) p.rest = 10.0;
  spec.toggle_flip = 0.05;
  const auto replace = [&spec](const std::string& from, const std::string& to) {
    spec.plan_text.replace(spec.plan_text.find(from), from.size(), to);
  };
  replace("dwell = 30 s", "dwell = 10 s");
  replace("pauses = 0 30 0 30 0 30 s", "pauses = 0 10 0 10 0 10 s");
  return spec;
}

namespace {
// The orientation plan of a tumble's rests: each rest's generated attitude as heading, pitch and
// roll (NED-FRD), on a three-axis table.
std::string tumble_plan_text(const ApophisLike& spec, double lat_deg, double dwell) {
  std::string text =
      "[plan]\nname = apophis-like-tumble\ntype = orientations\nconvention = ned-frd\n"
      "move_rate = 10 deg/s\nmove_acceleration = 10 deg/s^2\n\n[table]\naxes = 3\n\n[site]\n"
      "latitude = " +
      std::to_string(lat_deg) + " deg\n";
  const Truth truth = truth_of(spec);  // the attitude in the middle of each rest, as generated
  std::size_t at = 0;
  int k = 0;
  for (const auto& p : spec.phases) {
    const double seconds = p.rest > 0.0 ? p.rest : 2.0 * p.rate / p.accel + p.hold;
    const std::size_t middle = at + static_cast<std::size_t>(0.5 * seconds / kStep);
    at += static_cast<std::size_t>(std::round(seconds / kStep));
    if (!(p.rest > 0.0)) continue;
    const Eigen::Matrix3d& C = truth.C_b_n[std::min(middle, truth.C_b_n.size() - 1)];
    const EulerAngles e = euler_from_C_b_n(AngleConvention::NedFrd, C);
    char block[200];
    std::snprintf(block, sizeof block,
                  "\n[orientation.%d]\nheading = %.9f deg\npitch = %.9f deg\nroll = %.9f "
                  "deg\ndwell = %.0f s\n",
                  ++k, e.heading / units::deg, e.pitch / units::deg, e.roll / units::deg, dwell);
    text += block;
  }
  return text;
}
}  // namespace

ApophisLike apophis_tumble() {
  ApophisLike spec;
  const double rate = 10.0 * units::deg_per_s, accel = 10.0 * units::deg_per_s, dwell = 40.0;
  const auto move = [&](const Eigen::Vector3d& axis, double angle_deg) {
    return turn_phase(axis, rate, accel, angle_deg * units::deg / rate - rate / accel);
  };
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY();
  spec.phases = {rest_phase(dwell), move(y, 90), rest_phase(dwell), move(y, 90),
                 rest_phase(dwell), move(y, 90), rest_phase(dwell), move(y, 90),
                 rest_phase(dwell), move(x, 90), rest_phase(dwell), move(x, 180),
                 rest_phase(dwell), move(x, 90), rest_phase(dwell)};
  spec.min_hz = 12.5;  // a mean interval of 1/15 s: the readings' index at 15 Hz is their time
  spec.max_hz = 18.75;
  spec.toggling = false;
  spec.gyro_drift = Eigen::Vector3d(-0.0104, 0.0, -0.0022) * units::deg_per_s / 100.0;
  const double lat_deg = 28.6;
  spec.omega_ie_n = Earth::wgs84().omega_ie_n(lat_deg * units::deg);
  spec.plan_text = tumble_plan_text(spec, lat_deg, dwell);
  return spec;
}

std::pair<double, double> rest_window(const ApophisLike& spec, int k) {
  double t = 0.0;
  int rests = 0;
  for (const auto& p : spec.phases) {
    const double seconds = p.rest > 0.0 ? p.rest : 2.0 * p.rate / p.accel + p.hold;
    if (p.rest > 0.0 && ++rests == k) return {t, t + seconds};
    t += seconds;
  }
  throw std::invalid_argument("rest_window: no rest " + std::to_string(k));
}

ApophisLike apophis_tumble_step(int rest, double step) {
  ApophisLike spec = apophis_tumble();
  const auto [from, to] = rest_window(spec, rest);
  LevelStep s;
  s.from = 0.5 * (from + to);
  s.to = to;
  s.gyro.y() = step;
  spec.steps.push_back(s);
  return spec;
}

ApophisLike apophis_z_turns() {
  ApophisLike spec;
  const double rate = 25.0 * units::deg_per_s, accel = 25.0 * units::deg_per_s;
  spec.phases = {rest_phase(8.0), turn_phase(-Eigen::Vector3d::UnitZ(), rate, accel, 40.0),
                 turn_phase(Eigen::Vector3d::UnitZ(), rate, accel, 40.0), rest_phase(15.0)};
  spec.toggling = false;  // white noise at the data sheet's densities (per reading at 15 Hz)
  spec.gyro_white = 0.007 * units::deg_per_s * std::sqrt(15.0);
  spec.accel_white = 180.0 * units::ug * std::sqrt(15.0);
  spec.plan_text = kZTurnsPlan;
  spec.sensor_text = bmi160_profile_text();
  return spec;
}

ApophisLike apophis_hand_tumble(bool time_column) {
  ApophisLike spec;
  const double rate = 45.0 * units::deg_per_s, accel = 45.0 * units::deg_per_s;
  const double hold = M_PI / 2.0 / rate - rate / accel;  // 90 deg
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY();
  spec.phases.push_back(rest_phase(6.0));
  for (int k = 0; k < 14; ++k) {
    spec.phases.push_back(turn_phase((k / 3) % 2 == 0 ? x : y, rate, accel, hold));
    spec.phases.push_back(rest_phase(6.0));
  }
  spec.toggling = false;
  spec.gyro_bias = Eigen::Vector3d(0.2, -0.1, 0.15) * units::deg_per_s;
  spec.accel_bias = Eigen::Vector3d(0.01, -0.02, 0.015) * units::g0;
  spec.time_column = time_column;
  if (!time_column) {
    spec.min_hz = 9.0;
    spec.max_hz = 12.0;
  }
  spec.seed = 5;
  return spec;
}

}  // namespace sinscal::test
