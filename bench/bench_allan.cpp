// Allan deviation of long records in bounded memory (not a test): a simulated static record of
// white noise, flicker bias instability and random walk on all six channels, fed to the
// streamed estimator without a file; prints samples/s, the estimators' memory, the peak RSS
// (getrusage) and the fitted terms against the simulated truth.
//
// Usage: bench_allan [HOURS [RATE_HZ]]          (default 24 h at 1000 Hz: 8.64e7 samples)
//        bench_allan --log HOURS RATE_HZ        writes the record as CSV (ax,ay,az,gx,gy,gz:
//                                               m/s^2 and rad/s) to standard output, e.g. into
//                                               a FIFO read by `sinscal allan --all`
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "filter/noise/allan.hpp"
#include "filter/noise/allan_sim.hpp"
#include "models/units.hpp"

using namespace sinscal;

namespace {

// A tactical gyro (ARW 0.05 deg/sqrt(h), bias instability 0.5 deg/h, RRW 0.05 deg/h/sqrt(h))
// and accelerometer (VRW 50 ug/sqrt(Hz), 20 ug, 30 ug/sqrt(h)).
AllanTruth gyro_truth() {
  return {0.05 * units::deg_per_sqrt_h, 0.5 * units::deg_per_h, 0.05 * units::deg_per_h_per_sqrt_h,
          0.0};
}
AllanTruth accel_truth() {
  return {50.0 * units::ug_per_sqrt_hz, 20.0 * units::ug, 30.0 * units::ug_per_sqrt_h, 0.0};
}

std::vector<AllanNoiseSource> sources(double tau0, double seconds) {
  std::vector<AllanNoiseSource> s;
  for (std::uint64_t c = 0; c < 6; ++c)
    s.emplace_back(c < 3 ? gyro_truth() : accel_truth(), tau0, 10.0 * seconds, 100 + c, true);
  return s;
}

long peak_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

int write_log(double hours, double rate) {
  const double tau0 = 1.0 / rate;
  const auto n = static_cast<std::size_t>(hours * 3600.0 * rate);
  auto src = sources(tau0, static_cast<double>(n) * tau0);
  std::vector<char> buffer(1 << 20);
  std::setvbuf(stdout, buffer.data(), _IOFBF, buffer.size());
  for (std::size_t k = 0; k < n; ++k) {
    double v[6];
    for (std::size_t c = 0; c < 6; ++c) v[c] = src[c].next();
    std::printf("%.8g,%.8g,%.8g,%.8g,%.8g,%.8g\n", v[3], v[4], units::g0 + v[5], v[0], v[1], v[2]);
  }
  std::fflush(stdout);  // before the buffer goes
  return 0;
}

void print_fit(const char* what, const AllanFit& f, const AllanTruth& t, double unit,
               const char* name) {
  std::printf(
      "  %-6s N %.4g +- %.2g (truth %.4g)  B %.4g +- %.2g (truth %.4g)  K %.4g +- %.2g "
      "(truth %.4g)  [%s]\n",
      what, f.white / unit, f.white_sigma / unit, t.white / unit, f.bias_instability / unit,
      f.bias_instability_sigma / unit, t.bias_instability / unit, f.random_walk / unit,
      f.random_walk_sigma / unit, t.random_walk / unit, name);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "--log") == 0)
    return write_log(std::stod(argv[2]), std::stod(argv[3]));
  const double hours = argc > 1 ? std::stod(argv[1]) : 24.0;
  const double rate = argc > 2 ? std::stod(argv[2]) : 1000.0;
  const double tau0 = 1.0 / rate;
  const auto n = static_cast<std::size_t>(hours * 3600.0 * rate);
  auto src = sources(tau0, static_cast<double>(n) * tau0);
  AllanStream stream;
  double generate = 0.0, estimate = 0.0;
  using Clock = std::chrono::steady_clock;
  constexpr std::size_t kBlock = 4096;
  std::vector<double> v(6 * kBlock);
  for (std::size_t k = 0; k < n; k += kBlock) {
    const std::size_t m = std::min(kBlock, n - k);
    const auto t0 = Clock::now();
    for (std::size_t j = 0; j < m; ++j)
      for (std::size_t c = 0; c < 6; ++c) v[6 * j + c] = src[c].next();
    const auto t1 = Clock::now();
    for (std::size_t j = 0; j < m; ++j)
      stream.add_rates(Eigen::Vector3d(v[6 * j], v[6 * j + 1], v[6 * j + 2]),
                       Eigen::Vector3d(v[6 * j + 3], v[6 * j + 4], v[6 * j + 5]));
    generate += std::chrono::duration<double>(t1 - t0).count();
    estimate += std::chrono::duration<double>(Clock::now() - t1).count();
  }
  const auto t2 = Clock::now();
  const AllanAnalysis a = stream.analysis(tau0);
  const double fit = std::chrono::duration<double>(Clock::now() - t2).count();
  std::printf("allan, streamed: %.3g h at %g Hz = %zu samples x 6 channels\n", hours, rate, n);
  std::printf("  estimator: %.3g samples/s (%.1f s; simulation %.1f s, fit %.2f s)\n",
              static_cast<double>(n) / estimate, estimate, generate, fit);
  std::printf(
      "  estimators' memory %.2f MB, peak RSS %.1f MB, cluster times %zu (largest "
      "stride %zu)\n",
      static_cast<double>(stream.memory_bytes()) / 1e6, static_cast<double>(peak_rss_kb()) / 1024.0,
      a.gyro[0].size(), a.max_stride);
  for (std::size_t i = 0; i < 3; ++i) {
    print_fit(i == 0   ? "gyro x"
              : i == 1 ? "gyro y"
                       : "gyro z",
              a.gyro_fit[i], gyro_truth(), units::deg_per_h, "deg/h; N deg/h*sqrt(s)");
  }
  for (std::size_t i = 0; i < 3; ++i)
    print_fit(i == 0   ? "acc x"
              : i == 1 ? "acc y"
                       : "acc z",
              a.accel_fit[i], accel_truth(), units::ug, "ug; N ug*sqrt(s)");
  return 0;
}
