#include "filter/state_layout.hpp"

#include <algorithm>
#include <stdexcept>

#include "models/imu_error_model.hpp"
#include "models/sensor_profile.hpp"

namespace sinscal {

StateLayout StateLayout::make(const StateLayoutOptions& o) {
  StateLayout l;
  int next = 0;
  auto add = [&](Block& b, int size, bool on = true) {
    if (!on) return;
    b = Block{next, size};
    next += size;
  };
  add(l.attitude, 3);
  add(l.velocity, o.vertical_velocity ? 3 : 2);
  add(l.position, 3);
  add(l.gyro_bias, 3);
  add(l.gyro_scale, 3);
  add(l.gyro_misalignment, 6);
  add(l.accel_bias, 3);
  add(l.accel_scale, 3);
  add(l.accel_misalignment, o.accel_triad_frame ? 3 : 6);
  add(l.accel_k2, 3, o.accel_k2);
  add(l.gyro_scale_asym, 3, o.scale_asym);
  add(l.accel_scale_asym, 3, o.scale_asym);
  add(l.gyro_g_sensitivity, 9, o.g_sensitivity);
  add(l.accel_lever_arm, 9, o.lever_arm);
  add(l.time_delay, 1, o.time_delay);
  l.size = next;
  l.accel_triad_frame = o.accel_triad_frame;
  return l;
}

std::vector<StateLayout::CoefficientBlock> StateLayout::coefficient_blocks() const {
  const std::pair<const char*, const Block*> families[] = {
      {"gyro.bias", &gyro_bias},
      {"gyro.scale", &gyro_scale},
      {"gyro.misalignment", &gyro_misalignment},
      {"accel.bias", &accel_bias},
      {"accel.scale", &accel_scale},
      {"accel.misalignment", &accel_misalignment},
      {"accel.k2", &accel_k2},
      {"gyro.scale_asym", &gyro_scale_asym},
      {"accel.scale_asym", &accel_scale_asym},
      {"gyro.g_sensitivity", &gyro_g_sensitivity},
      {"accel.lever_arm", &accel_lever_arm},
      {"time_delay", &time_delay}};
  const auto& cat = coefficient_catalog();
  const std::vector<int> fixed = fixed_by_convention();
  std::vector<CoefficientBlock> out;
  for (const auto& [family, block] : families) {
    if (!on(*block)) continue;
    std::vector<int> members;
    for (int i = 0; i < static_cast<int>(cat.size()); ++i)
      if (coefficient_family(cat[i].name) == family &&
          std::find(fixed.begin(), fixed.end(), i) == fixed.end())
        members.push_back(i);
    if (static_cast<int>(members.size()) != block->size)
      throw std::logic_error(std::string("state layout: block ") + family + " has " +
                             std::to_string(block->size) + " states, the catalog " +
                             std::to_string(members.size()) + " coefficients");
    out.push_back({family, *block, members});
  }
  return out;
}

std::vector<int> StateLayout::fixed_by_convention() const {
  std::vector<int> out;
  if (!accel_triad_frame) return out;
  const auto& cat = coefficient_catalog();
  for (const char* name :
       {"accel.misalignment.xy", "accel.misalignment.xz", "accel.misalignment.yz"})
    for (int i = 0; i < static_cast<int>(cat.size()); ++i)
      if (cat[i].name == name) out.push_back(i);
  return out;
}

void apply_terms(StateLayoutOptions& o, const std::string& terms) {
  const std::pair<const char*, bool*> known[] = {
      {"k2", &o.accel_k2},           {"lever_arm", &o.lever_arm},
      {"time_delay", &o.time_delay}, {"g_sensitivity", &o.g_sensitivity},
      {"scale_asym", &o.scale_asym}, {"vertical_velocity", &o.vertical_velocity}};
  std::size_t pos = 0;
  while (pos <= terms.size()) {
    std::size_t end = terms.find(',', pos);
    if (end == std::string::npos) end = terms.size();
    std::string term = terms.substr(pos, end - pos);
    pos = end + 1;
    if (term.empty()) continue;
    bool on = true;
    if (term[0] == '-' || term[0] == '+') {
      on = term[0] == '+';
      term.erase(0, 1);
    }
    bool found = false;
    for (const auto& [name, flag] : known)
      if (term == name) {
        *flag = on;
        found = true;
      }
    if (!found)
      throw std::invalid_argument("unknown term '" + term +
                                  "' (known: k2, lever_arm, time_delay, g_sensitivity, "
                                  "scale_asym, vertical_velocity)");
  }
}

}  // namespace sinscal
