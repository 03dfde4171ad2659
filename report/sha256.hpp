// SHA-256 (FIPS 180-4) of a file, for the identity of a calibration's inputs: the hash a result
// and its certificate record of each log.
#pragma once

#include <cstdint>
#include <string>

namespace sinscal {

/// The SHA-256 of `bytes` as 64 lowercase hex digits.
std::string sha256_hex(const std::string& bytes);

/// The SHA-256 of a file's contents as 64 lowercase hex digits, read in blocks (memory constant in
/// the file's size). Throws std::runtime_error naming the file when it cannot be read.
std::string sha256_file(const std::string& path, std::uintmax_t* bytes = nullptr);

}  // namespace sinscal
