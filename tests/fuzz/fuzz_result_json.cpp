// libFuzzer target: read_result_json (report/result.hpp) and the comparison, which take a
// path: the input is written to a file first. Every error is a std::runtime_error naming the file.
#include "fuzz_support.hpp"
#include "report/compare.hpp"
#include "report/result.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = sinscal::fuzz::work_dir() + "/result.json";
  sinscal::fuzz::write_file(path, sinscal::fuzz::text_of(data, size));
  try {
    const sinscal::ResultCoefficients r = sinscal::read_result_json(path);
    try {
      sinscal::compare_results(r, r);
      sinscal::max_error_over_sigma(r, r);
    } catch (const std::runtime_error&) {
      // A readable result with nothing to compare: a content error, which the command line
      // prefixes with both file names (apps/cmd_compare.cpp).
    }
  } catch (const std::runtime_error& e) {
    sinscal::fuzz::check_message(e, path);
  } catch (const std::exception& e) {
    sinscal::fuzz::finding("not a std::runtime_error", e.what());
  }
  return 0;
}
