// Test support: how many samples the simulator plays for a plan (noise-free, error-free), the
// check that a plan written by the search runs through `simulate`.
#pragma once

#include "rig/imu_sim.hpp"
#include "rig/plan.hpp"

namespace sinscal {

inline int samples_played(const Plan& p, double rate_hz) {
  SimulatorOptions so;
  so.rate_hz = rate_hz;
  so.noise = false;
  const Motion motion = build_motion(p, p.site);  // the simulator keeps a reference
  ImuSimulator sim(motion, ImuErrorModel{}, NoiseModel{}, so);
  ImuSample s;
  int n = 0;
  while (sim.next(s)) ++n;
  return n;
}

}  // namespace sinscal
