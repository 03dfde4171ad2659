// Simulated six-face and known-turn sessions (Ferraris et al. 1995, filter/six_face/six_face.hpp)
// for the tests: a hand puts the unit on each of its six faces in turn (each face tilted by a
// random placement error, at a random heading, held with a slight tremor), then turns it by hand
// through a full turn about each body axis with that axis up (the total angle off by a random
// error, the rate uneven: the turn's axis wobbles in the body), with rests between. Every part is
// labelled with imucal's names.
// The procedure and its model: docs/methods/six-face.md.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "models/earth.hpp"
#include "models/units.hpp"
#include "rig/motion.hpp"

namespace sinscal {

/// What a six-face session declares ([six_face] in session.ini, docs/formats.md): the labels of
/// its parts and how well the hand did them.
struct FerrarisDeclaration {
  /// Labels of the faces with +x, -x, +y, -y, +z, -z up (imucal's names by default), and of the
  /// turns about x, y, z (the turned axis up).
  std::array<std::string, 6> faces = {"x_p", "x_a", "y_p", "y_a", "z_p", "z_a"};
  std::array<std::string, 3> turns = {"x_rot", "y_rot", "z_rot"};
  double turn_angle = 360.0 * units::deg;   // rad, right-handed about the up-pointing axis
  double turn_accuracy = 1.0 * units::deg;  // rad, 1-sigma of each turn's total angle
  double face_accuracy = 0.5 * units::deg;  // rad, 1-sigma of each face's two placement tilts
  double min_rest = 1.0;                    // s: shortest face
  /// s at each end of a turn's part whose mean specific force gives the gravity direction
  /// before and after it (a turn's part starts and ends at rest).
  double turn_edge = 0.2;
  /// s: the longest period of the hand's tremor or sway on the faces. A rest's noise is judged
  /// from the scatter of its means over blocks at least this long (shorter ones show the tremor's
  /// back-and-forth, not how the rest's mean scatters).
  double rest_correlation = 0.25;
};

class IniFile;
/// The [six_face] section (every key optional); throws ConfigError naming file, line and key.
FerrarisDeclaration read_ferraris_declaration(const IniFile& ini);

struct FerrarisOptions {
  double rest = 6.0;                           // s on each face
  double face_tilt = 0.5 * units::deg;         // rad, 1-sigma of each face's two tilt angles
  double move = 3.0;                           // s: the hand's move between two parts
  double pause = 2.0;                          // s at rest before and after each turn
  double turn = 6.0;                           // s: duration of each turn
  double turn_angle = 360.0 * units::deg;      // rad, declared (right-handed about the up axis)
  double turn_angle_error = 1.0 * units::deg;  // rad, 1-sigma of the angle the hand really turns
  double wobble = 3.0 * units::deg;            // rad: the turn's axis leans this far in the body
  double label_margin = 0.5;  // s of the rests before and after a turn inside its label
  /// The hand's tremor on the faces: every half `tremor_period` s a new small attitude offset
  /// (each component 1-sigma `tremor`, rad) reached by a short turn, so a rest ends off its start
  /// (0: the faces rest still).
  double tremor = 0.02 * units::deg;
  double tremor_period = 0.2;  // s
};

/// A labelled part of a simulated session.
struct LabelledPart {
  std::string label;
  double t_start = 0.0, t_end = 0.0;  // s
};

struct FerrarisSession {
  Motion motion;
  std::vector<LabelledPart> parts;  // x_p x_a y_p y_a z_p z_a x_rot y_rot z_rot, in that order
  /// The label of time t ("" between parts).
  std::string label_at(double t) const;
};

/// The same seed gives the same session. Throws std::invalid_argument for bad options.
FerrarisSession ferraris_session(const Site& site, const FerrarisOptions& options,
                                 std::uint64_t seed);

}  // namespace sinscal
