// Earth model: WGS-84 normal gravity, radii of curvature and Earth rate, all from GeographicLib.
// Navigation frame n = local North-East-Down (NED). See docs/conventions.md.
#pragma once

#include <Eigen/Core>
#include <GeographicLib/Ellipsoid.hpp>
#include <GeographicLib/NormalGravity.hpp>
#include <string>

namespace sinscal {

/// A point on the Earth: geodetic latitude and longitude (rad), height above the ellipsoid (m).
struct Site {
  double lat_rad = 0.0;
  double lon_rad = 0.0;
  double h_m = 0.0;
};

/// The sites sinscal accepts (docs/formats.md, [site]): |latitude| at most 89 deg (the
/// North-East-Down navigation frame is singular at the poles), |longitude| at most 360 deg,
/// height from -12 km to +100 km above the ellipsoid (the deepest ocean floor to the edge of
/// space). Values outside are wrong input (e.g. radians or feet where degrees or metres were
/// meant), never a place a table stands.
struct SiteLimits {
  static constexpr double max_latitude_deg = 89.0;
  static constexpr double max_longitude_deg = 360.0;
  static constexpr double min_height_m = -12000.0;
  static constexpr double max_height_m = 100000.0;
};
/// Empty when the value is within SiteLimits, else the cause for a message ("must be within
/// ..., got ..."). NaN is never within.
std::string latitude_problem(double lat_rad);
std::string longitude_problem(double lon_rad);
std::string height_problem(double h_m);

/// WGS-84 Earth. Stateless; evaluating it calls GeographicLib.
class Earth {
 public:
  static const Earth& wgs84();

  /// Earth rotation rate (rad/s).
  double rate() const;
  /// Earth rate in the NED frame at latitude `lat_rad` (rad/s).
  Eigen::Vector3d omega_ie_n(double lat_rad) const;
  /// Normal gravity vector (gravitation plus centrifugal) in NED at (lat, h) (m/s^2).
  Eigen::Vector3d gravity_n(double lat_rad, double h_m) const;
  /// Magnitude of normal gravity on the ellipsoid surface (m/s^2).
  double surface_gravity(double lat_rad) const;
  /// Meridian radius of curvature R_N (m).
  double radius_meridian(double lat_rad) const;
  /// Transverse (prime vertical) radius of curvature R_E (m).
  double radius_transverse(double lat_rad) const;

 private:
  Earth();
  const GeographicLib::NormalGravity& gravity_;
  GeographicLib::Ellipsoid ellipsoid_;
};

/// The Earth terms a navigator needs at one point.
struct EarthTerms {
  Eigen::Vector3d omega_ie_n;  // rad/s, NED
  Eigen::Vector3d g_n;         // m/s^2, NED
  double R_N = 0.0;            // m
  double R_E = 0.0;            // m
  double tan_lat = 0.0;
  double cos_lat = 1.0;
};

/// Earth terms linearised about a reference point and re-expanded when the point moves more than
/// `refresh_distance_m` from it. The linearisation error is second order: below 1e-8 m/s^2 of
/// gravity for the default 100 m, far below any effect sinscal estimates; at the reference point
/// itself the terms are exact. Makes the navigator's Earth terms cost a few multiplications.
class LocalEarth {
 public:
  explicit LocalEarth(const Earth& earth, double refresh_distance_m = 100.0);
  const EarthTerms& at(double lat_rad, double h_m);

 private:
  void expand(double lat_rad, double h_m);
  const Earth& earth_;
  double refresh_m_;
  double lat0_ = 1e300, h0_ = 1e300;
  EarthTerms t0_, d_lat_, d_h_, now_;
};

}  // namespace sinscal
