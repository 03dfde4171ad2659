// Printing of the hand-held commands: table-free calibration and Allan deviation.
#include <cmath>
#include <cstdio>
#include <vector>

#include "apps/cli.hpp"
#include "apps/print.hpp"
#include "filter/plausibility/rest_plausibility.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/table_free_result.hpp"

namespace sinscal::cli {

void print_table_free(const TableFreeRun& run, const HandheldFitBounds& b,
                      const ResultCoefficients& coefficients, const ResultCoefficients& truth) {
  const TableFreeResult& r = run.result;
  std::printf("Table-free calibration of '%s': %zu samples, %.1f s of data\n", run.name.c_str(),
              run.samples, run.duration);
  double shortest = 0.0, longest = 0.0;
  for (std::size_t k = 1; k < run.poses.size(); ++k) {
    const double d = run.poses[k].pose.duration();
    shortest = k == 1 ? d : std::min(shortest, d);
    longest = std::max(longest, d);
  }
  std::printf("Poses found: %zu (detector: %s, window %g s, shortest %g s)", run.poses.size(),
              run.detector.use_gyro ? "gyros and accelerometers" : "accelerometers only",
              run.detector.window, run.detector.min_duration);
  if (!run.poses.empty())
    std::printf(": the first %.1f-%.1f s", run.poses.front().pose.t_start,
                run.poses.front().pose.t_end);
  if (run.poses.size() > 1) std::printf(", then %.1f-%.1f s each", shortest, longest);
  std::printf("\nGravity %.5f m/s^2 (%s); body frame: the accelerometer triad\n", r.gravity,
              run.gravity_from.c_str());
  std::printf("Fit: chi2/dof %.3f (dof %d), %d iterations, %s (the last step %.2g of a sigma)\n",
              r.chi2_per_dof, r.dof, r.iterations, r.converged ? "converged" : "NOT converged",
              r.step_over_sigma);
  std::printf(
      "Fit quality per stage (chi2/dof against the white noise): accel poses %.3g, gyro poses "
      "%.3g, turns %.3g\nNoise model completed from the residuals%s: bias wander accel %.3g mg "
      "(pose sigmas x%.3g), gyro %.3g deg/s (x%.3g); the turns' variance x%.3g (sigmas x%.3g)\n",
      r.accel_fit.chi2_per_dof(), r.gyro_rest_fit.chi2_per_dof(), r.turn_fit.chi2_per_dof(),
      r.variance_settled ? "" : " (NOT settled)", r.accel_fit.wander / units::mg,
      r.accel_fit.sigma_scale, r.gyro_rest_fit.wander / units::deg_per_s,
      r.gyro_rest_fit.sigma_scale, r.turn_fit.sigma_scale * r.turn_fit.sigma_scale,
      r.turn_fit.sigma_scale);
  std::printf(
      "Fit gate (bias wander from the %s: accel %.3g mg, gyro %.3g deg/s): accel poses chi2 "
      "%.4g <= %.4g, gyro poses %.4g <= %.4g, turns %.4g <= %.4g (the turns' expected excess "
      "%.3g: timing and dynamics, docs/methods/table-free.md)\n",
      b.wander_source.c_str(), b.accel.wander / units::mg, b.gyro.wander / units::deg_per_s,
      b.accel.chi2, b.accel.bound, b.gyro.chi2, b.gyro.bound, b.turns.chi2, b.turns.bound,
      b.turn_excess);
  std::printf("Noise per reading at rest: accel %.3g %.3g %.3g m/s^2, gyro %.3g %.3g %.3g deg/s\n",
              r.accel_noise(0), r.accel_noise(1), r.accel_noise(2),
              r.gyro_noise(0) / units::deg_per_s, r.gyro_noise(1) / units::deg_per_s,
              r.gyro_noise(2) / units::deg_per_s);
  print_coefficient_table(coefficients, truth);
  print_truth_verdict(coefficients, truth);
  const auto raw = raw_entries(run);
  if (!raw.empty()) {
    std::printf("\nRaw-count view (the sensors' own axes; nominal: the log's conversion)\n");
    std::printf("%-24s %14s %10s %14s  %s\n", "", "value", "sigma", "nominal", "unit");
    for (const auto& e : raw) {
      if (e.has_sigma)
        std::printf("%-24s %14.3f %10.3f %14.3f  %s\n", e.name.c_str(), e.value, e.sigma, e.nominal,
                    e.unit.c_str());
      else
        std::printf("%-24s %14.3f %10s %14.3f  %s\n", e.name.c_str(), e.value, "", e.nominal,
                    e.unit.c_str());
    }
  }
  for (const auto& v : run.validations) {
    std::printf("\nValidation '%s' (%s): %zu poses, %zu turns    nominal -> calibrated\n",
                v.name.c_str(), v.session.c_str(), v.poses.size(), v.turns.size());
    std::printf("  |f| - g at rest, RMS      %10.4f -> %.4f m/s^2\n", v.gravity_rms_nominal,
                v.gravity_rms_calibrated);
    std::printf("  |rate| at rest, RMS       %10.4f -> %.4f deg/s\n",
                v.rate_rms_nominal / units::deg_per_s, v.rate_rms_calibrated / units::deg_per_s);
    if (!v.turns.empty())
      std::printf("  turn error, RMS           %10.3f -> %.3f deg\n",
                  v.turn_rms_nominal / units::deg, v.turn_rms_calibrated / units::deg);
  }
}

void print_allan(const AllanRun& run) {
  const AllanAnalysis& a = run.analysis;
  std::printf("Allan deviation of '%s': ", run.name.c_str());
  if (run.pose > 0)
    std::printf("pose %d of %d", run.pose, run.poses_found);
  else
    std::printf("the whole record");
  std::printf(", %.2f-%.2f s, %zu samples at %g s\n", run.t_start, run.t_end, a.samples, a.tau0);
  std::printf("\n%-8s %14s %14s %16s   %-8s %14s %12s %14s\n", "gyro", "ARW", "bias inst.",
              "rate rand. walk", "accel", "VRW", "bias inst.", "random walk");
  std::printf("%-8s %14s %14s %16s   %-8s %14s %12s %14s\n", "", "[deg/sqrt(h)]", "[deg/h]",
              "[deg/h/sqrt(h)]", "", "[ug/sqrt(Hz)]", "[ug]", "[ug/sqrt(h)]");
  const char* axis[3] = {"x", "y", "z"};
  for (std::size_t i = 0; i < 3; ++i) {
    const AllanFit& g = a.gyro_fit[i];
    const AllanFit& f = a.accel_fit[i];
    std::printf("%-8s %14.4g %14.4g %16.4g   %-8s %14.4g %12.4g %14.4g\n", axis[i],
                g.white / units::deg_per_sqrt_h, g.floor_bias_instability / units::deg_per_h,
                g.random_walk / units::deg_per_h_per_sqrt_h, axis[i],
                f.white / units::ug_per_sqrt_hz, f.floor_bias_instability / units::ug,
                f.random_walk / units::ug_per_sqrt_h);
    std::printf("%-8s %14.2g %14.2g %16.2g   %-8s %14.2g %12.2g %14.2g\n", "  1-sigma",
                g.white_sigma / units::deg_per_sqrt_h,
                g.floor_bias_instability_sigma / units::deg_per_h,
                g.random_walk_sigma / units::deg_per_h_per_sqrt_h, "",
                f.white_sigma / units::ug_per_sqrt_hz, f.floor_bias_instability_sigma / units::ug,
                f.random_walk_sigma / units::ug_per_sqrt_h);
  }
  std::printf(
      "bias instability: the fitted curve's minimum / 0.664 (IEEE Std 952's flicker floor)"
      "\nread %zu time(s), %.1f MB held by the estimators; cluster times fully "
      "overlapping up to %zu samples, then at a stride of at most %zu\n",
      run.passes, static_cast<double>(run.memory_bytes) / 1e6, AllanAccumulator::kExactClusters - 1,
      a.max_stride);
}

}  // namespace sinscal::cli
