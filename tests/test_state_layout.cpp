#include <catch2/catch.hpp>

#include "filter/kalman/state_layout.hpp"
#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"

using namespace sinscal;

namespace {
// Every extended family of the table switched on.
StateLayoutOptions all_families() {
  StateLayoutOptions o;
  for (const auto& f : coefficient_families())
    if (!f.base) o.set(f.name, true);
  return o;
}
int block_size(const StateLayout& l, const std::string& family) {
  const auto* b = l.block(family);
  return b ? b->block.size : 0;
}
}  // namespace

TEST_CASE("State layout: blocks tile the state, size derived from what is on", "[layout]") {
  StateLayoutOptions base;
  const StateLayout b = StateLayout::make(base);
  CHECK(b.size == 9 + 24);
  CHECK(b.block("accel.k2") == nullptr);
  const StateLayout a = StateLayout::make(all_families());
  CHECK(a.size == 9 + static_cast<int>(coefficient_catalog().size()));
  // Every coefficient block maps onto its catalog family, and together they tile the state
  // after the navigation errors without gaps or overlaps.
  int next = a.position.index + a.position.size;
  CHECK(next == a.nav_size);
  std::size_t coefficients = 0;
  for (const auto& cb : a.coefficient_blocks()) {
    CAPTURE(cb.family);
    CHECK(cb.block.index == next);
    next += cb.block.size;
    coefficients += static_cast<std::size_t>(cb.block.size);
    REQUIRE(static_cast<int>(cb.catalog.size()) == cb.block.size);
    for (int k = 0; k < cb.block.size; ++k) {
      const int c = cb.catalog[static_cast<std::size_t>(k)];
      CHECK(coefficient_catalog()[static_cast<std::size_t>(c)].name.rfind(cb.family, 0) == 0);
      CHECK(a.state_of[static_cast<std::size_t>(c)] == cb.block.index + k);
    }
  }
  CHECK(next == a.size);
  CHECK(coefficients == coefficient_catalog().size());
  StateLayoutOptions no_vertical;
  no_vertical.vertical_velocity = false;
  CHECK(StateLayout::make(no_vertical).velocity.size == 2);
}

TEST_CASE("State layout: the family table sizes every block, in its order", "[layout]") {
  const StateLayout a = StateLayout::make(all_families());
  REQUIRE(a.coefficient_blocks().size() == coefficient_families().size());
  for (std::size_t i = 0; i < coefficient_families().size(); ++i) {
    const CoefficientFamily& f = coefficient_families()[i];
    CAPTURE(f.name);
    CHECK(a.coefficient_blocks()[i].family == f.name);
    CHECK(a.coefficient_blocks()[i].block.size == f.size());
    // Every coefficient of the family is found by its name's family.
    for (int k = 0; k < f.size(); ++k) CHECK(coefficient_family(f.coefficient_name(k)) == f.name);
  }
  CHECK_THROWS_WITH(coefficient_family("gyro.bogus.x"), Catch::Contains("unknown coefficient"));
}

TEST_CASE("State layout: accelerometer-triad body frame drops the three fixed misalignments",
          "[layout]") {
  StateLayoutOptions o;
  o.accel_triad_frame = true;
  const StateLayout l = StateLayout::make(o);
  CHECK(l.size == 9 + 24 - 3);
  CHECK(block_size(l, "accel.misalignment") == 3);
  std::vector<std::string> names;
  for (int c : l.fixed_by_convention())
    names.push_back(coefficient_catalog()[static_cast<std::size_t>(c)].name);
  CHECK(names == std::vector<std::string>{"accel.misalignment.xy", "accel.misalignment.xz",
                                          "accel.misalignment.yz"});
  for (const auto& cb : l.coefficient_blocks())
    if (cb.family == "accel.misalignment")
      for (int c : cb.catalog) {
        const std::string& n = coefficient_catalog()[static_cast<std::size_t>(c)].name;
        CHECK((n == "accel.misalignment.yx" || n == "accel.misalignment.zx" ||
               n == "accel.misalignment.zy"));
      }
}

TEST_CASE("State layout: extended blocks switched by a terms list", "[layout]") {
  StateLayoutOptions o;
  o.set("accel.lever_arm", true);
  apply_terms(o, "k2,-lever_arm,+time_delay,-vertical_velocity");
  CHECK(o.on("accel.k2"));
  CHECK_FALSE(o.on("accel.lever_arm"));
  CHECK(o.on("time_delay"));
  CHECK_FALSE(o.vertical_velocity);
  CHECK_FALSE(o.on("gyro.g_sensitivity"));
  const StateLayout l = StateLayout::make(o);
  CHECK(l.velocity.size == 2);
  CHECK(block_size(l, "accel.k2") == 3);
  CHECK(block_size(l, "accel.lever_arm") == 0);
  CHECK(block_size(l, "time_delay") == 1);
  CHECK_THROWS_WITH(apply_terms(o, "k2,lever"), Catch::Contains("unknown term 'lever'"));
  // One term may switch several families; a family may be named on its own.
  apply_terms(o, "scale_asym");
  CHECK((o.on("gyro.scale_asym") && o.on("accel.scale_asym")));
  apply_terms(o, "-accel.scale_asym");
  CHECK((o.on("gyro.scale_asym") && !o.on("accel.scale_asym")));
  CHECK_THROWS_WITH(o.set("gyro.bias", false), Catch::Contains("base family"));
}
