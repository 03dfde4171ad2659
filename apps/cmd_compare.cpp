// sinscal compare: two calibration results side by side.
#include <cstdio>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "report/compare.hpp"

namespace sinscal::cli {

namespace {
// Coefficients beyond their family's physical range, compared with --force: named in the output.
void print_overrides(const ResultFile& f, const char* which) {
  for (const auto& o : f.forced) {
    std::printf("WARNING (--force): %s: %s\n", which, o.c_str());
    std::fprintf(stderr, "sinscal compare: WARNING (--force): %s: %s\n", which, o.c_str());
  }
}

// Coefficients in one result only: named (they have no difference to show).
void print_one_sided(const ResultCoefficients& a, const ResultCoefficients& b,
                     const std::vector<std::string>& files) {
  for (int side = 0; side < 2; ++side) {
    const ResultCoefficients &x = side ? b : a, &y = side ? a : b;
    std::string only;
    for (const auto& [name, c] : x)
      if (!y.count(name)) only += (only.empty() ? "" : ", ") + name;
    if (only.empty()) continue;
    std::printf("only in %s (%s): %s\n", side ? "B" : "A",
                files[static_cast<std::size_t>(side)].c_str(), only.c_str());
    std::fprintf(stderr, "sinscal compare: note: coefficients only in %s, not compared: %s\n",
                 files[static_cast<std::size_t>(side)].c_str(), only.c_str());
  }
}
}  // namespace

int cmd_compare(const std::vector<std::string>& args) {
  po::options_description d("sinscal compare options");
  std::vector<std::string> files;
  double max_sigma = 0.0, max_relative = 0.0;
  // clang-format off
  d.add_options()
      ("help,h", "this help")
      ("result", po::value(&files)->composing(), "the two result JSON files (also positional)")
      ("max-sigma", po::value(&max_sigma),
       "fail (exit 3) if a difference exceeds this many sigma of the difference")
      ("max-relative", po::value(&max_relative),
       "fail (exit 3) if a value or sigma differs by more than this fraction")
      ("force", "compare coefficients beyond their family's physical range (each named in the "
                "output)");
  // clang-format on
  po::positional_options_description pos;
  pos.add("result", 2);
  const auto vm =
      parse(args, d,
            "Usage: sinscal compare A.json B.json [--max-sigma K] [--max-relative R] [--force]\n"
            "Two calibration results side by side: difference, difference over its "
            "sigma\n(sigma from both results, taken as independent) and relative "
            "difference. Every coefficient name must be sinscal's (a mistyped one is "
            "refused);\nthose in one file only are named.",
            &pos);
  if (!vm) return 0;
  if (files.size() != 2) throw UsageError("give two result files");
  CompareTolerances tolerances;
  if (vm->count("max-sigma")) tolerances.max_sigma = max_sigma;
  if (vm->count("max-relative")) tolerances.max_relative = max_relative;
  if ((tolerances.max_sigma && !(max_sigma >= 0.0)) ||
      (tolerances.max_relative && !(max_relative >= 0.0)))
    throw UsageError("--max-sigma and --max-relative must be numbers >= 0");
  const bool force = vm->count("force") > 0;
  const ResultFile fa = read_result_file(files[0], force), fb = read_result_file(files[1], force);
  // Misalignments relative to the table and within the triads are different quantities.
  if (!fa.misalignment_frame.empty() && !fb.misalignment_frame.empty() &&
      fa.misalignment_frame != fb.misalignment_frame)
    throw std::runtime_error(
        files[0] + " and " + files[1] + ": different misalignment frames (A: " +
        fa.misalignment_frame + " frame, B: " + fb.misalignment_frame +
        " frame): the misalignments, and the coefficients that depend on the body axes, are not "
        "the same quantities; calibrate both with the same --misalignment-frame");
  const ResultCoefficients &a = fa.coefficients, &b = fb.coefficients;
  std::vector<CoefficientComparison> rows;
  try {
    rows = compare_results(a, b, tolerances);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(files[0] + " and " + files[1] + ": " + e.what());
  }
  std::printf("A = %s\nB = %s\n", files[0].c_str(), files[1].c_str());
  if (!fa.misalignment_frame.empty() || !fb.misalignment_frame.empty())
    std::printf("Misalignment frame: %s\n",
                (fa.misalignment_frame.empty() ? fb : fa).misalignment_frame.c_str());
  print_overrides(fa, "A");
  print_overrides(fb, "B");
  print_one_sided(a, b, files);
  std::printf("\n%-28s %14s %14s %12s %8s %10s %-8s\n", "coefficient", "A", "B", "A - B", "z",
              "relative", "unit");
  int failures = 0;
  for (const auto& c : rows) {
    auto num = [](const std::optional<double>& v, const char* f) {
      return v ? fmt(f, *v) : std::string("-");
    };
    std::printf("%-28s %14s %14s %12s %8s %10s %-8s%s\n", c.name.c_str(), num(c.a, "%.6g").c_str(),
                num(c.b, "%.6g").c_str(), c.a && c.b ? fmt("%.4g", *c.a - *c.b).c_str() : "-",
                num(c.z, "%.2f").c_str(), num(c.relative, "%.2e").c_str(), c.unit.c_str(),
                c.verdict.c_str());
    if (c.disagrees) ++failures;
  }
  if (failures == 0) return 0;
  std::fprintf(stderr, "sinscal compare: %d coefficients disagree\n", failures);
  return kDisagree;
}

}  // namespace sinscal::cli
