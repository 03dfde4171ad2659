#include "rig/table.hpp"

#include <cmath>
#include <sstream>

#include "models/attitude.hpp"

namespace sinscal {

Table::Table(const TableGeometry& geometry) : g_(geometry) {
  g_.outer_axis_n.normalize();
  g_.inner_axis_p.normalize();
}

Eigen::Matrix3d Table::C_b_n(const TableAngles& a) const {
  return rotation(g_.outer_axis_n, a.outer) * rotation(g_.inner_axis_p, a.inner) * g_.C_b_p;
}

Eigen::Vector3d Table::inner_axis_b() const { return g_.C_b_p.transpose() * g_.inner_axis_p; }

TableAngles Table::angles_for(const Eigen::Matrix3d& C_target) const {
  if (g_.axes == 3) return {};
  const Eigen::Vector3d& u = g_.outer_axis_n;
  const Eigen::Vector3d v0 = g_.inner_axis_p;           // inner axis in NED at outer angle 0
  const Eigen::Vector3d w = C_target * inner_axis_b();  // where the target puts the inner axis
  auto fail = [&](const std::string& why) {
    std::ostringstream s;
    s << "orientation not reachable by the two-axis table: " << why;
    throw UnreachableOrientation(s.str());
  };
  if (std::abs(u.dot(w) - u.dot(v0)) > 1e-9)
    fail("the inner axis would need an angle of " +
         std::to_string(std::acos(std::clamp(u.dot(w), -1.0, 1.0)) * 180 / M_PI) +
         " deg to the outer axis, the table has " +
         std::to_string(std::acos(std::clamp(u.dot(v0), -1.0, 1.0)) * 180 / M_PI) + " deg");
  const Eigen::Vector3d v_perp = v0 - u.dot(v0) * u, w_perp = w - u.dot(w) * u;
  if (v_perp.norm() < 1e-9) fail("inner axis parallel to outer axis");
  TableAngles a;
  a.outer = std::atan2(u.dot(v_perp.cross(w_perp)), v_perp.dot(w_perp));
  const Eigen::Matrix3d M = rotation(u, -a.outer) * C_target * g_.C_b_p.transpose();
  const Eigen::Vector3d& ui = g_.inner_axis_p;
  Eigen::Vector3d p = ui.cross(Eigen::Vector3d::UnitX());
  if (p.norm() < 0.5) p = ui.cross(Eigen::Vector3d::UnitY());
  p.normalize();
  const Eigen::Vector3d Mp = M * p;
  a.inner = std::atan2(ui.dot(p.cross(Mp)), p.dot(Mp));
  if ((rotation(ui, a.inner) - M).cwiseAbs().maxCoeff() > 1e-9) fail("no inner angle matches");
  return a;
}

}  // namespace sinscal
