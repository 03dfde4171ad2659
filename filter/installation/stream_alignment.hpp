// The alignment of a stream (calibrate --stream: standard input, read once). The batch run aligns
// from the means of all the plan's dwells, reading the log an extra time before the filter
// (installation.hpp); a stream cannot. Here the samples up to the end of the plan's first dwells
// are held in a bounded buffer as they arrive, the alignment is computed from those dwells' means
// (the same dwell_means and align), and the filter, started from it, reads the held samples
// again and then the rest of the stream. Memory: the buffer's capacity, whatever the log's
// length.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <exception>
#include <functional>
#include <vector>

#include "filter/installation/installation.hpp"
#include "models/units.hpp"
#include "rig/imu_sample.hpp"
#include "rig/io/log_io.hpp"
#include "rig/timeline.hpp"

namespace sinscal {

/// A stream aligns from the plan's first dwells, as few as determine the alignment: from the
/// third on (the fewest the alignment takes, installation.cpp), dwell by dwell, until the
/// alignment is valid and its base and mounting sigmas are below kStreamAlignmentSigma. (rot19's
/// first seven dwells are turned about one axis, which leaves the mounting about it and the base
/// about it apart undetermined; the eighth determines them, the ninth settles them.)
constexpr std::size_t kStreamAlignmentMinDwells = 3;
constexpr double kStreamAlignmentSigma = 0.05 * units::deg;
/// Samples held at most (3.9 MB; rot19 at 100 Hz: the first 9 dwells end at 302 s, 30,200
/// samples). Beyond (longer dwells, a higher rate) the stream is not aligned: it runs as before,
/// from the plan.
constexpr std::size_t kStreamAlignmentCapacity = 32768;

/// Whether a stream's alignment from its first dwells is determined well enough to start from.
inline bool stream_alignment_settled(const Alignment& a) {
  return a.valid && a.base_sigma_n.norm() < kStreamAlignmentSigma &&
         a.mounting_sigma_b.norm() < kStreamAlignmentSigma;
}

/// The alignment a stream's significance test sees (Alignment::significant): its sigmas times
/// sqrt(dwells). What the fit leaves unmodelled (the triads' own misalignments and scale factors
/// times gravity and the Earth rate) repeats from dwell to dwell of the same attitude family,
/// which the fit takes as independent: from rot19's first 9 dwells the base heading came out
/// 470 arcsec off at a sigma of 123 (3.8 sigma) on two sessions without any installation error,
/// and the stream started from it where the batch (19 dwells: 146 +- 75 arcsec) did not.
inline Alignment stream_alignment_judged(Alignment a) {
  const double inflate = std::sqrt(static_cast<double>(std::max(a.dwells, 1)));
  a.base_sigma_n *= inflate;
  a.mounting_sigma_b *= inflate;
  return a;
}

/// A source that first holds the samples of the plan's first dwells, then gives them again
/// followed by the rest of the stream.
class HeldStream : public SampleSource {
 public:
  /// `skip_bad_samples`: the source is a LogReader whose bad samples are skipped (reported to the
  /// callback of skip_bad_samples(), those met while holding as soon as it is set).
  HeldStream(SampleSource& source, std::size_t capacity, bool skip_bad_samples);
  /// Reads and holds samples until the first one past the end of the timeline's first `dwells`
  /// dwells (`margin` s inside their end; log time = plan time + `time_offset`), if not already
  /// held: called again with more dwells, it reads on. Stops early at the capacity, the input's
  /// end, a stop request or a read error (kept: thrown by next() after the held samples). True
  /// when the dwells were all held.
  bool hold(const PlanTimeline& timeline, std::size_t dwells, double time_offset, double margin,
            const std::atomic<bool>* stop);
  const std::vector<ImuSample>& held() const { return held_; }
  bool next(ImuSample& sample) override;
  /// Held samples are still to be given again.
  bool replaying() const { return next_ < held_.size(); }
  /// Where skipped bad samples are reported (the filter's run); the ones met while holding first.
  void skip_bad_samples(const std::function<void(const BadSampleError&)>& on_skip);

 private:
  SampleSource& source_;
  std::size_t capacity_;
  std::vector<ImuSample> held_;
  std::size_t next_ = 0;
  std::exception_ptr error_;  // a read error met while holding
  std::vector<BadSampleError> skipped_;
  std::function<void(const BadSampleError&)> on_skip_;
};

}  // namespace sinscal
