// State layout of the error-state Kalman filter: named blocks {index, size}, the total size
// derived from the blocks that are on. No index appears anywhere else as a number.
//
// Navigation errors (always on): attitude phi_n (3, rad), velocity dv_n (3, m/s; the vertical
// component is on by default), position dp_n (3, m). Coefficient blocks: the families of the
// coefficient catalog (models/imu_error_model.hpp), base ones always on, extended ones switched on
// by the options (from the sensor profile or the command line).
#pragma once

#include <string>
#include <vector>

#include "filter/ins_error_model.hpp"

namespace sinscal {

struct StateLayoutOptions {
  bool vertical_velocity = true;
  bool accel_k2 = false;
  bool lever_arm = false;
  bool time_delay = false;
  bool g_sensitivity = false;
  bool scale_asym = false;
  /// Body frame defined by the accelerometer triad (calibration without known attitude): the
  /// accelerometer misalignments xy, xz, yz are zero by this convention and not estimated; the
  /// block holds yx, zx, zy only (docs/conventions.md).
  bool accel_triad_frame = false;
};

/// Switches extended blocks on or off from a comma-separated list, e.g.
/// "k2,-lever_arm,+g_sensitivity": names k2, lever_arm, time_delay, g_sensitivity, scale_asym,
/// vertical_velocity; a leading '-' switches off, none or '+' on. Throws std::invalid_argument
/// naming an unknown term.
void apply_terms(StateLayoutOptions& options, const std::string& terms);

struct StateLayout {
  // Navigation errors.
  Block attitude{-1, 0};
  Block velocity{-1, 0};  // 2 or 3 components (north, east[, down])
  Block position{-1, 0};
  // Coefficient blocks, in coefficient-catalog units (SI).
  Block gyro_bias{-1, 0};
  Block gyro_scale{-1, 0};
  Block gyro_misalignment{-1, 0};
  Block accel_bias{-1, 0};
  Block accel_scale{-1, 0};
  Block accel_misalignment{-1, 0};
  Block accel_k2{-1, 0};
  Block gyro_scale_asym{-1, 0};
  Block accel_scale_asym{-1, 0};
  Block gyro_g_sensitivity{-1, 0};
  Block accel_lever_arm{-1, 0};
  Block time_delay{-1, 0};
  int size = 0;

  static StateLayout make(const StateLayoutOptions& options);
  /// Coefficient blocks that are on, with the catalog family each one holds.
  struct CoefficientBlock {
    std::string family;  // e.g. "gyro.bias"
    Block block;
    std::vector<int> catalog;  // coefficient_catalog() index of each state of the block
  };
  std::vector<CoefficientBlock> coefficient_blocks() const;
  static bool on(const Block& b) { return b.size > 0; }
  /// Catalog indices of the coefficients fixed at zero by the frame convention (not states).
  std::vector<int> fixed_by_convention() const;
  bool accel_triad_frame = false;
};

}  // namespace sinscal
