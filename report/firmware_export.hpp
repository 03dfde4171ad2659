// The compensation of a calibration result in the form a firmware applies (sinscal export,
// docs/formats.md "Firmware export"): the biases and the correction matrices C = A^-1 of both
// triads (A = I + diag(k) + M, docs/conventions.md), the extended terms the result estimated, each
// with the order and formula in which the firmware applies it, in SI units and the result's body
// frame, with sigmas; written as JSON, YAML or a C header.
//
// The firmware's inverse of the error model (docs/conventions.md), per sample, outputs y_g (rad/s),
// y_a (m/s^2) time-aligned (step 0 below), t the time since the start of the calibration session:
//   0. accelerometers late by tau: take the accelerometer output at t + tau (linear interpolation)
//   1. f0 = C_a (y_a - b_a - d_a t);  u_g = y_g - b_g - d_g t - G f0;  v_g = C_g u_g;
//      omega_ib_b = C_g (u_g - a_g .* |v_g|)
//   2. s_i = A_a(i,:) . (omega_dot x r_i + omega x (omega x r_i))  (size effect)
//   3. u_a = y_a - b_a - d_a t - s;  v_a = C_a u_a;
//      f_ib_b = C_a (u_a - a_a .* |v_a| - k2 .* v_a .* v_a)
// The nonlinear terms are evaluated at the linear estimate v (first order); the exact inverse
// (ImuErrorModel::compensate) differs by a second-order amount the export states.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "models/imu_error_model.hpp"

namespace sinscal {

struct FirmwareExportOptions {
  /// Export a result whose verdict failed (plausibility gate, divergence, an early stop, no
  /// convergence), coefficients the data did not determine (exported as zero, listed) and
  /// coefficients beyond their family's physical range (exported as given, in `warnings`).
  bool force = false;
};

/// A calibration result read for export: the estimated model and its sigmas, in SI.
struct FirmwareExport {
  std::string source_file;  // the result file as given
  std::uintmax_t source_bytes = 0;
  std::string method;      // the result's method.name: "kf", "closed-form", "table-free", ...
  std::string body_frame;  // "table platform", "accelerometer triad", "box faces"
  std::string body_frame_note;
  /// The frame of the misalignments, "table" or "triad" (ResultFile::misalignment_frame); empty
  /// for a method without one (six-face: the box's faces).
  std::string misalignment_frame;
  /// Where omega_ib_b and f_ib_b are (the point the lever arms are relative to); empty without
  /// lever arms.
  std::string reference_point;
  ImuErrorModel model;  // the estimate; absent families are zero
  ImuErrorModel sigma;  // 1-sigma of every coefficient (0: none given)
  /// Families the result has, in the family table's order (the base ones always).
  std::vector<std::string> families;
  std::vector<std::string> fixed_by_convention;  // zero by the result's convention
  std::vector<std::string> unobservable;         // not determined: exported as zero (--force)
  std::vector<std::string> warnings;  // failed verdicts, implausible coefficients (--force)

  bool has(const std::string& family) const;
};

/// Reads a calibration result (any method) for export, through read_result_file
/// (report/result.hpp). Throws std::runtime_error naming the file and the cause: not a result (not
/// JSON, no coefficients, no method: a truth file), an unknown coefficient or unit, a family with
/// coefficients missing (the base 24 are required), a coefficient beyond its family's physical
/// range, a failed verdict or coefficients the data did not determine (the last three unless
/// `force`: then listed in `warnings` and `unobservable`).
FirmwareExport read_result_for_export(const std::string& path,
                                      const FirmwareExportOptions& options = {});

enum class ExportFormat { Json, Yaml, CHeader };
/// "json", "yaml", "c-header"; throws std::invalid_argument naming the accepted ones.
ExportFormat export_format_from_name(const std::string& name);

/// The firmware's steps (the header comment above) as text lines, with the terms present.
std::vector<std::string> export_formula(const FirmwareExport& e);
/// The export in one format (a complete file's text).
std::string render_export(const FirmwareExport& e, ExportFormat format);

}  // namespace sinscal
