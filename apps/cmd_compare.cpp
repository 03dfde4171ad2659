// sinscal compare: two calibration results side by side.
#include <cstdio>

#include "apps/cli.hpp"
#include "apps/commands.hpp"
#include "report/compare.hpp"

namespace sinscal::cli {

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
       "fail (exit 3) if a value or sigma differs by more than this fraction");
  // clang-format on
  po::positional_options_description pos;
  pos.add("result", 2);
  const auto vm = parse(args, d,
                        "Usage: sinscal compare A.json B.json [--max-sigma K] [--max-relative R]\n"
                        "Two calibration results side by side: difference, difference over its "
                        "sigma\n(sigma from both results, taken as independent) and relative "
                        "difference.",
                        &pos);
  if (!vm) return 0;
  if (files.size() != 2) throw UsageError("give two result files");
  CompareTolerances tolerances;
  if (vm->count("max-sigma")) tolerances.max_sigma = max_sigma;
  if (vm->count("max-relative")) tolerances.max_relative = max_relative;
  if ((tolerances.max_sigma && !(max_sigma >= 0.0)) ||
      (tolerances.max_relative && !(max_relative >= 0.0)))
    throw UsageError("--max-sigma and --max-relative must be numbers >= 0");
  const ResultCoefficients a = read_result_json(files[0]);
  const ResultCoefficients b = read_result_json(files[1]);
  std::vector<CoefficientComparison> rows;
  try {
    rows = compare_results(a, b, tolerances);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(files[0] + " and " + files[1] + ": " + e.what());
  }
  std::printf("A = %s\nB = %s\n\n%-28s %14s %14s %12s %8s %10s %-8s\n", files[0].c_str(),
              files[1].c_str(), "coefficient", "A", "B", "A - B", "z", "relative", "unit");
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
