// The certificate's diagnosis summary, from what `sinscal diagnose --out DIR` wrote:
// DIR/diagnosis.json (findings, what the plan cannot separate, ambiguous sets) and
// DIR/residuals.png when it was drawn.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "report/certificate.hpp"

namespace sinscal {

namespace {

using Json = nlohmann::json;

std::string number(const Json& j, const char* key, const char* format) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_number()) return "-";
  char b[64];
  std::snprintf(b, sizeof b, format, j[key].get<double>());
  return b;
}

std::string rms(const Json& f, const char* key) {
  const Json r = f.value(key, Json::object());
  const Json u = f.value("residual_unit", Json::object());
  std::string out;
  for (const char* triad : {"accel", "gyro"})
    if (r.contains(triad) && r[triad].is_number())
      out += (out.empty() ? "" : ", ") + number(r, triad, "%.4g") + " " + u.value(triad, "");
  return out.empty() ? "-" : out;
}

}  // namespace

CertificateSection diagnosis_section(const std::string& dir) {
  namespace fs = std::filesystem;
  const std::string path = (fs::path(dir) / "diagnosis.json").string();
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw std::runtime_error(dir +
                             ": not a directory (--diagnosis takes the --out DIR of "
                             "sinscal diagnose)");
  std::ifstream in(path);
  if (!in)
    throw std::runtime_error(path +
                             ": cannot open (--diagnosis takes the --out DIR of sinscal "
                             "diagnose, which holds diagnosis.json)");
  Json j;
  try {
    j = Json::parse(in);
  } catch (const Json::exception& e) {
    throw std::runtime_error(path + ": not a sinscal diagnosis (not JSON: " + e.what() + ")");
  }
  if (!j.is_object() || !j.contains("findings") || !j["findings"].is_array())
    throw std::runtime_error(path + ": not a sinscal diagnosis (no \"findings\" array)");
  CertificateSection s;
  s.title = "Diagnosis: what the calibrated model misses";
  const std::string session = j.value("session", "");
  const Json method = j.value("method", Json::object());
  s.facts.emplace_back("Diagnosis of", session.empty() ? std::string("-") : session);
  s.facts.emplace_back(
      "Test",
      method.value("name", std::string("-")) +
          (method.contains("alpha") ? " (family-wise level " + number(method, "alpha", "%g") + ")"
                                    : ""));
  if (j["findings"].empty()) {
    s.paragraphs.push_back(
        "No finding: no effect outside the calibrated model is significant in this session.");
  } else {
    s.table.header = {
        "round", "effect", "from", "log10 p", "residual RMS before", "residual RMS after"};
    for (const auto& f : j["findings"]) {
      const Json st = f.value("statistic", Json::object());
      s.table.rows.push_back({f.contains("round") ? f["round"].dump() : "-",
                              f.value("title", f.value("effect", std::string("-"))),
                              f.value("source", std::string("-")), number(st, "log10_p", "%.1f"),
                              rms(f, "residual_rms_before"), rms(f, "residual_rms_after")});
    }
  }
  for (const auto& n : j.value("not_separable", Json::array()))
    s.paragraphs.push_back("Not separable by this plan: " + n.value("effect", std::string("?")) +
                           " (needs " + n.value("separated_by", std::string("?")) + ")");
  for (const auto& a : j.value("ambiguous", Json::array())) {
    std::string names;
    for (const auto& e : a.value("effects", Json::array()))
      names += (names.empty() ? "" : " / ") + (e.is_string() ? e.get<std::string>() : e.dump());
    s.paragraphs.push_back("Ambiguous on this plan: " + names);
  }
  const std::string png = (fs::path(dir) / "residuals.png").string();
  if (fs::is_regular_file(png, ec)) {
    std::ifstream p(png, std::ios::binary);
    std::ostringstream bytes;
    bytes << p.rdbuf();
    s.png = bytes.str();
    s.png_alt = "residuals before and after the findings";
  }
  return s;
}

}  // namespace sinscal
