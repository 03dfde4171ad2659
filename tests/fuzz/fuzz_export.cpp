// libFuzzer target: the result reader's checks as the export runs them (read_result_file and
// read_result_for_export, report/result.hpp, report/firmware_export.hpp): the first byte sets
// --force, the rest is the result file. Every error is a std::runtime_error naming the file; an
// export written without --force has every coefficient within its family's physical range
// (models/coefficient_families.hpp), and renders in every format.
#include <cmath>

#include "fuzz_support.hpp"
#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "report/firmware_export.hpp"
#include "report/result.hpp"

namespace {

void within_range(const sinscal::FirmwareExport& e) {
  for (const auto& [name, value] : e.model.coefficients()) {
    const sinscal::CoefficientInfo& info = sinscal::coefficient_info(name);
    const double range =
        sinscal::coefficient_family_info(info.family).plausible_max / info.si_per_unit;
    if (!(std::abs(value) <= range))
      sinscal::fuzz::finding("an export without --force holds an implausible coefficient", name);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const bool force = (data[0] & 1) != 0;
  const std::string path = sinscal::fuzz::work_dir() + "/result.json";
  sinscal::fuzz::write_file(path, sinscal::fuzz::text_of(data + 1, size - 1));
  try {
    const sinscal::ResultFile r = sinscal::read_result_file(path, force);
    if (!force && !r.forced.empty()) sinscal::fuzz::finding("an override without --force", path);
    const sinscal::FirmwareExport e = sinscal::read_result_for_export(path, {force});
    if (!force) within_range(e);
    for (auto format :
         {sinscal::ExportFormat::Json, sinscal::ExportFormat::Yaml, sinscal::ExportFormat::CHeader})
      sinscal::render_export(e, format);
  } catch (const std::runtime_error& e) {
    sinscal::fuzz::check_message(e, path);
  } catch (const std::exception& e) {
    sinscal::fuzz::finding("not a std::runtime_error", e.what());
  }
  return 0;
}
