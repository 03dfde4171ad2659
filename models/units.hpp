// Engineering units used at the edges of sinscal (configuration files, reports).
// Inside the library everything is SI: rad, rad/s, m/s^2, m, s. Multiply a value in the named
// unit by the factor to get SI; divide an SI value by it to report. docs/conventions.md lists them.
#pragma once

namespace sinscal::units {

constexpr double pi = 3.14159265358979323846;
constexpr double deg = pi / 180.0;       // rad
constexpr double arcmin = deg / 60.0;    // rad
constexpr double arcsec = deg / 3600.0;  // rad
constexpr double mrad = 1e-3;            // rad
constexpr double hour = 3600.0;          // s
constexpr double ms = 1e-3;              // s
constexpr double us = 1e-6;              // s
constexpr double ppm = 1e-6;             // dimensionless
// Standard gravity: the conventional value that defines the unit "g" (3rd CGPM, 1901). It is a
// unit of acceleration, not an Earth model; local gravity always comes from models/earth.hpp.
constexpr double g0 = 9.80665;                             // m/s^2
constexpr double ug = 1e-6 * g0;                           // m/s^2
constexpr double mg = 1e-3 * g0;                           // m/s^2
constexpr double mm = 1e-3;                                // m
constexpr double cm = 1e-2;                                // m
constexpr double deg_per_h = deg / hour;                   // rad/s
constexpr double deg_per_s = deg;                          // rad/s
constexpr double deg_per_sqrt_h = deg / 60.0;              // rad/sqrt(s)  (angle random walk)
constexpr double ug_per_sqrt_hz = ug;                      // m/s^2/sqrt(Hz) = m/s/sqrt(s)
constexpr double deg_per_h_per_sqrt_h = deg_per_h / 60.0;  // rad/s/sqrt(s) (rate random walk)
constexpr double ug_per_sqrt_h = ug / 60.0;                // m/s^2/sqrt(s)
constexpr double deg_per_h_per_g = deg_per_h / g0;         // rad/s per m/s^2 (g-sensitivity)
constexpr double ug_per_g2 = ug / (g0 * g0);  // 1/(m/s^2)      (quadratic scale factor)

}  // namespace sinscal::units
