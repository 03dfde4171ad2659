// The log-reader targets' common check: read every sample; each must be finite and move time
// forward (a finding otherwise).
#pragma once

#include <cmath>
#include <string>

#include "fuzz_support.hpp"
#include "rig/io/log_io.hpp"

namespace sinscal::fuzz {

inline void read_all_samples(LogReader& reader) {
  ImuSample s;
  double t_prev = -INFINITY;
  while (reader.next(s)) {
    if (!std::isfinite(s.t) || !(s.dt > 0.0) || !std::isfinite(s.dt) || !s.dtheta_b.allFinite() ||
        !s.dv_b.allFinite() || !std::isfinite(s.table_outer) || !std::isfinite(s.table_inner))
      finding("a sample is not finite", "line " + std::to_string(reader.line()));
    if (s.has_temperature && !(s.accel_temperature_c >= LogFormat::kMinTemperature &&
                               s.accel_temperature_c <= LogFormat::kMaxTemperature &&
                               s.gyro_temperature_c >= LogFormat::kMinTemperature &&
                               s.gyro_temperature_c <= LogFormat::kMaxTemperature))
      finding("a temperature out of range", "line " + std::to_string(reader.line()));
    if (!(s.t > t_prev)) finding("time does not increase", "line " + std::to_string(reader.line()));
    t_prev = s.t;
  }
}

}  // namespace sinscal::fuzz
