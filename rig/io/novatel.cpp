// NovAtel RAWIMUSA / RAWIMUSXA / RAWIMUA / RAWIMUXA ASCII logs: each line CRC-32 checked, the
// raw counts turned into increments with the receiver's IMU scale factors (gyro_scale,
// accel_scale), the IMU's y axis negated as the logs define it.
#include <boost/crc.hpp>
#include <charconv>
#include <cmath>
#include <cstdio>

#include "models/config.hpp"
#include "rig/io/log_keys.hpp"

namespace sinscal {

namespace {

// NovAtel's 32-bit CRC of ASCII logs: polynomial 0x04C11DB7 reflected (0xEDB88320), initial value
// 0, no final XOR, over the text between the '%' or '#' and the '*'.
std::uint32_t novatel_crc32(const char* data, std::size_t size) {
  boost::crc_optimal<32, 0x04C11DB7, 0, 0, true, true> crc;
  crc.process_bytes(data, size);
  return crc.checksum();
}

}  // namespace

namespace log_keys {

void read_novatel_format(const IniFile& ini, const std::string& base_dir, double rate_hz,
                         bool segmented, std::vector<std::string>& keys, LogFormat& f) {
  for (const char* k : {"gyro_unit", "gyro_scale", "gyro_axes", "gyro_saturation", "accel_unit",
                        "accel_scale", "accel_axes", "accel_saturation", "status_mask"})
    keys.emplace_back(k);
  ini.check_keys("log", keys);
  f.kind = LogFormat::Kind::NovAtel;
  f.native = false;
  f.header_lines = 0;
  if (!segmented) f.file = path_in(base_dir, ini.get_string("log.file"));
  for (const char* k : {"log.gyro_scale", "log.accel_scale"})
    if (!ini.has(k))
      throw ConfigError(ini.path() + ": [log] format = novatel: missing '" +
                        std::string(k).substr(4) +
                        "', the increment per count of the IMU inside (the receiver's raw "
                        "IMU scale factors table)");
  f.gyro = read_triad(ini, "gyro", true, rate_hz, true);
  f.accel = read_triad(ini, "accel", false, rate_hz, true);
  if (ini.has("log.status_mask")) {
    std::string m = ini.get_string("log.status_mask");
    if (m.size() > 2 && m[0] == '0' && (m[1] == 'x' || m[1] == 'X')) m = m.substr(2);
    const auto r = std::from_chars(m.data(), m.data() + m.size(), f.status_mask, 16);
    if (m.empty() || r.ec != std::errc() || r.ptr != m.data() + m.size())
      throw ConfigError(ini.where("log.status_mask") +
                        "expected a hexadecimal 32-bit mask like 0x00000004");
  }
  f.columns = {"t", "gx", "gy", "gz", "ax", "ay", "az"};
}

}  // namespace log_keys

bool LogReader::read_novatel_record() {
  loc_ = &main_;
  bool nl = true;
  for (;;) {
    if (!read_line(main_, text_, nl)) {
      if (novatel_message_.empty())
        fail("no RAWIMUSA, RAWIMUSXA, RAWIMUA or RAWIMUXA log in this file (" +
             std::to_string(novatel_other_) + " other lines)");
      return false;
    }
    const std::string& l = text_;
    if (l.empty() || (l[0] != '%' && l[0] != '#')) {
      ++novatel_other_;
      continue;
    }
    const std::size_t name_end = l.find_first_of(",;*");
    const std::string name = l.substr(1, name_end == std::string::npos ? l.npos : name_end - 1);
    if (name != "RAWIMUSA" && name != "RAWIMUSXA" && name != "RAWIMUA" && name != "RAWIMUXA") {
      ++novatel_other_;
      continue;
    }
    if (novatel_message_.empty()) novatel_message_ = name;
    if (name != novatel_message_) {  // the first raw IMU log found is the one read
      ++novatel_other_;
      continue;
    }
    // CRC-32 of the text between the sync character and '*'.
    const std::size_t star = l.rfind('*');
    if (star == std::string::npos) {
      if (!nl) fail("truncated line: the file ends in the middle of a log");
      bad_sample("no '*' and CRC at the end of the log: a damaged line");
    }
    const std::string crc_text = l.substr(star + 1);
    std::uint32_t crc = 0;
    const auto r = std::from_chars(crc_text.data(), crc_text.data() + crc_text.size(), crc, 16);
    if (crc_text.size() != 8 || r.ec != std::errc() || r.ptr != crc_text.data() + crc_text.size()) {
      if (!nl && crc_text.size() < 8) fail("truncated line: the file ends in the middle of a log");
      bad_sample("CRC '" + crc_text + "' is not 8 hexadecimal digits: a damaged line");
    }
    const std::uint32_t computed = novatel_crc32(l.data() + 1, star - 1);
    if (computed != crc) {
      char msg[160];
      std::snprintf(msg, sizeof msg,
                    "CRC-32 mismatch: the log says %08x, its text gives %08x (a damaged line)",
                    static_cast<unsigned>(crc), static_cast<unsigned>(computed));
      bad_sample(msg);
    }
    const std::size_t semi = l.find(';');
    if (semi == std::string::npos || semi > star) fail("no ';' after the log header");
    std::vector<std::string> body;
    for (std::size_t pos = semi + 1;;) {
      const std::size_t comma = l.find(',', pos);
      if (comma == std::string::npos || comma > star) {
        body.push_back(l.substr(pos, star - pos));
        break;
      }
      body.push_back(l.substr(pos, comma - pos));
      pos = comma + 1;
    }
    const bool extended = name == "RAWIMUSXA" || name == "RAWIMUXA";
    const std::size_t expected = extended ? 11 : 9;
    if (body.size() != expected)
      fail(name + ": expected " + std::to_string(expected) + " fields after the header, found " +
           std::to_string(body.size()));
    auto integer = [&](std::size_t i, int base) {
      const std::string& b = body[i];
      long long v = 0;
      const char* p = b.data();
      if (base == 10 && !b.empty() && b[0] == '+') ++p;
      const auto rr = std::from_chars(p, b.data() + b.size(), v, base);
      if (b.empty() || rr.ec != std::errc() || rr.ptr != b.data() + b.size())
        bad_sample(name + " field " + std::to_string(i + 2) + " '" + b + "' is not " +
                   (base == 16 ? "hexadecimal" : "a whole number"));
      return v;
    };
    const std::size_t k = extended ? 2 : 0;
    if (extended) {
      const long long info = integer(0, 16);
      if (info & 2) fail("the IMU data are encrypted (IMU Info bit 1): they cannot be used");
      if (info & 1)
        bad_sample("the receiver flags an IMU error (IMU Info bit 0; IMU status " + body[4] + ")");
    }
    const long long week = integer(k, 10);
    double sow = 0.0;
    {
      const std::string& b = body[k + 1];
      const auto rr = std::from_chars(b.data(), b.data() + b.size(), sow);
      if (b.empty() || rr.ec != std::errc() || rr.ptr != b.data() + b.size())
        bad_sample(name + " seconds into the week '" + b + "' is not a number");
    }
    if (week < 0 || week > 100000 || !(sow >= 0.0 && sow < 604800.0))
      bad_sample(name + ": GNSS week " + body[k] + ", seconds " + body[k + 1] + " out of range");
    const long long status = integer(k + 2, 16);
    if (static_cast<std::uint32_t>(status) & f_.status_mask) {
      char msg[160];
      std::snprintf(msg, sizeof msg, "IMU status %08llx has bits %08x of status_mask set",
                    static_cast<unsigned long long>(status),
                    static_cast<unsigned>(static_cast<std::uint32_t>(status) & f_.status_mask));
      bad_sample(msg);
    }
    // Body: z, -y, x accelerometer counts, then z, -y, x gyro counts (velocity and angle
    // increments per sample, IMU body frame).
    const double z_a = static_cast<double>(integer(k + 3, 10));
    const double my_a = static_cast<double>(integer(k + 4, 10));
    const double x_a = static_cast<double>(integer(k + 5, 10));
    const double z_g = static_cast<double>(integer(k + 6, 10));
    const double my_g = static_cast<double>(integer(k + 7, 10));
    const double x_g = static_cast<double>(integer(k + 8, 10));
    if (novatel_week0_ < 0) novatel_week0_ = static_cast<long>(week);
    const double t = sow + 604800.0 * static_cast<double>(week - novatel_week0_);
    fields_.assign({t, x_g, -my_g, z_g, x_a, -my_a, z_a});
    return true;
  }
}

}  // namespace sinscal
