// Sessions generated with the structure of the APOPHIS BMI160 table logs (issue 34): readings at an
// irregular 12-18 Hz logged without a time column (the session states 15 Hz), rests whose outputs
// toggle between two levels (the log's gyro y by about 1 deg/s, its accelerometer y by 18 mg) on
// top of white noise, constant-rate turns and moves of a table between rests. Written to disk in
// the documented formats (docs/formats.md): session.ini, plan.ini, sensor.ini, log.csv.
#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace sinscal::test {

/// One phase of the generated motion: a rest, or a turn about a body axis (unit, signed) at
/// `rate` (rad/s) reached and left at `accel` (rad/s^2), holding the rate for `hold` s.
struct ApophisPhase {
  double rest = 0.0;  // s at rest (a rest when > 0)
  Eigen::Vector3d axis_b = Eigen::Vector3d::UnitZ();
  double rate = 0.0, accel = 0.0, hold = 0.0;
};

inline ApophisPhase rest_phase(double seconds) {
  ApophisPhase p;
  p.rest = seconds;
  return p;
}
inline ApophisPhase turn_phase(const Eigen::Vector3d& axis_b, double rate, double accel,
                               double hold) {
  ApophisPhase p;
  p.axis_b = axis_b;
  p.rate = rate;
  p.accel = accel;
  p.hold = hold;
  return p;
}

/// A level change of the outputs from `from` to `to` s of true time: added to the gyros (rad/s)
/// and the accelerometers (m/s^2), as board 3's last rest shows in its gyro y.
struct LevelStep {
  double from = 0.0, to = 0.0;
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero(), accel = Eigen::Vector3d::Zero();
};

struct ApophisLike {
  std::vector<ApophisPhase> phases;
  Eigen::Matrix3d C_b_n_start = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();  // z up
  double min_hz = 12.0, max_hz = 18.0;  // the readings' true rate: uniform in the interval
  bool toggling = true;                 // two-level gyro y and accel y outputs, as the log's
  double toggle_flip = 0.3;  // probability per reading that the two-level outputs switch level
  /// Each gyro's toggle step (rad/s; the log's: gyro y 1.02 deg/s), each axis its own level; the
  /// accelerometer y switches with the gyro y.
  Eigen::Vector3d gyro_toggle = Eigen::Vector3d(0.0, 1.02, 0.0) * (M_PI / 180.0);
  double gyro_white = 0.0;   // rad/s per reading (0: as the log's, 0.05 deg/s)
  double accel_white = 0.0;  // m/s^2 per reading (0: as the log's, 1 mg)
  /// The sensors' biases (rad/s, m/s^2; the log's size by default).
  Eigen::Vector3d gyro_bias = Eigen::Vector3d(-1.27, 0.38, -1.15) * (M_PI / 180.0);
  Eigen::Vector3d accel_bias = Eigen::Vector3d(-0.03, 0.05, -0.02) * 9.80665;
  /// The accelerometers' scale factors and misalignments: f = (I + accel_error) f_true + bias.
  Eigen::Matrix3d accel_error = Eigen::Matrix3d::Zero();
  /// Gyro i's output per |rate| about body axis j (i != j): an offset while turning across the
  /// axis that depends on the turn's direction, as the APOPHIS rate logs show (0: none).
  Eigen::Matrix3d gyro_cross_asym = Eigen::Matrix3d::Zero();
  /// The gyros' bias drift (rad/s^2) over the true time from the log's start, as the APOPHIS
  /// tumbles' rests show (0: none).
  Eigen::Vector3d gyro_drift = Eigen::Vector3d::Zero();
  /// The Earth rate in the navigation frame (rad/s, NED) the gyros sense (0: none).
  Eigen::Vector3d omega_ie_n = Eigen::Vector3d::Zero();
  std::vector<LevelStep> steps;  // level changes of the outputs (none: stationary rests)
  unsigned seed = 1;
  std::string plan_text;     // plan.ini (empty: none; a hand-held session with [site] gravity)
  std::string sensor_text;   // sensor.ini (empty: none in the session)
  bool time_column = false;  // a first column t: each reading's true time (s)
};

/// Writes the session into `dir`; returns the path of its session.ini.
std::string write_apophis_like(const std::string& dir, const ApophisLike& spec);

/// The BMI160's data-sheet profile (docs/measured/apophis/bmi160.ini).
std::string bmi160_profile_text();

/// A rate test of the APOPHIS logs' structure: 30 s rests between +-25 deg/s turns of 3 whole
/// revolutions about z, y and x (z up), every gyro toggling between two levels 1.02 deg/s apart
/// (each switching on 10 % of the readings), white noise as the log's across the turning axis
/// (0.3 deg/s).
ApophisLike apophis_rate_test();

/// apophis_rate_test() with 10 s rests and runs of 20 readings at one level (each output switching
/// on 5 % of the readings: an autocorrelation time of about 14 readings with the white noise),
/// rests of about 150 readings, only about 10 times that long.
ApophisLike apophis_rate_test_short();

/// A six-face tumble of the APOPHIS tumble logs' structure on a three-axis table: 40 s rests at
/// z up, two x faces, z down, z up, two y faces and z up again (90 and 180 deg moves at 10 deg/s
/// about body y and x), readings at 12.5-18.75 Hz (15 Hz on average) without time, white noise
/// as the logs' (gyro 0.05 deg/s, accelerometer 1 mg per reading), the Earth rate at 28.6 deg
/// latitude, and the gyros' bias drifting as board 2's (x -0.0104, z -0.0022 deg/s per 100 s).
/// Its plan (orientations, from the generated attitudes) is in plan_text.
ApophisLike apophis_tumble();

/// The true start and end (s) of rest `k` (1-based) of `spec`.
std::pair<double, double> rest_window(const ApophisLike& spec, int k);

/// apophis_tumble() with gyro y's level changed by `step` (rad/s) from the middle of rest `rest`
/// (1-based) to its end: a rest that is not a rest (APOPHIS board 3's last rest).
ApophisLike apophis_tumble_step(int rest, double step);

/// Board 1's rate test about z (8 s at rest, -z and +z at 25 deg/s for 40 s each, 15 s at rest)
/// at the data sheet's white noise, with the BMI160 profile: turns that move no gravity.
ApophisLike apophis_z_turns();

/// A hand-held tumble of the APOPHIS logs' timing (issue 34, item 4): 15 rests of 6 s joined by
/// 90 deg turns at 45 deg/s about body x and y, no plan (`[site] gravity`), white noise only.
/// `time_column`: with the readings' true times (12-18 Hz: the irregular time the table-free fit
/// must refuse); without: readings at 9-12 Hz while the session states 15 Hz (the turns' timing
/// against gravity shows it).
ApophisLike apophis_hand_tumble(bool time_column);

}  // namespace sinscal::test
