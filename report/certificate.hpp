// The calibration certificate (`sinscal report`, docs/formats.md "Calibration certificate"): one
// self-contained HTML page built from a result file (and a diagnosis directory): the unit and the
// data it was calibrated from with their hashes, the coefficients with sigma and unit, the
// verdict, the installation, the convergence, the residuals, the noise and the diagnosis, each
// when the result has it. Everything the page shows is read here into a Certificate; the page is
// written from that alone (certificate_html), so the builder is tested without files.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "report/result.hpp"

namespace sinscal {

/// A table of text cells.
struct CertificateTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
};

/// One part of the page after the coefficients.
struct CertificateSection {
  std::string title;
  std::vector<std::string> paragraphs;
  std::vector<std::pair<std::string, std::string>> facts;  // label, value
  CertificateTable table;
  std::string png;  // a picture's bytes, inline as a data: URI (empty: none)
  std::string png_alt;
};

/// An input file of the calibration as the result records it, checked against the file now.
struct CertificateFile {
  std::string role;    // "log", "session", "sensor profile", ...
  std::string path;    // as recorded
  std::string sha256;  // as recorded (empty: not available)
  std::optional<std::uintmax_t> bytes;
  std::string state;  // "unchanged", "changed since the calibration", "not found now", ...
};

enum class Verdict { Pass, Warning, Fail };

struct Certificate {
  std::string unit_name;  // the sensor profile's name, else the session's
  std::vector<std::pair<std::string, std::string>> identity;  // label, value
  std::vector<CertificateFile> files;
  std::string files_note;  // why there are no hashes, when there are none
  ResultCoefficients coefficients;
  /// The misalignments' frame, "table" or "triad" (ResultFile::misalignment_frame; empty: the
  /// method has none).
  std::string misalignment_frame;
  Verdict verdict = Verdict::Pass;
  std::string verdict_title;  // "Converged", "Diverged", ...
  std::vector<std::string> verdict_reasons;
  std::vector<CertificateSection> sections;
  std::string issued;  // "sinscal 1.2.0, 2026-12-01T09:30:00Z"
  /// The coverage factor k of the expanded uncertainty U = k sigma shown beside each value.
  double coverage_factor = 2.0;
  /// The conditions of the calibration: label, value (the log's temperature, the soaks', ...).
  std::vector<std::pair<std::string, std::string>> conditions;
  /// Coefficients beyond their family's physical range, certified with --force (each with why).
  std::vector<std::string> forced;
  std::string approver;  // the person who approves the certificate (empty: a blank to sign)
};

struct CertificateOptions {
  std::string result_path;
  std::string diagnosis_dir;  // empty: none
  std::string monitor_path;   // empty: the one the result records
  std::string gnuplot = "gnuplot";
  /// Certify coefficients beyond their family's physical range (noted on the page).
  bool force = false;
  double coverage_factor = 2.0;  // k of U = k sigma; 1 <= k <= 10
  std::string approver;          // --approved-by
};

/// Reads a result file (every method's) and, when given, a diagnosis directory. Throws
/// std::runtime_error naming the file and the cause: not JSON, not a result (no coefficients, a
/// truth file, an unknown coefficient, a coefficient beyond its family's physical range unless
/// `force`: read_result_file), a diagnosis directory without diagnosis.json.
Certificate read_certificate(const CertificateOptions& options);

/// The convergence section: the largest sigma of each coefficient family over time, drawn by
/// gnuplot from the monitor file (said so on the page when there is none).
CertificateSection convergence_section(const std::string& monitor_path,
                                       const std::string& sensor_profile, double converged_at_t,
                                       const std::string& gnuplot);

/// The summary of `sinscal diagnose --out DIR`: findings, what the plan cannot separate, the
/// residual plot. Throws std::runtime_error naming the directory when diagnosis.json is missing
/// or not a diagnosis.
CertificateSection diagnosis_section(const std::string& dir);

/// The conditions of a calibration as its result (and its log) give them: the temperature of
/// the log where it has temperature columns (read through the session the provenance names, when
/// the log is unchanged), the soaks' temperatures of a thermal result, the site.
std::vector<std::pair<std::string, std::string>> calibration_conditions(
    const nlohmann::json& result);

/// A result's method key as a reader of the certificate says it ("attitude_from": "Attitude
/// updates from"); unknown keys in words, their unit suffix in brackets ("window_s": "Window [s]").
std::string method_label(const std::string& key);

/// The page: one HTML document, CSS inline, pictures as data: URIs, no script, an A4 print style.
std::string certificate_html(const Certificate& certificate);

/// Text safe inside HTML elements and quoted attributes (& < > " ' escaped).
std::string html_escaped(const std::string& text);
/// Base64 (RFC 4648) of bytes.
std::string base64(const std::string& bytes);

/// The PDF printer is not installed.
struct ChromiumMissing : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Prints `html_path` to `pdf_path` with headless Chromium (Debian's `chromium`), through a
/// temporary file renamed when complete. Throws ChromiumMissing when `chromium` cannot be run,
/// std::runtime_error when it fails or writes no PDF.
void print_pdf(const std::string& html_path, const std::string& pdf_path,
               const std::string& chromium = "chromium");

}  // namespace sinscal
