// A session recorded as one file per dwell of the plan (files, dwells of [log]): each file is read
// with the session's format and placed at its dwell's start; data past the dwell's end are an
// error (plan and data do not match).
#include <algorithm>
#include <charconv>
#include <cstdio>
#include <filesystem>

#include "models/config.hpp"
#include "rig/io/log_keys.hpp"
#include "rig/motion.hpp"
#include "rig/plan.hpp"

namespace sinscal {

namespace log_keys {

// The files of a log recorded as one file per dwell: `files` (and `dwells`) of [log], placed in
// the dwells of the session's plan.
std::vector<LogSegment> read_segments(const IniFile& ini, const std::string& base_dir) {
  const auto files = tokens_of(ini.get_string("log.files"));
  if (files.empty()) throw ConfigError(ini.where("log.files") + "no files given");
  std::vector<int> dwells;
  if (ini.has("log.dwells")) {
    for (const auto& d : tokens_of(ini.get_string("log.dwells"))) {
      int v = 0;
      const auto r = std::from_chars(d.data(), d.data() + d.size(), v);
      if (r.ec != std::errc() || r.ptr != d.data() + d.size() || v < 1)
        throw ConfigError(ini.where("log.dwells") + "'" + d +
                          "' is not a dwell number (1, 2, ...)");
      dwells.push_back(v);
    }
    if (dwells.size() != files.size())
      throw ConfigError(ini.where("log.dwells") + std::to_string(dwells.size()) + " dwells for " +
                        std::to_string(files.size()) + " files: give one dwell per file");
  } else {
    for (std::size_t i = 0; i < files.size(); ++i) dwells.push_back(static_cast<int>(i) + 1);
  }
  if (!ini.has("session.plan"))
    throw ConfigError(ini.where("log.files") +
                      "a log in one file per dwell needs the session's plan ([session] plan) "
                      "for the dwells' times");
  const Plan plan = Plan::load(path_in(base_dir, ini.get_string("session.plan")));
  const double offset = ini.get_quantity("session.time_offset", QuantityKind::Time, "s", 0.0);
  const Motion motion = build_motion(plan, Site{});
  const auto& plan_dwells = motion.dwells();
  std::vector<LogSegment> out;
  for (std::size_t i = 0; i < files.size(); ++i) {
    LogSegment seg;
    seg.file = path_in(base_dir, files[i]);
    seg.dwell = dwells[i];
    std::error_code ec;  // a name the system refuses (too long, ...) reads as "no such file"
    if (!std::filesystem::is_regular_file(seg.file, ec))
      throw ConfigError(ini.where("log.files") + "'" + files[i] + "': no such file (" + seg.file +
                        ")");
    if (seg.dwell > static_cast<int>(plan_dwells.size()))
      throw ConfigError(ini.where(ini.has("log.dwells") ? "log.dwells" : "log.files") + "'" +
                        files[i] + "' is assigned to dwell " + std::to_string(seg.dwell) +
                        " but the plan " + plan.path + " has " +
                        std::to_string(plan_dwells.size()) + " dwells");
    for (const auto& other : out)
      if (other.dwell == seg.dwell)
        throw ConfigError(ini.where(ini.has("log.dwells") ? "log.dwells" : "log.files") + "'" +
                          files[i] + "' and '" + other.file + "' are both assigned to dwell " +
                          std::to_string(seg.dwell) + ": their times would overlap");
    const Dwell& d = plan_dwells[static_cast<std::size_t>(seg.dwell - 1)];
    seg.t_start = offset + d.t_start;
    seg.t_end = offset + d.t_end;
    out.push_back(seg);
  }
  std::sort(out.begin(), out.end(),
            [](const LogSegment& a, const LogSegment& b) { return a.dwell < b.dwell; });
  return out;
}

}  // namespace log_keys

bool LogReader::next_segment_sample(ImuSample& s) {
  for (;;) {
    if (segment_next_ >= f_.segments.size()) return false;
    const LogSegment& seg = f_.segments[segment_next_];
    if (!segment_) {
      LogFormat one = f_;
      one.segments.clear();
      one.file = seg.file;
      segment_ = std::make_unique<LogReader>(one);
      segment_->segment_child_ = true;
      if (on_skip_) segment_->skip_bad_samples(on_skip_);
      segment_count_ = 0;
    }
    if (segment_->next(s)) {
      // The file's own time from its first sample's interval start, placed at the dwell's start.
      if (segment_count_ == 0) segment_shift_ = seg.t_start - (s.t - s.dt);
      ++segment_count_;
      ++count_;
      s.t += segment_shift_;
      // Every file with temperatures or none (a thermal model cannot start and stop).
      if (segment_temperature_ < 0) segment_temperature_ = s.has_temperature ? 1 : 0;
      if ((segment_temperature_ == 1) != s.has_temperature)
        throw LogError(seg.file, segment_->line(),
                       std::string("this file ") + (s.has_temperature ? "has" : "has no") +
                           " temperature columns but " + f_.segments.front().file +
                           (s.has_temperature ? " has none" : " has them") +
                           ": give every dwell's file the same columns");
      temperature_summary_.add(s, seg.file, segment_->line());
      if (s.t > seg.t_end + 0.5 / f_.rate_hz) {
        char msg[300];
        std::snprintf(msg, sizeof msg,
                      "this file's data reach t = %.6f s, past the end of dwell %d at %.6f s: a "
                      "file must lie within its dwell (plan and data do not match)",
                      s.t, seg.dwell, seg.t_end);
        throw LogError(seg.file, segment_->line(), msg);
      }
      return true;
    }
    if (segment_count_ == 0)
      throw LogError(seg.file, segment_->line(),
                     "no samples in the file for dwell " + std::to_string(seg.dwell));
    segment_.reset();
    ++segment_next_;
  }
}

}  // namespace sinscal
