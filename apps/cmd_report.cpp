// sinscal report: the calibration certificate of a result, one self-contained HTML page (and a
// PDF printed by headless Chromium); report/certificate.hpp.
#include <cstdio>
#include <filesystem>
#include <iostream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "report/certificate.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

namespace {
// The input files the result records, as recorded and against the calibration's working
// directory (a relative path there).
std::vector<std::pair<std::string, std::string>> recorded_inputs(const Certificate& c) {
  std::string cwd;
  for (const auto& [label, value] : c.identity)
    if (label == "Working directory") cwd = value;
  std::vector<std::pair<std::string, std::string>> in;
  for (const auto& f : c.files) {
    if (f.path.empty() || f.path == "<stdin>") continue;
    in.emplace_back(f.role, f.path);
    if (!cwd.empty() && std::filesystem::path(f.path).is_relative())
      in.emplace_back(f.role, (std::filesystem::path(cwd) / f.path).string());
  }
  return in;
}
}  // namespace

int cmd_report(const std::vector<std::string>& args) {
  po::options_description d("sinscal report options");
  std::string result_path, diagnosis_dir, out_path, pdf_path, monitor_path, approver;
  double coverage_factor = 2.0;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("result", po::value(&result_path)->required(),
       "result JSON of calibrate (any method) or thermal (also positional)")
      ("diagnosis", po::value(&diagnosis_dir),
       "the --out DIR of sinscal diagnose on the same session: its summary on the page")
      ("monitor", po::value(&monitor_path),
       "the monitor file of the run (default: the one the result records)")
      ("out", po::value(&out_path)->required(), "the HTML page to write")
      ("pdf", po::value(&pdf_path), "also print the page to this PDF (needs Debian's chromium)")
      ("coverage-factor", po::value(&coverage_factor),
       "k of the expanded uncertainty U = k sigma beside each value (default 2: about 95 %)")
      ("approved-by", po::value(&approver),
       "the name of the person who approves the certificate (default: a blank to fill in)")
      ("force", "replace existing output files, and certify coefficients beyond their family's "
                "physical range (noted on the page, the verdict failed)");
  // clang-format on
  po::positional_options_description pos;
  pos.add("result", 1);
  const auto vm = parse(
      args, d,
      "Usage: sinscal report --result result.json [--diagnosis DIR] --out report.html "
      "[--pdf report.pdf] [--coverage-factor K] [--approved-by NAME] [--force]\n"
      "The calibration certificate: the unit and its data (SHA-256 of the logs), the\n"
      "conditions, the coefficients with the expanded uncertainty U = k sigma (k = 2) and unit,\n"
      "the verdict, the installation, the convergence plot,\n"
      "the residuals and the noise when the result has them, the diagnosis summary; one HTML\n"
      "page that prints to A4 (docs/formats.md \"Calibration certificate\"). Exit 4: the page\n"
      "was written but not the PDF (chromium missing or failed).",
      &pos);
  if (!vm) return 0;
  if (!(coverage_factor >= 1.0 && coverage_factor <= 10.0))
    throw UsageError("--coverage-factor must be 1 to 10 (2: about 95 % coverage)");
  std::vector<std::pair<std::string, std::string>> inputs = {{"result", result_path},
                                                             {"monitor file", monitor_path}};
  if (!diagnosis_dir.empty())
    for (const char* f : {"diagnosis.json", "residuals.png", "report.md"})
      inputs.emplace_back("diagnosis", (std::filesystem::path(diagnosis_dir) / f).string());
  refuse_overwrite(inputs, {{"--out", out_path}, {"--pdf", pdf_path}});
  CertificateOptions o;
  o.result_path = result_path;
  o.diagnosis_dir = diagnosis_dir;
  o.monitor_path = monitor_path;
  o.force = vm->count("force") > 0;
  o.coverage_factor = coverage_factor;
  o.approver = approver;
  const Certificate c = read_certificate(o);
  // The calibration's own inputs (its session, logs, profile) are never replaced either.
  refuse_overwrite(recorded_inputs(c), {{"--out", out_path}, {"--pdf", pdf_path}});
  if (!pdf_path.empty()) {
    try {
      check_writable(pdf_path);  // before chromium, which would only say it failed
    } catch (const std::runtime_error& e) {
      throw UsageError(std::string("--pdf ") + e.what());
    }
  }
  if (vm->count("force") == 0) {
    std::error_code ec;
    for (const auto& [option, path] : {std::pair{"--out", out_path}, std::pair{"--pdf", pdf_path}})
      if (!path.empty() && std::filesystem::exists(path, ec))
        throw UsageError(std::string(option) + " " + path +
                         ": exists; sinscal report does not replace a file without --force");
  }
  for (const auto& f : c.forced)
    std::cerr << "sinscal report: WARNING (--force): " << result_path << ": certified beyond the "
              << "physical range: " << f << "\n";
  const std::string html = certificate_html(c);
  write_atomically(out_path, [&](std::ostream& out) { out << html; });
  std::printf("%s: calibration certificate of %s (%s; %zu coefficients, %zu sections)\n",
              out_path.c_str(), result_path.c_str(), c.verdict_title.c_str(), c.coefficients.size(),
              c.sections.size());
  if (pdf_path.empty()) return 0;
  try {
    print_pdf(out_path, pdf_path);
  } catch (const ChromiumMissing& e) {
    std::cerr << "sinscal report: error: no PDF: " << e.what() << "; the HTML page was written to "
              << out_path << "\n";
    return kPartial;
  } catch (const std::runtime_error& e) {
    std::cerr << "sinscal report: error: no PDF: " << e.what() << "; the HTML page was written to "
              << out_path << "\n";
    return kPartial;
  }
  std::printf("%s: the certificate printed to PDF\n", pdf_path.c_str());
  return 0;
}

}  // namespace sinscal::cli
