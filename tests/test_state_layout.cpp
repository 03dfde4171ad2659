#include <catch2/catch.hpp>

#include "filter/state_layout.hpp"
#include "models/imu_error_model.hpp"

using namespace sinscal;

TEST_CASE("State layout: blocks tile the state, size derived from what is on", "[layout]") {
  StateLayoutOptions base;
  const StateLayout b = StateLayout::make(base);
  CHECK(b.size == 9 + 24);
  CHECK_FALSE(StateLayout::on(b.accel_k2));
  StateLayoutOptions all{true, true, true, true, true, true};
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
    CHECK(coefficient_catalog()[static_cast<std::size_t>(cb.catalog_index)].name.rfind(cb.family,
                                                                                       0) == 0);
  }
  CHECK(next == a.size);
  CHECK(coefficients == coefficient_catalog().size());
  StateLayoutOptions no_vertical;
  no_vertical.vertical_velocity = false;
  CHECK(StateLayout::make(no_vertical).velocity.size == 2);
}
