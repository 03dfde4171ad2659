#include "filter/kalman/misalignment_frame.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <stdexcept>

namespace sinscal {

std::string misalignment_frame_name(MisalignmentFrame frame) {
  switch (frame) {
    case MisalignmentFrame::Table:
      return "table";
    case MisalignmentFrame::Triad:
      return "triad";
    case MisalignmentFrame::ByMode:
      break;
  }
  throw std::invalid_argument("misalignment frame: 'by mode' has no name (resolve it first)");
}

MisalignmentFrame parse_misalignment_frame(const std::string& text) {
  if (text == "table") return MisalignmentFrame::Table;
  if (text == "triad") return MisalignmentFrame::Triad;
  throw std::invalid_argument("unknown misalignment frame '" + text + "' (table or triad)");
}

MisalignmentFrame resolve_misalignment_frame(MisalignmentFrame requested, bool attitude_updates) {
  if (requested == MisalignmentFrame::ByMode)
    return attitude_updates ? MisalignmentFrame::Table : MisalignmentFrame::Triad;
  if (requested == MisalignmentFrame::Table && !attitude_updates)
    throw std::invalid_argument(
        "the table frame is not observable without table-attitude updates (--attitude none): "
        "nothing measures the table's axes, so the body frame is the accelerometer triad's; use "
        "the triad frame or attitude updates (--attitude every or first)");
  return requested;
}

std::string misalignment_frame_words(MisalignmentFrame frame) {
  if (frame == MisalignmentFrame::Table)
    return "relative to the table's platform axes (the table frame: includes the IMU's mounting "
           "on the table, bounded by the table's attitude accuracy)";
  return "within the triads (the triad frame: the accelerometer triad is the body frame, body x "
         "along the x accelerometer, body y in the plane of the x and y accelerometers; "
         "accel.misalignment.xy, .xz and .yz are zero by this convention)";
}

namespace {

void split(TriadErrors& t, const Eigen::Matrix3d& linear_change) {
  t.scale = linear_change.diagonal();
  t.misalignment = linear_change;
  t.misalignment.diagonal().setZero();
}

// The change of the triad-frame model for a change `d` of the model (d's linear parts as I + dA).
ImuErrorModel triad_frame_change(const ImuErrorModel& m, const Eigen::Matrix3d& Q,
                                 const Eigen::Matrix3d& L, const ImuErrorModel& d) {
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const Eigen::Matrix3d X = L.inverse() * (d.accel.linear() - I) * Q;
  Eigen::Matrix3d W = Eigen::Matrix3d::Zero();
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j) {
      W(i, j) = -X(i, j);
      W(j, i) = X(i, j);
    }
  Eigen::Matrix3d dL = L * (X + W);
  dL.triangularView<Eigen::StrictlyUpper>().setZero();  // zero but for rounding
  ImuErrorModel out = d;                                // every other coefficient: unchanged
  split(out.accel, dL);
  split(out.gyro, (d.gyro.linear() - I) * Q + m.gyro.linear() * Q * W);
  out.gyro_g_sensitivity = d.gyro_g_sensitivity * Q + m.gyro_g_sensitivity * Q * W;
  out.accel_lever_arm_b =
      -W * Q.transpose() * m.accel_lever_arm_b + Q.transpose() * d.accel_lever_arm_b;
  return out;
}

}  // namespace

Eigen::MatrixXd accel_triad_frame_jacobian(const ImuErrorModel& model) {
  Eigen::Matrix3d Q;
  const ImuErrorModel triad = in_accel_triad_frame(model, &Q);
  const Eigen::Matrix3d L = triad.accel.linear();
  const auto n = static_cast<Eigen::Index>(coefficient_catalog().size());
  Eigen::MatrixXd J(n, n);
  ImuErrorModel d;
  const auto refs = d.coefficient_refs();
  for (Eigen::Index k = 0; k < n; ++k) {
    double& unit = *refs[static_cast<std::size_t>(k)].second;
    unit = 1.0;
    J.col(k) = triad_frame_change(model, Q, L, d).vector();
    unit = 0.0;
  }
  return J;
}

const std::vector<int>& triad_fixed_coefficients() {
  static const std::vector<int> fixed = [] {
    std::vector<int> out;
    const auto& cat = coefficient_catalog();
    for (const char* name :
         {"accel.misalignment.xy", "accel.misalignment.xz", "accel.misalignment.yz"})
      for (std::size_t c = 0; c < cat.size(); ++c)
        if (cat[c].name == name) out.push_back(static_cast<int>(c));
    return out;
  }();
  return fixed;
}

TriadFrameEstimate to_accel_triad_frame(const Eigen::VectorXd& values,
                                        const Eigen::MatrixXd& covariance,
                                        const std::vector<int>& catalog) {
  const ImuErrorModel m = ImuErrorModel::from_vector(values);
  TriadFrameEstimate out;
  out.jacobian = accel_triad_frame_jacobian(m);
  const Eigen::MatrixXd& J = out.jacobian;
  out.values = in_accel_triad_frame(m).vector();
  for (int c : triad_fixed_coefficients()) out.values(c) = 0.0;
  const auto& fixed = triad_fixed_coefficients();
  for (int c : catalog)
    if (std::find(fixed.begin(), fixed.end(), c) == fixed.end()) out.catalog.push_back(c);
  // J restricted: rows the new states, columns the old ones.
  Eigen::MatrixXd Js(static_cast<Eigen::Index>(out.catalog.size()),
                     static_cast<Eigen::Index>(catalog.size()));
  for (std::size_t i = 0; i < out.catalog.size(); ++i)
    for (std::size_t j = 0; j < catalog.size(); ++j)
      Js(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          J(out.catalog[i], catalog[j]);
  out.covariance = Js * covariance * Js.transpose();
  return out;
}

}  // namespace sinscal
