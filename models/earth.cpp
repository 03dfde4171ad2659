#include "models/earth.hpp"

#include <GeographicLib/Constants.hpp>
#include <cmath>
#include <cstdio>

#include "models/units.hpp"

namespace sinscal {

namespace {
// `value`, `lo`, `hi` in SI; `per_unit`: SI per unit of the message.
std::string out_of_bounds(double value, double lo, double hi, double per_unit, const char* unit) {
  if (value >= lo && value <= hi) return {};
  char b[160];
  std::snprintf(b, sizeof b, "must be within %g and %g %s, got %g %s", lo / per_unit, hi / per_unit,
                unit, value / per_unit, unit);
  return b;
}
}  // namespace

std::string latitude_problem(double lat_rad) {
  const double m = SiteLimits::max_latitude_deg * units::deg;
  return out_of_bounds(lat_rad, -m, m, units::deg, "deg");
}

std::string longitude_problem(double lon_rad) {
  const double m = SiteLimits::max_longitude_deg * units::deg;
  return out_of_bounds(lon_rad, -m, m, units::deg, "deg");
}

std::string height_problem(double h_m) {
  return out_of_bounds(h_m, SiteLimits::min_height_m, SiteLimits::max_height_m, 1.0, "m");
}

Earth::Earth()
    : gravity_(GeographicLib::NormalGravity::WGS84()),
      ellipsoid_(GeographicLib::Constants::WGS84_a(), GeographicLib::Constants::WGS84_f()) {}

const Earth& Earth::wgs84() {
  static const Earth earth;
  return earth;
}

double Earth::rate() const { return GeographicLib::Constants::WGS84_omega(); }

Eigen::Vector3d Earth::omega_ie_n(double lat_rad) const {
  return rate() * Eigen::Vector3d(std::cos(lat_rad), 0.0, -std::sin(lat_rad));
}

Eigen::Vector3d Earth::gravity_n(double lat_rad, double h_m) const {
  double gamma_north = 0.0, gamma_up = 0.0;
  gravity_.Gravity(lat_rad / units::deg, h_m, gamma_north, gamma_up);
  return {gamma_north, 0.0, -gamma_up};
}

double Earth::surface_gravity(double lat_rad) const {
  return gravity_.SurfaceGravity(lat_rad / units::deg);
}

double Earth::radius_meridian(double lat_rad) const {
  return ellipsoid_.MeridionalCurvatureRadius(lat_rad / units::deg);
}

double Earth::radius_transverse(double lat_rad) const {
  return ellipsoid_.TransverseCurvatureRadius(lat_rad / units::deg);
}

namespace {
EarthTerms exact_terms(const Earth& earth, double lat, double h) {
  EarthTerms t;
  t.omega_ie_n = earth.omega_ie_n(lat);
  t.g_n = earth.gravity_n(lat, h);
  t.R_N = earth.radius_meridian(lat);
  t.R_E = earth.radius_transverse(lat);
  t.tan_lat = std::tan(lat);
  t.cos_lat = std::cos(lat);
  return t;
}
EarthTerms difference(const EarthTerms& a, const EarthTerms& b, double step) {
  EarthTerms d;
  d.omega_ie_n = (a.omega_ie_n - b.omega_ie_n) / step;
  d.g_n = (a.g_n - b.g_n) / step;
  d.R_N = (a.R_N - b.R_N) / step;
  d.R_E = (a.R_E - b.R_E) / step;
  d.tan_lat = (a.tan_lat - b.tan_lat) / step;
  d.cos_lat = (a.cos_lat - b.cos_lat) / step;
  return d;
}
}  // namespace

LocalEarth::LocalEarth(const Earth& earth, double refresh_distance_m)
    : earth_(earth), refresh_m_(refresh_distance_m) {}

void LocalEarth::expand(double lat, double h) {
  lat0_ = lat;
  h0_ = h;
  t0_ = exact_terms(earth_, lat, h);
  const double dlat = 1e-5, dh = 10.0;  // central differences; their error is O(step^2)
  d_lat_ =
      difference(exact_terms(earth_, lat + dlat, h), exact_terms(earth_, lat - dlat, h), 2 * dlat);
  d_h_ = difference(exact_terms(earth_, lat, h + dh), exact_terms(earth_, lat, h - dh), 2 * dh);
}

const EarthTerms& LocalEarth::at(double lat, double h) {
  const double dl = lat - lat0_, dh = h - h0_;
  if (std::abs(dl) * GeographicLib::Constants::WGS84_a() > refresh_m_ ||
      std::abs(dh) > refresh_m_) {
    expand(lat, h);
    now_ = t0_;
    return now_;
  }
  now_.omega_ie_n = t0_.omega_ie_n + d_lat_.omega_ie_n * dl + d_h_.omega_ie_n * dh;
  now_.g_n = t0_.g_n + d_lat_.g_n * dl + d_h_.g_n * dh;
  now_.R_N = t0_.R_N + d_lat_.R_N * dl + d_h_.R_N * dh;
  now_.R_E = t0_.R_E + d_lat_.R_E * dl + d_h_.R_E * dh;
  now_.tan_lat = t0_.tan_lat + d_lat_.tan_lat * dl;
  now_.cos_lat = t0_.cos_lat + d_lat_.cos_lat * dl;
  return now_;
}

}  // namespace sinscal
