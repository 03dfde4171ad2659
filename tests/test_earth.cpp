#include <GeographicLib/Constants.hpp>
#include <catch2/catch.hpp>

#include "models/earth.hpp"
#include "models/units.hpp"

using namespace sinscal;

TEST_CASE("Normal gravity equals the published WGS-84 values", "[earth]") {
  const Earth& e = Earth::wgs84();
  // WGS-84 (NIMA TR8350.2): normal gravity at the equator and at the poles.
  CHECK(std::abs(e.surface_gravity(0.0) / 9.7803253359 - 1.0) < 1e-9);
  CHECK(std::abs(e.surface_gravity(90.0 * units::deg) / 9.8321849378 - 1.0) < 1e-9);
  // The vector on the ellipsoid is along the normal (down) with that magnitude.
  const Eigen::Vector3d g = e.gravity_n(55.75 * units::deg, 0.0);
  CHECK(std::abs(g.x()) < 1e-12);
  CHECK(g.y() == 0.0);
  CHECK(std::abs(g.z() - e.surface_gravity(55.75 * units::deg)) < 1e-12);
  // Gravity decreases with height by about 3.086e-6 m/s^2 per metre (free-air gradient).
  const double gradient = (e.gravity_n(0.7, 100.0).z() - e.gravity_n(0.7, 0.0).z()) / 100.0;
  CHECK(gradient == Approx(-3.086e-6).epsilon(0.01));
}

TEST_CASE("Earth rate and radii of curvature", "[earth]") {
  const Earth& e = Earth::wgs84();
  CHECK(e.rate() == 7.292115e-5);  // WGS-84 defining constant, rad/s
  const double lat = 30.0 * units::deg;
  const Eigen::Vector3d w = e.omega_ie_n(lat);
  CHECK(w.norm() == Approx(7.292115e-5).epsilon(1e-14));
  CHECK(w.z() < 0.0);  // Earth rate points up in the northern hemisphere: negative down
  const double a = GeographicLib::Constants::WGS84_a(), f = GeographicLib::Constants::WGS84_f();
  const double e2 = f * (2 - f);
  CHECK(e.radius_meridian(0.0) == Approx(a * (1 - e2)).epsilon(1e-14));
  CHECK(e.radius_transverse(0.0) == Approx(a).epsilon(1e-14));
  const double s2 = std::sin(lat) * std::sin(lat);
  CHECK(e.radius_transverse(lat) == Approx(a / std::sqrt(1 - e2 * s2)).epsilon(1e-13));
}

TEST_CASE("LocalEarth is exact at its reference and second-order close nearby", "[earth]") {
  const Earth& e = Earth::wgs84();
  LocalEarth local(e);
  const double lat = 55.75 * units::deg, h = 150.0;
  const EarthTerms t0 = local.at(lat, h);
  CHECK((t0.g_n - e.gravity_n(lat, h)).norm() == 0.0);
  CHECK(t0.R_N == e.radius_meridian(lat));
  // 50 m up and 80 m north: linearisation error far below 1e-8 m/s^2 and 1e-3 m.
  const double dlat = 80.0 / e.radius_meridian(lat);
  const EarthTerms t1 = local.at(lat + dlat, h + 50.0);
  CHECK((t1.g_n - e.gravity_n(lat + dlat, h + 50.0)).norm() < 1e-8);
  CHECK(std::abs(t1.R_E - e.radius_transverse(lat + dlat)) < 1e-3);
  // Second order: Omega * dlat^2 / 2 = 6e-15 rad/s.
  CHECK((t1.omega_ie_n - e.omega_ie_n(lat + dlat)).norm() < 1e-14);
}
