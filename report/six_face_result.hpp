// Result files of the six-face calibration (docs/formats.md, "Six-face result"): the 24 base
// coefficients in the result schema of the other methods (the faces' frame: every misalignment
// estimated), and its sections: method, faces (placement tilts), turns, what the procedure cannot
// determine, and the raw-count view of a log in counts.
#pragma once

#include <nlohmann/json.hpp>

#include "filter/six_face/six_face.hpp"
#include "report/result.hpp"
#include "rig/io/log_io.hpp"

namespace sinscal {

ResultCoefficients result_coefficients(const SixFaceResult& r);
/// The sections after "coefficients"; `log` gives the raw-count view (triads logged in counts
/// with the sensors' axes as the body's).
nlohmann::ordered_json result_sections(const SixFaceResult& r, const SixFaceOptions& o,
                                       const LogFormat& log);
/// The terminal table: coefficients, faces, turns, what is not determined.
std::string six_face_table(const SixFaceResult& r, const ResultCoefficients& truth);

}  // namespace sinscal
