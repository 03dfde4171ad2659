// certificate_html: the page. One HTML document, no script, no network: the CSS inline, pictures
// as data: URIs; a print style for A4 (tables' headers repeated, rows and figures kept whole).
#include <cstdio>
#include <sstream>

#include "filter/kalman/misalignment_frame.hpp"
#include "models/coefficient_families.hpp"
#include "report/certificate.hpp"
#include "report/coefficient_table.hpp"

namespace sinscal {

std::string html_escaped(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string base64(const std::string& bytes) {
  static const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) |
                       static_cast<unsigned char>(bytes[i + 2]);
    for (int s = 18; s >= 0; s -= 6) out += alphabet[(v >> s) & 63];
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (rest == 2) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += alphabet[(v >> 18) & 63];
    out += alphabet[(v >> 12) & 63];
    out += rest == 2 ? alphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

namespace {

const char* kStyle = R"(
:root { --ink: #1b2330; --muted: #5b6675; --rule: #c9d1db; --band: #14324f; --soft: #f2f5f8; }
* { box-sizing: border-box; }
body { font-family: "DejaVu Sans", "Liberation Sans", Arial, sans-serif; color: var(--ink);
       font-size: 13px; line-height: 1.4; margin: 0; background: #e9edf1; }
.page { max-width: 1000px; margin: 24px auto; background: #fff; padding: 32px 40px 28px;
        box-shadow: 0 1px 4px rgba(0,0,0,.15); }
header { border-bottom: 3px solid var(--band); padding-bottom: 12px; margin-bottom: 18px;
         display: flex; justify-content: space-between; align-items: flex-end; gap: 24px; }
header .kicker { font-size: 11px; letter-spacing: .14em; text-transform: uppercase;
                 color: var(--muted); }
header h1 { margin: 2px 0 0; font-size: 26px; color: var(--band); font-weight: 700; }
header .unit { font-size: 16px; margin-top: 4px; }
.verdict { border-radius: 4px; padding: 8px 14px; font-weight: 700; font-size: 15px;
           text-align: center; min-width: 200px; border: 2px solid; }
.verdict.pass { color: #1e6b2e; border-color: #2e8b47; background: #eef8f0; }
.verdict.warning { color: #7a5200; border-color: #c98a00; background: #fdf6e3; }
.verdict.fail { color: #9b1c1c; border-color: #c53030; background: #fdeeee; }
h2 { font-size: 15px; color: var(--band); border-bottom: 1px solid var(--rule);
     padding-bottom: 3px; margin: 22px 0 8px; }
table { border-collapse: collapse; width: 100%; }
th, td { padding: 3px 8px; text-align: left; vertical-align: top; }
thead th { background: var(--band); color: #fff; font-weight: 600; font-size: 12px; }
tbody tr:nth-child(even) td { background: var(--soft); }
td.num, th.num { text-align: right; font-variant-numeric: tabular-nums;
                 font-family: "DejaVu Sans Mono", "Liberation Mono", monospace; }
tr.family td { background: #dde5ee !important; font-weight: 600; padding-top: 5px; }
tr.family td span { font-weight: 400; color: var(--muted); margin-left: 8px; }
td.na { color: var(--muted); font-style: italic; text-align: right; }
table.facts th { width: 28%; color: var(--muted); font-weight: 600; background: none;
                 border-bottom: 1px solid #edf0f3; }
table.facts td { border-bottom: 1px solid #edf0f3; }
.mono { font-family: "DejaVu Sans Mono", "Liberation Mono", monospace; font-size: 11.5px;
        word-break: break-all; }
ul.reasons { margin: 6px 0 0 18px; padding: 0; }
p.note { color: var(--muted); margin: 6px 0; }
.changed { color: #9b1c1c; font-weight: 700; }
table.facts td.sign { height: 28px; border-bottom: 1px solid var(--ink); min-width: 300px; }
figure { margin: 8px 0; text-align: center; }
figure img { max-width: 100%; border: 1px solid var(--rule); }
footer { margin-top: 26px; border-top: 1px solid var(--rule); padding-top: 8px;
         color: var(--muted); font-size: 11px; display: flex; justify-content: space-between; }
@page { size: A4; margin: 14mm 12mm 16mm; }
@media print {
  body { background: #fff; font-size: 10.5px; }
  .page { margin: 0; padding: 0; max-width: none; box-shadow: none; }
  thead { display: table-header-group; }
  tr, figure, .verdict, table.facts { break-inside: avoid; page-break-inside: avoid; }
  h2 { break-after: avoid; page-break-after: avoid; }
  section { break-inside: auto; }
  section.keep { break-inside: avoid; page-break-inside: avoid; }
  * { -webkit-print-color-adjust: exact; print-color-adjust: exact; }
}
)";

const char* verdict_class(Verdict v) {
  return v == Verdict::Pass ? "pass" : v == Verdict::Warning ? "warning" : "fail";
}

void facts(std::ostringstream& h, const std::vector<std::pair<std::string, std::string>>& rows,
           bool mono_values = false) {
  h << "<table class=\"facts\">\n";
  for (const auto& [k, v] : rows)
    h << "<tr><th>" << html_escaped(k) << "</th><td" << (mono_values ? " class=\"mono\"" : "")
      << ">" << html_escaped(v) << "</td></tr>\n";
  h << "</table>\n";
}

void table(std::ostringstream& h, const CertificateTable& t) {
  if (t.header.empty() && t.rows.empty()) return;
  h << "<table class=\"data\">\n<thead><tr>";
  for (const auto& c : t.header) h << "<th>" << html_escaped(c) << "</th>";
  h << "</tr></thead>\n<tbody>\n";
  for (const auto& row : t.rows) {
    h << "<tr>";
    for (const auto& c : row) h << "<td>" << html_escaped(c) << "</td>";
    h << "</tr>\n";
  }
  h << "</tbody></table>\n";
}

void identity(std::ostringstream& h, const Certificate& c) {
  h << "<section class=\"keep\"><h2>Unit and session</h2>\n";
  facts(h, c.identity);
  h << "</section>\n<section><h2>Input data</h2>\n";
  if (!c.files_note.empty()) h << "<p class=\"note\">" << html_escaped(c.files_note) << "</p>\n";
  if (!c.files.empty()) {
    h << "<table class=\"data files\">\n<thead><tr><th>role</th><th>file</th>"
         "<th class=\"num\">bytes</th><th>SHA-256 (at calibration)</th><th>now</th></tr>"
         "</thead>\n<tbody>\n";
    for (const auto& f : c.files) {
      h << "<tr><td>" << html_escaped(f.role) << "</td><td class=\"mono\">" << html_escaped(f.path)
        << "</td><td class=\"num\">" << (f.bytes ? std::to_string(*f.bytes) : "-")
        << "</td><td class=\"mono\">" << html_escaped(f.sha256.empty() ? "not available" : f.sha256)
        << "</td><td" << (f.state.rfind("CHANGED", 0) == 0 ? " class=\"changed\"" : "") << ">"
        << html_escaped(f.state) << "</td></tr>\n";
    }
    h << "</tbody></table>\n";
  }
  h << "</section>\n";
}

std::string k_text(double k) {
  char b[32];
  std::snprintf(b, sizeof b, "%g", k);
  return b;
}

void coefficients(std::ostringstream& h, const Certificate& c) {
  const std::string k = k_text(c.coverage_factor);
  h << "<section><h2>Calibration coefficients</h2>\n"
       "<table class=\"data coefficients\">\n<thead><tr><th>coefficient</th>"
       "<th class=\"num\">value</th><th class=\"num\">U (k = "
    << k
    << ")</th><th class=\"num\">1-sigma</th><th>unit</th></tr></thead>\n"
       "<tbody>\n";
  std::string family;
  for (const CoefficientRow& r : coefficient_rows(c.coefficients)) {
    if (r.family != family) {
      family = r.family;
      h << "<tr class=\"family\"><td colspan=\"5\">" << html_escaped(family) << "<span>"
        << html_escaped(coefficient_family_info(family).help) << "</span></td></tr>\n";
    }
    h << "<tr><td>" << html_escaped(r.name) << "</td>";
    if (r.kind == CoefficientRow::Kind::Estimated)
      h << "<td class=\"num\">" << html_escaped(r.value) << "</td><td class=\"num u\">± "
        << coefficient_number(c.coverage_factor * *c.coefficients.at(r.name).sigma)
        << "</td><td class=\"num sigma\">" << html_escaped(r.sigma) << "</td>";
    else
      h << "<td class=\"na\" colspan=\"3\">" << html_escaped(r.value) << "</td>";
    h << "<td>" << html_escaped(r.unit) << "</td></tr>\n";
  }
  h << "</tbody></table>\n<p class=\"note\">Values in the display units of the result file "
       "(docs/conventions.md). U is the expanded uncertainty U = k &#183; u, u the standard "
       "(1-sigma) uncertainty of the estimate, with the coverage factor k = "
    << k
    << (c.coverage_factor == 2.0 ? " (a coverage probability of about 95 % for a normal "
                                   "distribution)"
                                 : "")
    << ". \"unobservable\": the data do not determine the coefficient and no value is given; "
       "\"0 (convention)\": fixed by the body-frame convention, not estimated.</p>\n";
  if (!c.misalignment_frame.empty())
    h << "<p class=\"note\" id=\"misalignment-frame\">Misalignments (and the other "
         "coefficients that depend on the body axes) are given "
      << html_escaped(misalignment_frame_words(parse_misalignment_frame(c.misalignment_frame)))
      << ".</p>\n";
  if (!c.forced.empty()) {
    h << "<p class=\"changed\" id=\"forced\">Certified with --force although beyond the "
         "physical range of their family (models/coefficient_families.cpp):</p>\n<ul "
         "class=\"reasons\">\n";
    for (const auto& f : c.forced) h << "<li>" << html_escaped(f) << "</li>\n";
    h << "</ul>\n";
  }
  h << "</section>\n";
}

void conditions(std::ostringstream& h, const Certificate& c) {
  if (c.conditions.empty()) return;
  h << "<section class=\"keep\"><h2>Conditions of the calibration</h2>\n";
  facts(h, c.conditions);
  h << "</section>\n";
}

void approval(std::ostringstream& h, const Certificate& c) {
  h << "<section class=\"keep approval\"><h2>Approval</h2>\n<table class=\"facts\">\n"
       "<tr><th>Approved by (name, function)</th><td class=\"sign\" id=\"approver\">"
    << html_escaped(c.approver)
    << "</td></tr>\n<tr><th>Signature</th><td class=\"sign\"></td></tr>\n"
       "<tr><th>Date</th><td class=\"sign\"></td></tr>\n</table>\n</section>\n";
}

void section(std::ostringstream& h, const CertificateSection& s) {
  const bool keep = s.table.rows.size() < 12 && s.png.empty();
  h << "<section" << (keep ? " class=\"keep\"" : "") << "><h2>" << html_escaped(s.title)
    << "</h2>\n";
  if (!s.facts.empty()) facts(h, s.facts);
  for (const auto& p : s.paragraphs) h << "<p class=\"note\">" << html_escaped(p) << "</p>\n";
  table(h, s.table);
  if (!s.png.empty())
    h << "<figure><img alt=\"" << html_escaped(s.png_alt) << "\" src=\"data:image/png;base64,"
      << base64(s.png) << "\"></figure>\n";
  h << "</section>\n";
}

}  // namespace

std::string certificate_html(const Certificate& c) {
  std::ostringstream h;
  const std::string unit = c.unit_name.empty() ? "unit not recorded" : c.unit_name;
  h << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
    << "<meta name=\"generator\" content=\"sinscal report\">\n"
    << "<title>Calibration certificate: " << html_escaped(unit) << "</title>\n<style>" << kStyle
    << "</style>\n</head>\n<body>\n<div class=\"page\">\n<header><div>"
    << "<div class=\"kicker\">Strapdown inertial unit</div>"
    << "<h1>Calibration certificate</h1><div class=\"unit\">" << html_escaped(unit)
    << "</div></div>\n<div class=\"verdict " << verdict_class(c.verdict) << "\" id=\"verdict\">"
    << html_escaped(c.verdict_title) << "</div></header>\n";
  if (!c.verdict_reasons.empty()) {
    h << "<section class=\"keep\"><h2>Verdict</h2>\n<ul class=\"reasons\">\n";
    for (const auto& r : c.verdict_reasons) h << "<li>" << html_escaped(r) << "</li>\n";
    h << "</ul></section>\n";
  }
  identity(h, c);
  conditions(h, c);
  coefficients(h, c);
  for (const auto& s : c.sections) section(h, s);
  approval(h, c);
  h << "<footer><span>Issued by " << html_escaped(c.issued)
    << "</span><span>sinscal calibration certificate</span></footer>\n</div>\n</body>\n</html>\n";
  return h.str();
}

}  // namespace sinscal
