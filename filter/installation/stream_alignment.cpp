#include "filter/installation/stream_alignment.hpp"

#include <stdexcept>
#include <utility>

namespace sinscal {

HeldStream::HeldStream(SampleSource& source, std::size_t capacity, bool skip_bad_samples)
    : source_(source), capacity_(capacity) {
  if (!skip_bad_samples) return;
  auto* log = dynamic_cast<LogReader*>(&source);
  if (!log) throw std::invalid_argument("skipping bad samples needs a log reader");
  log->skip_bad_samples([this](const BadSampleError& e) {
    if (on_skip_)
      on_skip_(e);
    else
      skipped_.push_back(e);
  });
}

bool HeldStream::hold(const PlanTimeline& timeline, std::size_t dwells, double time_offset,
                      double margin, const std::atomic<bool>* stop) {
  if (dwells == 0 || dwells > timeline.dwells.size()) return false;
  const double t_end = timeline.dwells[dwells - 1].t_end - margin;  // plan time
  // The sample's middle, as dwell_means takes it: past the last dwell's end, all are held.
  auto past = [&](const ImuSample& s) { return s.t - 0.5 * s.dt - time_offset > t_end; };
  if (!held_.empty() && past(held_.back())) return true;
  if (error_) return false;
  if (held_.capacity() < capacity_) held_.reserve(capacity_);  // no copy while growing
  ImuSample s;
  try {
    while (held_.size() < capacity_ && !(stop && stop->load(std::memory_order_relaxed)) &&
           source_.next(s)) {
      held_.push_back(s);
      if (past(s)) return true;
    }
  } catch (const std::exception&) {
    error_ = std::current_exception();
  }
  return false;
}

bool HeldStream::next(ImuSample& sample) {
  if (next_ < held_.size()) {
    sample = held_[next_++];
    if (next_ == held_.size()) {  // all given again: the buffer's memory back
      held_ = {};
      next_ = 0;
    }
    return true;
  }
  if (error_) std::rethrow_exception(std::exchange(error_, nullptr));
  return source_.next(sample);
}

void HeldStream::skip_bad_samples(const std::function<void(const BadSampleError&)>& on_skip) {
  for (const auto& e : skipped_) on_skip(e);
  skipped_.clear();
  on_skip_ = on_skip;
}

}  // namespace sinscal
