#include <catch2/catch.hpp>

#include "filter/state_layout.hpp"
#include "models/imu_error_model.hpp"

using namespace sinscal;

TEST_CASE("State layout: blocks tile the state, size derived from what is on", "[layout]") {
  StateLayoutOptions base;
  const StateLayout b = StateLayout::make(base);
  CHECK(b.size == 9 + 24);
  CHECK_FALSE(StateLayout::on(b.accel_k2));
  StateLayoutOptions all{true, true, true, true, true, true, false};
  const StateLayout a = StateLayout::make(all);
  CHECK(a.size == 9 + 24 + 3 + 6 + 9 + 9 + 1);
  // Every coefficient block maps onto its catalog family, and together they tile the state
  // after the navigation errors without gaps or overlaps.
  int next = a.position.index + a.position.size;
  std::size_t coefficients = 0;
  for (const auto& cb : a.coefficient_blocks()) {
    CAPTURE(cb.family);
    CHECK(cb.block.index == next);
    next += cb.block.size;
    coefficients += static_cast<std::size_t>(cb.block.size);
    REQUIRE(static_cast<int>(cb.catalog.size()) == cb.block.size);
    for (int c : cb.catalog)
      CHECK(coefficient_catalog()[static_cast<std::size_t>(c)].name.rfind(cb.family, 0) == 0);
  }
  CHECK(next == a.size);
  CHECK(coefficients == coefficient_catalog().size());
  StateLayoutOptions no_vertical;
  no_vertical.vertical_velocity = false;
  CHECK(StateLayout::make(no_vertical).velocity.size == 2);
}

TEST_CASE("State layout: accelerometer-triad body frame drops the three fixed misalignments",
          "[layout]") {
  StateLayoutOptions o;
  o.accel_triad_frame = true;
  const StateLayout l = StateLayout::make(o);
  CHECK(l.size == 9 + 24 - 3);
  CHECK(l.accel_misalignment.size == 3);
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
  o.lever_arm = true;
  apply_terms(o, "k2,-lever_arm,+time_delay,-vertical_velocity");
  CHECK(o.accel_k2);
  CHECK_FALSE(o.lever_arm);
  CHECK(o.time_delay);
  CHECK_FALSE(o.vertical_velocity);
  CHECK_FALSE(o.g_sensitivity);
  const StateLayout l = StateLayout::make(o);
  CHECK(l.velocity.size == 2);
  CHECK(l.accel_k2.size == 3);
  CHECK(l.accel_lever_arm.size == 0);
  CHECK(l.time_delay.size == 1);
  CHECK_THROWS_WITH(apply_terms(o, "k2,lever"), Catch::Contains("unknown term 'lever'"));
}
