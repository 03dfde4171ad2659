#include "filter/table_free/handheld_run.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <stdexcept>

#include "models/attitude.hpp"
#include "models/config.hpp"

namespace sinscal {

namespace {

// A triad's nominal conversion as a raw-count scaling per body axis: the reader computes
// value_i = sign_i (raw - offset) scale, so raw = (sign_i / scale) value_i + offset.
void nominal_of(const TriadColumns& c, bool& counts, Eigen::Vector3d& sensitivity,
                Eigen::Vector3d& offset, std::array<int, 3>& log_axis) {
  log_axis = c.axis;
  counts = c.counts && !c.increments;
  sensitivity.setOnes();
  offset.setZero();
  if (!counts) return;
  for (int i = 0; i < 3; ++i) {
    sensitivity(i) = c.sign[static_cast<std::size_t>(i)] / c.scale;
    offset(i) = c.offset;
  }
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

std::string normal(const std::string& path) {
  return path.empty() ? path : std::filesystem::path(path).lexically_normal().string();
}

// The log's files, each path in its normal form (config/x/../../data/a.csv: data/a.csv).
std::string describe(const LogFormat& log) {
  if (log.split()) return normal(log.accel_file) + " + " + normal(log.gyro_file);
  if (!log.segments.empty()) return log.file;
  return normal(log.file);
}

double rms(const std::vector<double>& v) {
  if (v.empty()) return 0.0;
  double s = 0.0;
  for (double x : v) s += x * x;
  return std::sqrt(s / static_cast<double>(v.size()));
}

}  // namespace

std::vector<ImuReading> HandheldRecord::detector_readings() const {
  return raw() ? counts_from_readings(readings, nominal, false) : readings;
}

HandheldRecord read_handheld_record(const LogFormat& log) {
  HandheldRecord r;
  r.file = describe(log);
  LogReader reader(log);
  ImuSample s;
  while (reader.next(s)) r.samples.push_back(s);
  if (r.samples.empty()) throw LogError(log.file, 0, "the log has no samples");
  r.readings = readings_from_samples(r.samples);
  nominal_of(log.accel, r.accel_counts, r.nominal.accel_sensitivity, r.nominal.accel_offset,
             r.accel_log_axis);
  nominal_of(log.gyro, r.gyro_counts, r.nominal.gyro_sensitivity, r.nominal.gyro_offset,
             r.gyro_log_axis);
  return r;
}

std::vector<HandheldPose> handheld_poses(const HandheldRecord& record,
                                         const PoseDetection& detection) {
  std::vector<HandheldPose> out;
  for (const Pose& p : detection.poses) {
    HandheldPose h;
    h.pose = p;
    reading_statistics(record.readings, p.first, p.last, h.accel_mean, h.gyro_mean, h.accel_std,
                       h.gyro_std);
    out.push_back(h);
  }
  return out;
}

TableFreeRun run_table_free(const Session& s, const TableFreeRunOptions& o) {
  TableFreeRun run;
  run.session = normal(s.path);
  run.name = s.name;
  run.log = describe(s.log);
  run.options = o.calibration;
  run.detector = o.detector;
  run.has_site = s.has_site;
  run.site = s.site;
  if (s.has_site)
    run.options.site = s.site;
  else
    run.options.site.reset();
  if (o.gravity > 0.0) {
    run.options.gravity = o.gravity;
    run.gravity_from = "given";
  } else if (s.gravity > 0.0) {
    run.options.gravity = s.gravity;
    run.gravity_from = "session";
  } else if (s.has_site) {
    run.options.gravity = 0.0;
    run.gravity_from = "normal gravity at the site";
  } else {
    throw ConfigError(s.path +
                      ": no local gravity: the session has neither [site] gravity nor a site "
                      "(latitude) for the normal gravity, and none was given");
  }
  const HandheldRecord rec = read_handheld_record(s.log);
  run.samples = rec.samples.size();
  run.duration = rec.samples.back().t - rec.samples.front().t;
  run.accel_counts = rec.accel_counts;
  run.gyro_counts = rec.gyro_counts;
  run.nominal = rec.nominal;
  run.accel_log_axis = rec.accel_log_axis;
  run.gyro_log_axis = rec.gyro_log_axis;
  const std::vector<ImuReading> detector_in = rec.detector_readings();
  try {
    run.detection = detect_poses(detector_in, o.detector);
  } catch (const PoseDetectorError& e) {
    throw TableFreeError(TableFreeError::Kind::BadInput, run.log + ": " + e.what());
  }
  run.poses = handheld_poses(rec, run.detection);
  run.readings = rec.raw() ? si_from_counts(detector_in, rec.nominal) : rec.readings;
  if (o.before_fit) o.before_fit(rec, run);
  try {
    run.result =
        rec.raw() ? calibrate_table_free_counts(detector_in, rec.nominal, run.options, o.detector)
                  : calibrate_table_free(rec.readings, run.detection.poses, run.options);
  } catch (const TableFreeError& e) {
    std::string hint;
    if (e.kind() == TableFreeError::Kind::TooFewPoses && o.detector.use_gyro) {
      // The gyros may see a hand's tremor where the accelerometers see a pose.
      PoseDetectorOptions accel_only = o.detector;
      accel_only.use_gyro = false;
      try {
        const std::size_t n = detect_poses(detector_in, accel_only).poses.size();
        if (n > run.detection.poses.size())
          hint = "; the accelerometers alone find " + std::to_string(n) +
                 " poses: the gyros move at rest (a unit held in the hand?): --pose-accel-only, "
                 "or pose_accel_only = true in the session's [table_free]";
      } catch (const PoseDetectorError&) {
      }
    }
    throw TableFreeError(e.kind(), run.log + ": " + e.what() + hint);  // names the log
  }
  return run;
}

namespace {

// A validation record's readings, nominal or corrected with the calibration's whole model (any
// extended terms a diagnosis added; time-dependent terms from the record's start).
struct Corrector {
  const ImuErrorModel& m;
  double t0;
  std::pair<Eigen::Vector3d, Eigen::Vector3d> correct(const Eigen::Vector3d& yg,
                                                      const Eigen::Vector3d& ya, double t,
                                                      bool calibrated) const {
    std::pair<Eigen::Vector3d, Eigen::Vector3d> wf{yg, ya};
    if (calibrated) m.compensate(yg, ya, Eigen::Vector3d::Zero(), wf.first, wf.second, t - t0);
    return wf;
  }
  Eigen::Vector3d accel(const Eigen::Vector3d& ya, const Eigen::Vector3d& yg, double t,
                        bool calibrated) const {
    return correct(yg, ya, t, calibrated).second;
  }
  Eigen::Vector3d gyro(const Eigen::Vector3d& yg, const Eigen::Vector3d& ya, double t,
                       bool calibrated) const {
    return correct(yg, ya, t, calibrated).first;
  }
};

struct PoseMean {
  Eigen::Vector3d f, w;
  double t;
};

// Each turn: the gyro rates integrated from the end of one pose to the start of the next (each
// reading's rate over its interval) turn the gravity direction of the first pose into the one
// the accelerometers see in the next.
void validation_turns(const std::vector<ImuReading>& si, const PoseDetection& detection,
                      const std::vector<PoseMean>& means, const Corrector& c,
                      HandheldValidation& out) {
  std::vector<double> t_n, t_c;
  for (std::size_t p = 0; p + 1 < detection.poses.size(); ++p) {
    ValidationTurn vt;
    vt.from = detection.poses[p].index;
    for (const bool calibrated : {false, true}) {
      Eigen::Matrix3d C = Eigen::Matrix3d::Identity();
      for (std::size_t k = detection.poses[p].last + 1; k <= detection.poses[p + 1].first; ++k)
        C = C * dcm_from_rotvec(c.gyro(si[k].gyro, si[k].accel, si[k].t, calibrated) *
                                (si[k].t - si[k - 1].t));
      const PoseMean &a = means[p], &b = means[p + 1];
      const Eigen::Vector3d u0 = c.accel(a.f, a.w, a.t, calibrated).normalized();
      const Eigen::Vector3d u1 = c.accel(b.f, b.w, b.t, calibrated).normalized();
      const double e = angle_between(C.transpose() * u0, u1);
      (calibrated ? vt.error_calibrated : vt.error_nominal) = e;
      (calibrated ? t_c : t_n).push_back(e);
      if (calibrated) vt.angle = rotvec_from_dcm(C).norm();
    }
    out.turns.push_back(vt);
  }
  out.turn_rms_nominal = rms(t_n);
  out.turn_rms_calibrated = rms(t_c);
}

}  // namespace

HandheldValidation validate_table_free(const Session& v, const TableFreeRun& run,
                                       const PoseDetectorOptions& detector) {
  const HandheldRecord rec = read_handheld_record(v.log);
  if (rec.accel_counts != run.accel_counts || rec.gyro_counts != run.gyro_counts ||
      rec.accel_log_axis != run.accel_log_axis || rec.gyro_log_axis != run.gyro_log_axis)
    throw std::invalid_argument(
        v.path +
        ": the validation log's triads are not logged as the calibration session's (raw counts "
        "or not, the same axes): its readings cannot take that calibration");
  // The readings through the calibration session's nominal conversion: the calibration is
  // relative to it.
  const std::vector<ImuReading> si =
      rec.raw() ? si_from_counts(rec.detector_readings(), run.nominal) : rec.readings;
  const PoseDetection detection = detect_poses(rec.detector_readings(), detector);
  HandheldValidation out;
  out.session = normal(v.path);
  out.name = v.name;
  out.samples = rec.samples.size();
  out.duration = rec.samples.back().t - rec.samples.front().t;
  const Corrector c{run.result.model, si.front().t};
  const double g = run.result.gravity;
  std::vector<double> ge_n, ge_c, r_n, r_c;
  std::vector<PoseMean> means;
  for (const Pose& p : detection.poses) {
    Eigen::Vector3d f, w, fs, ws;
    reading_statistics(si, p.first, p.last, f, w, fs, ws);
    const double tm = 0.5 * (si[p.first].t + si[p.last].t);
    means.push_back({f, w, tm});
    ValidationPose vp;
    vp.index = p.index;
    vp.t_start = p.t_start;
    vp.t_end = p.t_end;
    vp.gravity_error_nominal = c.accel(f, w, tm, false).norm() - g;
    vp.gravity_error_calibrated = c.accel(f, w, tm, true).norm() - g;
    vp.rate_nominal = c.gyro(w, f, tm, false).norm();
    vp.rate_calibrated = c.gyro(w, f, tm, true).norm();
    ge_n.push_back(vp.gravity_error_nominal);
    ge_c.push_back(vp.gravity_error_calibrated);
    r_n.push_back(vp.rate_nominal);
    r_c.push_back(vp.rate_calibrated);
    out.poses.push_back(vp);
  }
  validation_turns(si, detection, means, c, out);
  out.gravity_rms_nominal = rms(ge_n);
  out.gravity_rms_calibrated = rms(ge_c);
  out.rate_rms_nominal = rms(r_n);
  out.rate_rms_calibrated = rms(r_c);
  return out;
}

namespace {

// Block means of a record in at most kAllanBlockReadings readings: when full, pairs are merged
// and the block doubles (entry j covers samples [j block, (j + 1) block)).
class BlockMeans {
 public:
  explicit BlockMeans(AllanRecord& rec) : rec_(rec) {}
  void add(const ImuReading& r) {
    sum_.t += r.t;
    sum_.accel += r.accel;
    sum_.gyro += r.gyro;
    if (++in_ == rec_.block) flush();
  }
  void flush() {
    if (in_ == 0) return;
    if (rec_.readings.size() == kAllanBlockReadings) merge();
    const double w = 1.0 / static_cast<double>(in_);
    rec_.readings.push_back({sum_.t * w, sum_.accel * w, sum_.gyro * w});
    sum_ = ImuReading{};
    in_ = 0;
  }

 private:
  void merge() {
    auto& r = rec_.readings;
    for (std::size_t j = 0; j < r.size() / 2; ++j)
      r[j] = {0.5 * (r[2 * j].t + r[2 * j + 1].t), 0.5 * (r[2 * j].accel + r[2 * j + 1].accel),
              0.5 * (r[2 * j].gyro + r[2 * j + 1].gyro)};
    r.resize(r.size() / 2);
    rec_.block *= 2;
    // The block under way holds the samples after the merged ones: it now ends at the new size.
  }
  AllanRecord& rec_;
  ImuReading sum_;
  std::size_t in_ = 0;
};

// What a pass over the log feeds the Allan deviation: rates of a log of rates at the median
// interval of the first 2^20 (found at the end), increments at their constant interval. The
// first AllanError (a varying interval) is kept and thrown after the gate.
class AllanFeed {
 public:
  AllanFeed(const LogFormat& log, const AllanOptions& o)
      : rates_(!log.gyro.increments && !log.accel.increments), stream_(o) {}
  void add(const ImuSample& s, const ImuReading& r) {
    if (!error_.empty()) return;
    if (stream_.samples() > 0 && dts_.size() < (std::size_t{1} << 20)) dts_.push_back(s.t - t_);
    t_ = s.t;
    try {
      if (rates_)
        stream_.add_rates(r.gyro, r.accel);
      else
        stream_.add(s);
    } catch (const AllanError& e) {
      error_ = e.what();
    }
  }
  AllanAnalysis analysis() {
    if (!error_.empty()) throw AllanError(error_);
    double tau0 = stream_.first_interval();
    if (rates_ && !dts_.empty()) {
      std::nth_element(dts_.begin(), dts_.begin() + static_cast<std::ptrdiff_t>(dts_.size() / 2),
                       dts_.end());
      tau0 = dts_[dts_.size() / 2];
    }
    return stream_.analysis(tau0);
  }
  std::size_t memory_bytes() const {
    return stream_.memory_bytes() + dts_.capacity() * sizeof(double);
  }

 private:
  bool rates_;
  AllanStream stream_;
  std::vector<double> dts_;
  double t_ = 0.0;
  std::string error_;
};

ImuReading reading_of(const ImuSample& s) {
  if (!(s.dt > 0.0)) throw std::invalid_argument("sample interval must be positive");
  return {s.t, s.dv_b / s.dt, s.dtheta_b / s.dt};
}

// Pass 1: the block means, the count and times, and the whole record into `feed` when given.
AllanRecord read_allan_record(const LogFormat& log, AllanFeed* feed) {
  AllanRecord rec;
  rec.file = describe(log);
  nominal_of(log.accel, rec.accel_counts, rec.nominal.accel_sensitivity, rec.nominal.accel_offset,
             rec.accel_log_axis);
  nominal_of(log.gyro, rec.gyro_counts, rec.nominal.gyro_sensitivity, rec.nominal.gyro_offset,
             rec.gyro_log_axis);
  LogReader reader(log);
  BlockMeans means(rec);
  ImuSample s;
  while (reader.next(s)) {
    const ImuReading r = reading_of(s);
    if (rec.count++ == 0) rec.t_first = s.t;
    rec.t_last = s.t;
    means.add(r);
    if (feed) feed->add(s, r);
  }
  means.flush();
  if (rec.count == 0) throw LogError(log.file, 0, "the log has no samples");
  return rec;
}

// Pass 2: samples [first, last] of the log into `feed`; their first and last times.
void feed_stretch(const LogFormat& log, std::size_t first, std::size_t last, AllanFeed& feed,
                  AllanRun& out) {
  LogReader reader(log);
  ImuSample s;
  for (std::size_t k = 0; k <= last && reader.next(s); ++k) {
    if (k < first) continue;
    if (k == first) out.t_start = s.t;
    out.t_end = s.t;
    feed.add(s, reading_of(s));
  }
}

// The pose the options select (its readings' indices), or none for the whole record.
const Pose* selected_pose(const AllanRunOptions& o, const PoseDetection& detection,
                          const std::string& log) {
  if (o.selection == AllanSelection::All) return nullptr;
  if (detection.poses.empty()) throw PoseDetectorError(log + ": no static pose found");
  if (o.selection == AllanSelection::LongestPose)
    return &*std::max_element(
        detection.poses.begin(), detection.poses.end(),
        [](const Pose& a, const Pose& b) { return a.duration() < b.duration(); });
  if (o.pose < 1 || o.pose > static_cast<int>(detection.poses.size()))
    throw std::invalid_argument(log + ": pose " + std::to_string(o.pose) +
                                " does not exist: the detector found " +
                                std::to_string(detection.poses.size()) + " poses (1 to " +
                                std::to_string(detection.poses.size()) + ")");
  return &detection.poses[static_cast<std::size_t>(o.pose - 1)];
}

// Detects the poses and judges the whole record: static when one pose covers (nearly) all of
// it (several poses covering most of it are a record with moves between them, which would
// dominate its Allan deviation).
PoseDetection judge_record(const AllanRecord& rec, const AllanRunOptions& o, AllanRun& out) {
  const double duration = rec.t_last - rec.t_first;
  PoseDetection detection;
  bool detected = false;
  std::string undetected;
  try {
    detection = detect_poses(rec.detector_readings(), o.detector);
    detected = true;
  } catch (const PoseDetectorError& e) {
    if (o.selection != AllanSelection::All) throw;
    undetected = e.what();
  }
  out.poses_found = detected ? static_cast<int>(detection.poses.size()) : -1;
  double longest = 0.0;
  for (const Pose& p : detection.poses) longest = std::max(longest, p.duration());
  out.static_fraction = duration > 0.0 ? longest / duration : 0.0;
  if (o.selection == AllanSelection::All && out.static_fraction < 0.9) {
    out.warning = "the record is not static: its longest static pose covers " +
                  std::to_string(static_cast<int>(std::round(100.0 * out.static_fraction))) +
                  " % of it (" + std::to_string(std::max(out.poses_found, 0)) +
                  " poses found); --longest-pose or --pose N analyses one pose";
    if (!detected)
      out.warning = "whether the record is static cannot be told (" + undetected +
                    "): it is too short for the pose detector";
    if (o.require_static) throw std::invalid_argument(out.log + ": " + out.warning);
  }
  return detection;
}

}  // namespace

AllanRun run_allan(const Session& s, const AllanRunOptions& o) {
  AllanRun out;
  out.session = normal(s.path);
  out.name = s.name;
  out.log = describe(s.log);
  out.selection = o.selection;
  const bool whole = o.selection == AllanSelection::All;
  AllanFeed feed(s.log, o.allan);
  const AllanRecord rec = read_allan_record(s.log, whole ? &feed : nullptr);
  out.block = rec.block;
  if (rec.count < kAllanMinSamples)
    throw AllanError(
        out.log + ": the record is too short for an Allan deviation: " + std::to_string(rec.count) +
        " samples over " + std::to_string(rec.t_last - rec.t_first) + " s (" +
        std::to_string(kAllanMinSamples) + " at least)");
  const PoseDetection detection = judge_record(rec, o, out);
  const Pose* pose = selected_pose(o, detection, out.log);
  std::size_t first = 0, last = rec.readings.size() - 1;
  out.t_start = rec.t_first;
  out.t_end = rec.t_last;
  if (pose) {
    out.pose = pose->index;
    first = pose->first;
    last = pose->last;
  }
  if (o.before_analysis)
    o.before_analysis(
        rec, std::vector<ImuReading>(rec.readings.begin() + static_cast<std::ptrdiff_t>(first),
                                     rec.readings.begin() + static_cast<std::ptrdiff_t>(last) + 1));
  if (pose) {
    out.passes = 2;
    feed_stretch(s.log, first * rec.block, std::min((last + 1) * rec.block, rec.count) - 1, feed,
                 out);
  }
  out.memory_bytes = feed.memory_bytes();
  out.analysis = feed.analysis();
  return out;
}

}  // namespace sinscal
