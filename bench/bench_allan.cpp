// Allan deviation of long records in bounded memory (not a test): a simulated static record of
// white noise, flicker bias instability and random walk on all six channels, fed to the
// streamed estimator without a file; prints samples/s, the estimators' memory, the peak RSS
// (getrusage) and the fitted terms against the simulated truth, each with its z = (fit - truth)
// / sigma.
//
// Usage: bench_allan [OPTIONS] [HOURS [RATE_HZ]]   (default 24 h at 1000 Hz: 8.64e7 samples)
//        bench_allan --log [OPTIONS] HOURS RATE_HZ  writes the record as CSV (ax,ay,az,gx,gy,gz:
//                                                   m/s^2 and rad/s) to standard output, e.g.
//                                                   into a FIFO read by `sinscal allan --all`
// OPTIONS: --compare    also fit the same record with the Gaussian fit of the variances (the
//                        fit before 2026-12-06) and print it ("old")
//          --seed S      the channels' seeds S .. S + 5 (default 100)
//          --truth NAME  tactical (default) or adis16405 (the ADIS16405 data sheet's terms)
//          --fast        the quicker flicker generator, about 2 % low (allan_sim.hpp): the
//                        bench's default before 2026-12-06
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "filter/noise/allan.hpp"
#include "filter/noise/allan_sim.hpp"
#include "models/units.hpp"

using namespace sinscal;

namespace {

// The simulated terms of one triad.
struct Truths {
  AllanTruth gyro, accel;
};

// A tactical gyro (ARW 0.05 deg/sqrt(h), bias instability 0.5 deg/h, RRW 0.5 deg/h/sqrt(h):
// flicker and random walk cross at 4.8e3 s, well inside a 24 h record's longest cluster time of
// 2.2e4 s) and accelerometer (VRW 50 ug/sqrt(Hz), 20 ug, 30 ug/sqrt(h): crossing at 2.1e3 s).
// Before 2026-12-06 the gyro's RRW was 0.05 deg/h/sqrt(h), crossing at 4.8e5 s: beyond any
// record's reach, so the fit could not identify it.
Truths tactical() {
  return {{0.05 * units::deg_per_sqrt_h, 0.5 * units::deg_per_h, 0.5 * units::deg_per_h_per_sqrt_h,
           0.0},
          {50.0 * units::ug_per_sqrt_hz, 20.0 * units::ug, 30.0 * units::ug_per_sqrt_h, 0.0}};
}
// ADIS16405 data sheet (Analog Devices, Rev. B): gyro ARW 2.0 deg/sqrt(h), in-run bias stability
// 0.007 deg/s (25.2 deg/h); accelerometer VRW 0.2 m/s/sqrt(h), in-run bias stability 0.2 mg; no
// random walk stated (0). The bias stability is taken as B (sinscal's reading: floor / 0.664).
Truths adis16405() {
  return {{2.0 * units::deg_per_sqrt_h, 0.007 * units::deg_per_s, 0.0, 0.0},
          {0.2 / 60.0, 200.0 * units::ug, 0.0, 0.0}};
}

struct Options {
  std::uint64_t seed = 100;
  bool fast = false;
  Truths truth = tactical();
  std::vector<double> numbers;  // HOURS, RATE_HZ
  bool log = false;
  bool compare = false;
};

std::vector<AllanNoiseSource> sources(const Options& o, double tau0, double seconds) {
  std::vector<AllanNoiseSource> s;
  for (std::uint64_t c = 0; c < 6; ++c)
    s.emplace_back(c < 3 ? o.truth.gyro : o.truth.accel, tau0, 10.0 * seconds, o.seed + c, o.fast);
  return s;
}

long peak_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

int write_log(const Options& o, double hours, double rate) {
  const double tau0 = 1.0 / rate;
  const auto n = static_cast<std::size_t>(hours * 3600.0 * rate);
  auto src = sources(o, tau0, static_cast<double>(n) * tau0);
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

// "fit +- sigma (truth, z)"; a term the fit dropped (sigma 0) reads "0 (dropped)".
void print_term(const char* name, double fit, double sigma, double truth, double unit) {
  if (sigma > 0.0)
    std::printf("  %s %.5g +- %.2g (truth %.4g, z %+.2f)", name, fit / unit, sigma / unit,
                truth / unit, (fit - truth) / sigma);
  else
    std::printf("  %s %.5g (dropped; truth %.4g)", name, fit / unit, truth / unit);
}

void print_fit(const char* what, const AllanFit& f, const AllanTruth& t, double unit,
               const char* name) {
  std::printf("  %-6s", what);
  print_term("N", f.white, f.white_sigma, t.white, unit);
  print_term("B", f.bias_instability, f.bias_instability_sigma, t.bias_instability, unit);
  print_term("K", f.random_walk, f.random_walk_sigma, t.random_walk, unit);
  print_term("floor/0.664", f.floor_bias_instability, f.floor_bias_instability_sigma,
             t.bias_instability, unit);
  std::printf("  [%s]\n", name);
}

Options parse(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--log") {
      o.log = true;
    } else if (a == "--compare") {
      o.compare = true;
    } else if (a == "--fast") {
      o.fast = true;
    } else if (a == "--seed" && i + 1 < argc) {
      o.seed = std::stoull(argv[++i]);
    } else if (a == "--truth" && i + 1 < argc) {
      const std::string t = argv[++i];
      if (t == "tactical")
        o.truth = tactical();
      else if (t == "adis16405")
        o.truth = adis16405();
      else
        throw std::invalid_argument("--truth: tactical or adis16405, not " + t);
    } else {
      o.numbers.push_back(std::stod(a));
    }
  }
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  try {
    o = parse(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_allan: %s\n", e.what());
    return 2;
  }
  const double hours = !o.numbers.empty() ? o.numbers[0] : 24.0;
  const double rate = o.numbers.size() > 1 ? o.numbers[1] : 1000.0;
  if (o.log) return write_log(o, hours, rate);
  const double tau0 = 1.0 / rate;
  const auto n = static_cast<std::size_t>(hours * 3600.0 * rate);
  auto src = sources(o, tau0, static_cast<double>(n) * tau0);
  AllanStream stream;
  AllanOptions gaussian;
  gaussian.log_fit = false;
  AllanStream old_stream(gaussian);  // --compare: the fit before 2026-12-06
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
    for (std::size_t j = 0; j < m; ++j) {
      const Eigen::Vector3d w(v[6 * j], v[6 * j + 1], v[6 * j + 2]);
      const Eigen::Vector3d f(v[6 * j + 3], v[6 * j + 4], v[6 * j + 5]);
      stream.add_rates(w, f);
      if (o.compare) old_stream.add_rates(w, f);
    }
    generate += std::chrono::duration<double>(t1 - t0).count();
    estimate += std::chrono::duration<double>(Clock::now() - t1).count();
  }
  const auto t2 = Clock::now();
  const AllanAnalysis a = stream.analysis(tau0);
  const double fit = std::chrono::duration<double>(Clock::now() - t2).count();
  std::printf(
      "allan, streamed: %.3g h at %g Hz = %zu samples x 6 channels (seed %llu, %s flicker)\n",
      hours, rate, n, static_cast<unsigned long long>(o.seed), o.fast ? "fast" : "exact");
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
              a.gyro_fit[i], o.truth.gyro, units::deg_per_h, "deg/h; N deg/h*sqrt(s)");
  }
  for (std::size_t i = 0; i < 3; ++i)
    print_fit(i == 0   ? "acc x"
              : i == 1 ? "acc y"
                       : "acc z",
              a.accel_fit[i], o.truth.accel, units::ug, "ug; N ug*sqrt(s)");
  if (!o.compare) return 0;
  const AllanAnalysis b = old_stream.analysis(tau0);
  std::printf("  the Gaussian fit of the variances (before 2026-12-06), same record:\n");
  for (std::size_t i = 0; i < 3; ++i)
    print_fit(i == 0   ? "old gx"
              : i == 1 ? "old gy"
                       : "old gz",
              b.gyro_fit[i], o.truth.gyro, units::deg_per_h, "deg/h; N deg/h*sqrt(s)");
  for (std::size_t i = 0; i < 3; ++i)
    print_fit(i == 0   ? "old ax"
              : i == 1 ? "old ay"
                       : "old az",
              b.accel_fit[i], o.truth.accel, units::ug, "ug; N ug*sqrt(s)");
  return 0;
}
