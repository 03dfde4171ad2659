#include "filter/kalman/state_layout.hpp"

#include <algorithm>
#include <stdexcept>

#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"

namespace sinscal {

bool StateLayoutOptions::on(const std::string& family) const {
  return coefficient_family_info(family).base || extended.count(family) > 0;
}

void StateLayoutOptions::set(const std::string& family, bool is_on) {
  if (coefficient_family_info(family).base)
    throw std::invalid_argument("'" + family + "' is a base family: always estimated");
  if (is_on)
    extended.insert(family);
  else
    extended.erase(family);
}

StateLayout StateLayout::make(const StateLayoutOptions& o) {
  StateLayout l;
  int next = 0;
  auto add = [&](Block& b, int count) {
    b = Block{next, count};
    next += count;
  };
  add(l.attitude, 3);
  add(l.velocity, o.vertical_velocity ? 3 : 2);
  add(l.position, 3);
  l.nav_size = next;
  l.accel_triad_frame = o.accel_triad_frame;
  const auto& cat = coefficient_catalog();
  std::vector<std::string> fixed = o.fixed;
  if (o.accel_triad_frame)
    fixed.insert(fixed.end(),
                 {"accel.misalignment.xy", "accel.misalignment.xz", "accel.misalignment.yz"});
  for (const auto& name : fixed) {
    const auto it = std::find_if(cat.begin(), cat.end(),
                                 [&](const CoefficientInfo& c) { return c.name == name; });
    if (it == cat.end())
      throw std::invalid_argument("state layout: no coefficient '" + name + "' to fix");
    const int c = static_cast<int>(it - cat.begin());
    if (!o.on(it->family)) continue;  // a family not estimated has nothing to fix
    if (std::find(l.fixed.begin(), l.fixed.end(), c) == l.fixed.end()) l.fixed.push_back(c);
  }
  std::sort(l.fixed.begin(), l.fixed.end());
  l.state_of.assign(cat.size(), -1);
  for (const auto& f : coefficient_families()) {
    if (!o.on(f.name)) continue;
    CoefficientBlock cb{f.name, Block{next, 0}, {}};
    for (int c = 0; c < static_cast<int>(cat.size()); ++c)
      if (cat[static_cast<std::size_t>(c)].family == f.name &&
          !std::binary_search(l.fixed.begin(), l.fixed.end(), c)) {
        l.state_of[static_cast<std::size_t>(c)] = next++;
        cb.catalog.push_back(c);
      }
    cb.block.size = static_cast<int>(cb.catalog.size());
    if (cb.block.size > 0) l.coefficients.push_back(cb);
  }
  if (o.base_attitude) add(l.base, 3);
  if (o.dwell_orientation) add(l.dwell_orientation, 3);
  if (o.bias_wander) add(l.wander, 6);
  l.size = next;
  return l;
}

const StateLayout::CoefficientBlock* StateLayout::block(const std::string& family) const {
  for (const auto& cb : coefficients)
    if (cb.family == family) return &cb;
  return nullptr;
}

void set_lever_arm_reference(StateLayoutOptions& o, const std::string& axis) {
  if (axis != "x" && axis != "y" && axis != "z")
    throw std::invalid_argument("the lever-arm reference is accelerometer x, y or z, not '" + axis +
                                "'");
  for (const char* component : {"x", "y", "z"})
    o.fixed.push_back("accel.lever_arm." + axis + "." + component);
}

void apply_terms(StateLayoutOptions& o, const std::string& terms) {
  const auto known_terms = extended_terms();
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
    if (term == "vertical_velocity") {
      o.vertical_velocity = on;
      continue;
    }
    bool found = false;
    for (const auto& [name, families] : known_terms)
      if (term == name) {
        for (const auto& f : families) o.set(f, on);
        found = true;
      }
    for (const auto& f : coefficient_families())
      if (!f.base && term == f.name) {
        o.set(f.name, on);
        found = true;
      }
    if (!found) {
      std::string names;
      for (const auto& t : known_terms) names += t.first + ", ";
      throw std::invalid_argument("unknown term '" + term + "' (known: " + names +
                                  "vertical_velocity, or an extended family's name such as "
                                  "gyro.scale_asym)");
    }
  }
}

}  // namespace sinscal
