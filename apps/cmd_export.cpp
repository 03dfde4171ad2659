// sinscal export: a calibration result as the compensation a firmware applies (JSON, YAML or a C
// header; report/firmware_export.hpp).
#include <cstdio>
#include <iostream>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "report/firmware_export.hpp"
#include "report/output.hpp"

namespace sinscal::cli {

int cmd_export(const std::vector<std::string>& args) {
  po::options_description d("sinscal export options");
  std::string result_path, format_name, out_path;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("result", po::value(&result_path)->required(),
       "result JSON of calibrate (any method; also positional)")
      ("format", po::value(&format_name)->required(), "json | yaml | c-header")
      ("out", po::value(&out_path), "file to write (default: standard output); never an input")
      ("force", "export a result whose own checks failed (plausibility gate, divergence, early "
                "stop, no convergence), coefficients the data did not determine (as zero, "
                "listed in the export) and coefficients beyond their family's physical range "
                "(each recorded in the export's warnings)");
  // clang-format on
  po::positional_options_description pos;
  pos.add("result", 1);
  const auto vm = parse(
      args, d,
      "Usage: sinscal export --result result.json --format json|yaml|c-header [--out FILE] "
      "[--force]\n"
      "The calibration as a firmware applies it: per triad the bias b and the correction matrix\n"
      "C = A^-1 (omega_ib_b = C_g (raw_g - b_g), f_ib_b = C_a (raw_a - b_a)), the extended terms\n"
      "the result estimated with the order in which they are applied, sigmas, the body frame;\n"
      "SI units (docs/formats.md \"Firmware export\").",
      &pos);
  if (!vm) return 0;
  ExportFormat format{};
  try {
    format = export_format_from_name(format_name);
  } catch (const std::invalid_argument& e) {
    throw UsageError(std::string("--format: ") + e.what());
  }
  refuse_overwrite({{"result", result_path}}, {{"--out", out_path}});
  FirmwareExportOptions options;
  options.force = vm->count("force") > 0;
  const FirmwareExport e = read_result_for_export(result_path, options);
  const std::string text = render_export(e, format);
  for (const auto& w : e.warnings)
    std::cerr << "sinscal export: WARNING (--force): " << result_path << ": " << w << "\n";
  if (out_path.empty()) {
    std::cout << text << std::flush;
    if (!std::cout) throw std::runtime_error("standard output: write failed");
    return 0;
  }
  write_atomically(out_path, [&](std::ostream& out) { out << text; });
  std::printf("%s: %s export of %s (method %s, body frame: %s; terms: %zu families)\n",
              out_path.c_str(), format_name.c_str(), result_path.c_str(), e.method.c_str(),
              e.body_frame.c_str(), e.families.size());
  return 0;
}

}  // namespace sinscal::cli
