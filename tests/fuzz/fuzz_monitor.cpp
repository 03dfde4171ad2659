// libFuzzer target: read_monitor (report/monitor.hpp), which takes a path:
// the input is written to a file first. Every error is a std::runtime_error naming the file; a
// series read has one entry per record in every column.
#include "fuzz_support.hpp"
#include "report/monitor.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = sinscal::fuzz::work_dir() + "/monitor.jsonl";
  sinscal::fuzz::write_file(path, sinscal::fuzz::text_of(data, size));
  try {
    const sinscal::MonitorSeries m = sinscal::read_monitor(path);
    const std::size_t n = m.t.size();
    bool ok = m.nis_per_dof.size() == n && m.converged.size() == n &&
              m.value.size() == m.names.size() && m.sigma.size() == m.names.size();
    for (std::size_t i = 0; ok && i < m.names.size(); ++i)
      ok = m.value[i].size() == n && m.sigma[i].size() == n;
    if (!ok) sinscal::fuzz::finding("columns of different lengths", path);
  } catch (const std::runtime_error& e) {
    sinscal::fuzz::check_message(e, path);
  } catch (const std::exception& e) {
    sinscal::fuzz::finding("not a std::runtime_error", e.what());
  }
  return 0;
}
