// The one state layout of the estimators: named blocks {index, size}, the total size derived from
// the blocks that are on. No state index appears anywhere else as a number.
//
// Navigation errors (always on): attitude phi_n (3, rad), velocity dv_n (3, m/s; the vertical
// component can be switched off), position dp_n (3, m); definitions in docs/conventions.md. Then
// one block per coefficient family of the family table (models/coefficient_families.hpp), in its
// order: base families always, extended ones when switched on (sensor profile or `--terms`).
// Coefficients fixed by a convention (the accelerometer-triad body frame, a reference lever arm)
// are not states. Then, when on, the table base attitude (3, rad, NED: a random constant, not an
// IMU coefficient; docs/conventions.md "Table base and mounting"), and last the table's
// orientation error in the current dwell (3, rad, NED: constant within a dwell, drawn anew at
// each), and last the bias instability's Gauss-Markov wander of the gyros and the accelerometers
// (6, rad/s and m/s^2, the compensated inputs' axes): the coefficient states are
// [nav_size, nav_size + coefficient_states()).

#pragma once

#include <set>
#include <string>
#include <vector>

namespace sinscal {

/// A block of a state or input vector.
struct Block {
  int index;
  int size;
};

/// The navigation-error blocks. The default is the full 9-state INS error (closed form).
struct NavBlocks {
  Block attitude{0, 3};  // phi_n, rad
  Block velocity{3, 3};  // dv_n, m/s (north, east[, down])
  Block position{6, 3};  // dp_n, m (north, east, down)
  constexpr int size() const { return position.index + position.size; }
};

/// Largest number of navigation-error states (fixed-size storage in the filter).
constexpr int kMaxNavStates = 9;

struct StateLayoutOptions {
  bool vertical_velocity = true;
  /// Extended families switched on, by family name (the base families are always on).
  std::set<std::string> extended;
  /// Body frame defined by the accelerometer triad (calibration without known attitude): the
  /// accelerometer misalignments xy, xz, yz are zero by this convention and not estimated; the
  /// block holds yx, zx, zy only (docs/conventions.md).
  bool accel_triad_frame = false;
  /// Further coefficients fixed at zero by a stated convention (e.g. a reference lever arm).
  std::vector<std::string> fixed;
  /// The table base attitude as states (the table-attitude updates then measure the attitude
  /// relative to the base).
  bool base_attitude = false;
  /// The table's orientation error of the current dwell as states: the attitude updates then
  /// repeat through each dwell (the table holds its orientation; its error is the same at every
  /// update of the dwell), so the gyros' drift at rest is measured against the still table.
  bool dwell_orientation = false;
  /// The bias instability's Gauss-Markov wander as states (gyro x, y, z, accelerometer x, y, z):
  /// the bias families then hold the constant bias, and the wander, bounded at the bias
  /// instability, is not carried as a random walk of them.
  bool bias_wander = false;

  bool on(const std::string& family) const;
  /// Switches an extended family; throws std::invalid_argument for an unknown or base family.
  void set(const std::string& family, bool on);
};

/// Switches extended families on or off from a comma-separated list of `--terms` names or family
/// names, e.g. "k2,-lever_arm,+gyro.g_sensitivity" (models/coefficient_families.hpp), plus
/// vertical_velocity; a leading '-' switches off, none or '+' on. Throws std::invalid_argument
/// naming an unknown term and the known ones.
void apply_terms(StateLayoutOptions& options, const std::string& terms);

/// Fixes the inner lever arm of accelerometer `axis` ("x", "y" or "z") at zero: the IMU reference
/// point becomes that accelerometer's proof mass (the reference MATLAB toolbox's convention; a
/// common shift of all arms is unobservable without zero velocity while turning or a known
/// position). Throws std::invalid_argument for another axis.
void set_lever_arm_reference(StateLayoutOptions& options, const std::string& axis);

struct StateLayout {
  // Navigation errors.
  Block attitude{-1, 0};
  Block velocity{-1, 0};
  Block position{-1, 0};
  /// A coefficient family's block.
  struct CoefficientBlock {
    std::string family;  // e.g. "gyro.bias"
    Block block;
    std::vector<int> catalog;  // coefficient_catalog() index of each state of the block
  };
  std::vector<CoefficientBlock> coefficients;  // family-table order, on families only
  /// The table base attitude's error (true minus estimated rotation vector, rad, NED), after the
  /// coefficients; off (size 0) unless StateLayoutOptions::base_attitude.
  Block base{-1, 0};
  /// The table's orientation error in the current dwell (true minus estimated rotation vector,
  /// rad, NED; reset at each dwell), after the base; off (size 0) unless
  /// StateLayoutOptions::dwell_orientation.
  Block dwell_orientation{-1, 0};
  /// The bias wander (true minus estimated, rad/s then m/s^2, in the compensated inputs' axes),
  /// last; off (size 0) unless StateLayoutOptions::bias_wander.
  Block wander{-1, 0};
  int size = 0;
  int nav_size = 0;  // the navigation errors come first: states [0, nav_size)
  bool accel_triad_frame = false;
  std::vector<int> fixed;     // catalog indices fixed by a convention (not states)
  std::vector<int> state_of;  // catalog index -> state index, -1 when not a state

  static StateLayout make(const StateLayoutOptions& options);
  NavBlocks nav() const { return {attitude, velocity, position}; }
  /// The block of a family, or null when it is not in the state.
  const CoefficientBlock* block(const std::string& family) const;
  /// Coefficient blocks that are on, with the catalog family each one holds.
  const std::vector<CoefficientBlock>& coefficient_blocks() const { return coefficients; }
  static bool on(const Block& b) { return b.size > 0; }
  /// Number of coefficient states (they follow the navigation errors).
  int coefficient_states() const {
    return size - nav_size - base.size - dwell_orientation.size - wander.size;
  }
  /// Catalog indices of the coefficients fixed at zero by a convention (not states).
  const std::vector<int>& fixed_by_convention() const { return fixed; }
};

}  // namespace sinscal
