#include "apps/print.hpp"

#include <cmath>
#include <cstdio>
#include <vector>

#include "apps/cli.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/coefficient_table.hpp"

namespace sinscal::cli {

void print_coefficient_table(const ResultCoefficients& coefficients,
                             const ResultCoefficients& truth) {
  std::printf("\n%-24s %12s %10s %-7s", "coefficient", "estimate", "sigma", "unit");
  if (!truth.empty()) std::printf(" %12s %10s %7s", "truth", "error", "err/sig");
  std::printf("\n");
  for (const CoefficientRow& r : coefficient_rows(coefficients, truth)) {
    if (r.kind == CoefficientRow::Kind::Estimated)
      std::printf("%-24s %12s %10s %-7s", r.name.c_str(), r.value.c_str(), r.sigma.c_str(),
                  r.unit.c_str());
    else
      std::printf("%-24s %23s %-7s", r.name.c_str(), r.value.c_str(), r.unit.c_str());
    if (r.truth) std::printf(" %12s", r.truth->c_str());
    if (r.error) std::printf(" %10s %7s", r.error->c_str(), r.error_over_sigma->c_str());
    std::printf("\n");
  }
}

// Against the truth (simulations): the largest |error| / sigma and how many are beyond 3.
void print_truth_verdict(const ResultCoefficients& coefficients, const ResultCoefficients& truth) {
  if (truth.empty()) return;
  const auto worst = max_error_over_sigma(coefficients, truth);
  if (!worst) return;
  int beyond = 0, n = 0;
  for (const auto& [name, c] : coefficients) {
    const auto t = truth.find(name);
    if (t == truth.end() || !c.observable || c.fixed_by_convention || !c.sigma) continue;
    ++n;
    if (std::abs(c.value - t->second.value) > 3.0 * *c.sigma) ++beyond;
  }
  std::printf("Against the injected truth: every one of the %d estimates within %.2f sigma%s\n", n,
              *worst,
              beyond == 0 ? " (the errors are what the sigmas say: the calibration is right)"
                          : "; beyond 3 sigma: see err/sig above");
}

// One family above its target, with what sets its sigma.
void explain_above_target(const KalmanRun& run, const std::string& family, double sigma,
                          double target, int dwells) {
  const CoefficientFamily& f = coefficient_family_info(family);
  std::printf("  %-20s sigma %.3g > target %.3g %s", family.c_str(), sigma / f.si_per_unit(),
              target / f.si_per_unit(), f.unit().c_str());
  // In the triad frame the table's accuracy has dropped out of the misalignments.
  const bool attitude = run.options.attitude != CalibratorOptions::AttitudeUpdates::None &&
                        !run.converted_to_triad_frame;
  if (attitude && family.find("misalignment") != std::string::npos && dwells > 0) {
    const double limit = run.options.attitude_sigma / std::sqrt(static_cast<double>(dwells));
    std::printf(
        ": the table sets each of the %d dwells to %.2f arcsec, which alone allows "
        "about %.2f arcsec (--table-sigma)\n",
        dwells, run.options.attitude_sigma / units::arcsec, limit / units::arcsec);
  } else {
    std::printf(
        ": the noise over this plan's dwells and turns allows no less (more or longer "
        "dwells would)\n");
  }
}

namespace {
// The table base and the IMU's mounting (arcsec), and the alignment the filter started from.
void print_installation(const InstallationResult& in) {
  auto v = [](const Eigen::Vector3d& x) { return Eigen::Vector3d(x / units::arcsec); };
  if (in.base_estimated) {
    const Eigen::Vector3d b = v(in.base_n), s = v(in.base_sigma_n);
    std::printf(
        "Table base: level %.1f +- %.1f arcsec (North), %.1f +- %.1f arcsec (East), "
        "heading %.1f +- %.1f arcsec\n",
        b.x(), s.x(), b.y(), s.y(), b.z(), s.z());
  } else if (in.base_known) {
    std::printf("Table base: known (--base known): the plan's, not estimated\n");
  }
  if (in.mounting_estimated) {
    const Eigen::Vector3d m = v(in.mounting_b), s = v(in.mounting_sigma_b);
    std::printf(
        "IMU mounting (common rotation of the triads, polar decomposition of the "
        "accelerometer matrix): %.1f +- %.1f, %.1f +- %.1f, %.1f +- %.1f arcsec (x, y, z; "
        "%.4f deg)\n",
        m.x(), s.x(), m.y(), s.y(), m.z(), s.z(), in.mounting_b.norm() / units::deg);
  }
  if (in.alignment && in.alignment->valid && in.alignment_applied)
    std::printf(
        "  (the filter started from the alignment of the dwells: base %.4f deg%s, "
        "mounting %.4f deg)\n",
        in.alignment->base_n.norm() / units::deg, in.base_known ? " not taken, known" : "",
        in.alignment->mounting_b.norm() / units::deg);
  if (in.alignment && in.alignment_streamed && in.alignment->dwells > 0)
    std::printf("  (the stream's alignment: from its first %d dwells, held)\n",
                in.alignment->dwells);
  else if (in.alignment_streamed)
    std::printf("  (the stream's first dwells did not fit in the samples held: not aligned)\n");
}
}  // namespace

void print_innovation_check(const InnovationCheck& c) {
  if (!c.tested()) return;
  std::printf(
      "Innovations against the noise model (NIS upper tail and Ljung-Box whiteness per channel, "
      "alpha %.2g over %d tests): %s\n",
      c.alpha, c.tests, c.consistent ? "consistent" : "NOT consistent");
  std::printf("   %-24s %8s %10s %9s %10s %5s %9s\n", "channel", "updates", "NIS/dof", "p", "Q",
              "lags", "p");
  for (const auto& k : c.channels)
    std::printf("   %-24s %8ld %10.3f %9.2g%s %10.4g %5d %9.2g%s\n", k.channel.c_str(), k.updates,
                k.nis_per_dof, k.nis_p, k.nis_holds ? " " : "*", k.ljung_box_q, k.lags,
                k.ljung_box_p, k.white ? (k.sigma_bound ? "b" : " ") : "*");
  for (const auto& f : c.failures) std::printf("   Not consistent: %s\n", f.c_str());
  std::printf(
      "   (*: fails at alpha / tests; b: the update's sigma is a bound, not the noise (all but the "
      "dwells' zero velocity, or a NIS per dof below its lower quantile): whiteness not "
      "tested)\n");
}

void print_kalman_verdicts(const KalmanRun& run, const SensorProfile& profile,
                           const ResultCoefficients& truth) {
  const ResultCoefficients coefficients = result_coefficients(run);
  std::vector<std::string> fixed;
  for (const auto& [name, c] : coefficients)
    if (c.fixed_by_convention) fixed.push_back(name);
  if (!fixed.empty()) {
    std::printf("\nZero by convention (not estimated):");
    for (const auto& n : fixed) std::printf(" %s", n.c_str());
    std::printf("\n");
  }
  std::printf("\n");
  print_truth_verdict(coefficients, truth);
  print_installation(run.installation);
  if (!run.unobservable.empty()) {
    std::fprintf(stderr,
                 "sinscal calibrate: warning: the plan does not observe these coefficients (the "
                 "data determine them worse than the prior did; reported as not observable):");
    for (const auto& n : run.unobservable) std::fprintf(stderr, " %s", n.c_str());
    std::fprintf(stderr, "\n");
    for (const auto& d : run.unobservable_directions)
      std::fprintf(stderr, "  not determined by the data: %s\n", d.text().c_str());
    for (const auto& n : run.unobservable)
      if (n.rfind("accel.lever_arm.", 0) == 0 && run.options.layout.fixed.empty()) {
        std::fprintf(stderr,
                     "  (a common shift of the lever arms is the IMU reference point: "
                     "--lever-arm-reference x fixes accelerometer x's at zero)\n");
        break;
      }
  }
  if (profile.sigma_targets.empty()) {
    std::printf("Convergence: the sensor profile sets no sigma targets ([targets])\n");
  } else if (run.converged_at) {
    std::printf("Convergence: every sigma below its target from t = %.1f s\n", *run.converged_at);
  } else {
    std::printf(
        "Convergence: %zu of the estimated coefficients stay above their profile's sigma "
        "target (the estimates are still right; the targets ask for more than this plan "
        "gives):\n",
        run.above_target.size());
    std::map<std::string, double> worst;  // family -> largest sigma, SI
    for (const auto& name : run.above_target) {
      const double s =
          coefficients.at(name).sigma.value_or(0.0) * coefficient_info(name).si_per_unit;
      double& w = worst[coefficient_family(name)];
      w = std::max(w, s);
    }
    const int dwells =
        run.options.attitude == CalibratorOptions::AttitudeUpdates::First ? 1 : run.dwells;
    for (const auto& [family, s] : worst)
      explain_above_target(run, family, s, profile.sigma_targets.at(family), dwells);
  }
  if (run.skipped > 0) {
    std::fprintf(stderr, "sinscal calibrate: warning: %zu bad samples skipped, the first:\n",
                 run.skipped);
    for (const auto& m : run.skipped_examples) std::fprintf(stderr, "  %s\n", m.c_str());
  }
}

void print_live_table(const MonitorRecord& rec, const std::map<std::string, double>& targets) {
  std::map<std::string, std::pair<double, const CoefficientInfo*>> worst;  // family -> max sigma
  const auto& cat = coefficient_catalog();
  for (std::size_t i = 0; i < cat.size(); ++i) {
    if (rec.estimates[i].status != CoefficientEstimate::Status::Estimated) continue;
    auto& w = worst[cat[i].family];
    if (rec.estimates[i].sigma >= w.first) w = {rec.estimates[i].sigma, &cat[i]};
  }
  std::fprintf(stderr, "\033[H\033[J");  // home, clear
  std::fprintf(stderr, "sinscal calibrate --method kf   t = %.1f s   NIS/dof %.3f   %s\n", rec.t,
               rec.nis_per_dof, rec.converged ? "CONVERGED" : "converging");
  std::fprintf(stderr, "%-22s %12s %12s %-8s\n", "family", "max sigma", "target", "unit");
  for (const auto& [family, w] : worst) {
    const auto t = targets.find(family);
    const double sigma = w.first / w.second->si_per_unit;
    std::string target = "-";
    if (t != targets.end()) target = fmt("%.4g", t->second / w.second->si_per_unit);
    std::fprintf(stderr, "%-22s %12.4g %12s %-8s %s\n", family.c_str(), sigma, target.c_str(),
                 w.second->unit.c_str(), t != targets.end() && w.first <= t->second ? "ok" : "");
  }
}

void print_closed_form(const ClosedFormReport& r, const ResultCoefficients& coefficients,
                       const ResultCoefficients& truth) {
  std::printf("\nStage 1: equivalent inputs per dwell (value +- sigma)\n");
  std::printf("%5s %-10s %6s %20s %20s %20s %20s %20s %20s %8s\n", "dwell", "label", "T [s]",
              "df_n [ug]", "df_e [ug]", "df_d [ug]", "dw_n [deg/h]", "dw_e [deg/h]", "dw_d [deg/h]",
              "chi2/dof");
  for (const auto& e : r.stage1) {
    std::printf("%5d %-10s %6.1f", e.dwell.index, e.dwell.label.c_str(), e.duration);
    for (int i = 0; i < 6; ++i) {
      const double f = i < 3 ? units::ug : units::deg_per_h;
      if (e.estimated[static_cast<std::size_t>(i)])
        std::printf(" %10.4f +- %6.4f", e.u(i) / f, std::sqrt(e.cov(i, i)) / f);
      else
        std::printf(" %20s", "-");
    }
    std::printf(" %8.3f\n", e.chi2_per_dof);
  }
  const std::size_t base = r.stage2.base_estimated ? 3 : 0;
  std::printf("\nIdentifiability: rank %d of %zu%s; stage-2 chi2 per dof %.3f (%d dof)\n",
              r.stage2.rank, r.stage2.parameters.size() + base,
              base > 0 ? " (the coefficients and the table base's 3 angles)" : "",
              r.stage2.chi2_per_dof, r.stage2.dof);
  for (const auto& u : r.stage2.unobservable_directions)
    std::printf("  unobservable direction: %s\n", u.c_str());
  print_coefficient_table(coefficients, truth);
  std::printf("\n");
  print_installation(r.installation);
  // The limits of a static plan, shown rather than hidden.
  auto sigma_range = [&](const std::string& family) {
    std::pair<double, double> range{1e300, 0.0};
    for (const auto& [name, c] : coefficients)
      if (coefficient_family(name) == family && c.observable && c.sigma)
        range = {std::min(range.first, *c.sigma), std::max(range.second, *c.sigma)};
    return range;
  };
  const auto [smin, smax] = sigma_range("gyro.scale");
  const auto [mmin, mmax] = sigma_range("gyro.misalignment");
  std::printf(
      "\nLimit of static orientations: gyro scale factors and misalignments come from Earth "
      "rate alone:\n  sigma %.0f-%.0f ppm and %.0f-%.0f arcsec. Rotations are needed for them "
      "(Kalman filter, rot19).\n",
      smin, smax, mmin, mmax);
  if (!r.has_paper_forms) return;
  std::printf(
      "\nThe paper's literal closed forms (X and Z sensors) beside the general solution:\n");
  for (const auto& [name, v] : named(r.paper)) {
    const CoefficientInfo& info = coefficient_info(name);
    const auto& c = coefficients.at(name);
    std::printf("  %-24s paper %12.4f   general %12.4f %s\n", name.c_str(), v / info.si_per_unit,
                c.observable ? c.value : std::nan(""), info.unit.c_str());
  }
}

}  // namespace sinscal::cli
