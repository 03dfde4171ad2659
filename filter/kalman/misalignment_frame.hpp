// The frame the misalignments are reported in (docs/conventions.md "The misalignment frame"):
// relative to the table's platform (the body frame of calibration with table-attitude updates,
// bounded by the table's attitude accuracy) or within the triads (the accelerometer triad as
// the body frame, the convention without attitude updates). An estimate made relative to the
// table converts to the triad frame after the estimation, with its full covariance: the common
// rotation between the frames, which carries the table's attitude uncertainty, drops out.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "models/imu_error_model.hpp"

namespace sinscal {

/// ByMode: the estimator's own frame (table with attitude updates, triad without).
enum class MisalignmentFrame { ByMode, Table, Triad };

/// "table" or "triad" (ByMode has no name: resolve it first).
std::string misalignment_frame_name(MisalignmentFrame frame);
/// "table" or "triad"; throws std::invalid_argument naming the text and the names.
MisalignmentFrame parse_misalignment_frame(const std::string& text);
/// The frame a run reports in: `requested`, or by mode when ByMode. Throws std::invalid_argument
/// for the table frame without attitude updates (nothing observes the table's axes then).
MisalignmentFrame resolve_misalignment_frame(MisalignmentFrame requested, bool attitude_updates);
/// The sentence a certificate or a table states the frame in.
std::string misalignment_frame_words(MisalignmentFrame frame);

/// The Jacobian of in_accel_triad_frame(model).vector() with respect to model.vector() (SI, the
/// catalog's order on both sides), exact at `model`: the rotation Q that makes the accelerometer
/// matrix A lower triangular (L = A Q) moves by dQ = Q W, W skew with the strictly upper part of
/// -L^-1 dA Q; every linear part turned by Q moves with it.
Eigen::MatrixXd accel_triad_frame_jacobian(const ImuErrorModel& model);

/// Catalog indices of the coefficients zero by the triad convention (accel.misalignment.xy, .xz,
/// .yz).
const std::vector<int>& triad_fixed_coefficients();

/// An estimate's values (catalog order, SI) and the covariance of its states (`catalog`: the
/// catalog index of each row) in the accelerometer-triad frame: values by in_accel_triad_frame,
/// the covariance J P J^T with J the Jacobian above. The states fixed by the convention leave the
/// covariance; the coefficients that are not states keep their values.
struct TriadFrameEstimate {
  Eigen::VectorXd values;
  Eigen::MatrixXd covariance;
  std::vector<int> catalog;
  Eigen::MatrixXd jacobian;  // of the conversion, catalog by catalog (accel_triad_frame_jacobian)
};
TriadFrameEstimate to_accel_triad_frame(const Eigen::VectorXd& values,
                                        const Eigen::MatrixXd& covariance,
                                        const std::vector<int>& catalog);

}  // namespace sinscal
