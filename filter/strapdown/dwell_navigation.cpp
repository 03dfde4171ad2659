#include "filter/strapdown/dwell_navigation.hpp"

#include <cmath>
#include <sstream>

namespace sinscal {

DwellNavigation::DwellNavigation(std::vector<PlanDwell> dwells, const Site& site,
                                 const DwellNavOptions& options)
    : dwells_(std::move(dwells)), site_(site), options_(options) {}

void DwellNavigation::run(SampleSource& source,
                          const std::function<void(const DwellNavRow&)>& sink) {
  Strapdown nav(Earth::wgs84(), options_.strapdown);
  std::size_t d = 0;
  bool active = false;
  DwellNavSummary current;
  double next_output = 0.0;
  const double eps = 1e-6;
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  auto emit = [&](double t_log, const ImuSample* sample) {
    DwellNavRow row;
    row.sample = sample;
    row.dwell = dwells_[d].index;
    row.info = &dwells_[d];
    row.t_log = t_log;
    row.error = nav_error(nav.state(), dwells_[d].C_b_n_known, zero, site_);
    sink(row);
    return row.error;
  };
  ImuSample s;
  auto finish = [&](double t_log) {
    current.final_error = emit(t_log, nullptr);
    summaries_.push_back(current);
    active = false;
    ++d;
  };
  double t_last = -1e300;
  while (d < dwells_.size() && source.next(s)) {
    t_last = s.t;
    const double start = s.t - s.dt - options_.time_offset;  // plan time of the interval
    const double end = s.t - options_.time_offset;
    if (active && end > dwells_[d].t_end + eps) finish(s.t - s.dt);
    if (d >= dwells_.size()) break;
    if (!active && start >= dwells_[d].t_start - eps && end <= dwells_[d].t_end + eps) {
      if (start > dwells_[d].t_start + 1.5 * s.dt) {
        std::ostringstream m;
        m << options_.input << ": the log starts after dwell " << dwells_[d].index << " ("
          << dwells_[d].label << ") begins at plan time " << dwells_[d].t_start << " s";
        throw PlanMismatch(m.str());
      }
      nav.reset(NavState::at_rest(dwells_[d].C_b_n_known, site_));
      current = DwellNavSummary{};
      current.dwell = dwells_[d];
      active = true;
      emit(s.t - s.dt, nullptr);
      next_output = options_.output_interval;
    }
    if (active) {
      nav.step(s.dtheta_b, s.dv_b, s.dt);
      ++current.samples;
      const bool last = end > dwells_[d].t_end - 0.5 * s.dt;
      if (last) {
        current.final_error = emit(s.t, &s);
        summaries_.push_back(current);
        active = false;
        ++d;
      } else if (nav.state().t >= next_output - eps) {
        emit(s.t, &s);
        next_output += options_.output_interval;
      }
    }
  }
  // Data ending within a sample of the dwell's end complete it.
  if (active && d < dwells_.size() && t_last - options_.time_offset > dwells_[d].t_end - 1.5 * s.dt)
    finish(t_last);
  if (d < dwells_.size()) {
    std::ostringstream m;
    m << options_.input << ": the log ends at t = " << t_last << " s but dwell " << dwells_[d].index
      << " (" << dwells_[d].label << ") needs data until "
      << dwells_[d].t_end + options_.time_offset << " s: the plan does not match the data";
    throw PlanMismatch(m.str());
  }
}

}  // namespace sinscal
