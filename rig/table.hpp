// Two-axis tilt-rotation calibration table.
//
// The outer (tilt) axis is fixed to the ground, direction outer_axis_n in NED. It carries the
// platform; at outer angle 0 the platform frame p coincides with NED. The inner axis is fixed in
// the platform (inner_axis_p) and carries the IMU, mounted with C_b_p (body to platform). So
//   C_b_n(outer, inner) = R(outer_axis_n, outer) * R(inner_axis_p, inner) * C_b_p.
// Default: outer axis horizontal North-South, inner axis the platform normal (up); this reaches
// every orientation with one body axis along North-South, all 8 of the paper's.
#pragma once

#include <Eigen/Core>
#include <stdexcept>

namespace sinscal {

class UnreachableOrientation : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TableGeometry {
  Eigen::Vector3d outer_axis_n = Eigen::Vector3d::UnitX();   // unit, NED
  Eigen::Vector3d inner_axis_p = -Eigen::Vector3d::UnitZ();  // unit, platform frame
  Eigen::Matrix3d C_b_p = Eigen::Matrix3d::Identity();       // IMU mounting
  /// 2: the tilt-rotation table above; 3: a three-axis table, which reaches every attitude (its
  /// moves are simulated as one turn about the rotation's eigen-axis; it has no two-axis angles).
  int axes = 2;
};

/// How well the table sets the IMU's attitude at a dwell, as every estimator models it: an
/// independent error of `sigma` about each of the three navigation axes (the two axes' angle
/// errors and the platform's wobble and mounting repeatability about the third), constant within
/// the dwell.
struct TableAttitudeError {
  double sigma = 0.0;  // rad, per axis
  Eigen::Matrix3d covariance_n() const { return sigma * sigma * Eigen::Matrix3d::Identity(); }
};

struct TableAngles {
  double outer = 0.0;  // rad
  double inner = 0.0;  // rad
};

class Table {
 public:
  explicit Table(const TableGeometry& geometry);
  const TableGeometry& geometry() const { return g_; }
  Eigen::Matrix3d C_b_n(const TableAngles& angles) const;
  /// Inner axis in body axes (constant).
  Eigen::Vector3d inner_axis_b() const;
  /// Axis angles that put the body at C_b_n (within 1e-9 rad); throws UnreachableOrientation.
  /// A three-axis table reaches every attitude: zero angles (it has no two-axis angles).
  TableAngles angles_for(const Eigen::Matrix3d& C_b_n) const;

 private:
  TableGeometry g_;
};

}  // namespace sinscal
