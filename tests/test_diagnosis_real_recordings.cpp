// The hand-held diagnosis on the bundled real recordings (issue 33's acceptance: "Xsens: still
// g-sensitivity first, with its held-out gain; MPU-6050: no name that the held-out data
// contradict"). Every finding must predict the poses and turns it was not fitted to (each one
// predicted by the fit without it: filter/diagnosis/handheld_diagnosis.hpp) better than the model
// before it, by more than the held-out chi-square's 99 % point of the finding's components: a
// name the held-out data contradict, or do not support, turns it red. docs/measured/README.md.
#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <catch2/catch.hpp>

#include "filter/diagnosis/handheld_diagnosis.hpp"
#include "filter/table_free/handheld_run.hpp"
#include "helpers.hpp"
#include "rig/session.hpp"

using namespace sinscal;

namespace {

HandheldDiagnosis diagnose_recording(const std::string& session_ini) {
  const Session session =
      Session::load(test::source_path(session_ini), Session::PlanNeed::Optional);
  // The session's [table_free] settings, as `sinscal diagnose` applies them.
  TableFreeRunOptions o;
  const TableFreeSettings& t = session.table_free;
  if (t.pose_window) o.detector.window = *t.pose_window;
  if (t.min_pose) o.detector.min_duration = *t.min_pose;
  if (t.pose_accel_only) o.detector.use_gyro = !*t.pose_accel_only;
  if (t.edge_trim) o.calibration.edge_trim = *t.edge_trim;
  const TableFreeRun run = run_table_free(session, o);
  REQUIRE(run.result.converged);
  return diagnose_handheld(run.readings, run.result, run.options);
}

// Each finding against the model before it: the held-out chi-square falls by more than its 99 %
// point on the finding's separable components (the gain the finding's own columns could make by
// chance), and the held-out RMS in sigmas falls too.
void check_heldout_gains(const HandheldDiagnosis& d) {
  const FitFigures* before = &d.report.initial;
  for (const CandidateTest& f : d.report.findings) {
    const double dof = static_cast<double>(std::max<std::size_t>(1, f.separable.size()));
    const double q = boost::math::quantile(boost::math::chi_squared(dof), 0.99);
    INFO(f.family << ": held-out chi2 " << before->heldout_chi2 << " -> " << f.with.heldout_chi2
                  << " (99 % point of the gain " << q << "), sigmas " << before->heldout << " -> "
                  << f.with.heldout);
    CHECK(before->heldout_chi2 - f.with.heldout_chi2 > q);
    CHECK(f.with.heldout < before->heldout);
    before = &f.with;
  }
}

}  // namespace

TEST_CASE("Diagnosis of the Xsens recording: gyro g-sensitivity first, held out",
          "[diagnosis][handheld][measured]") {
  const HandheldDiagnosis d = diagnose_recording("config/measured/xsens-mti-handheld/session.ini");
  REQUIRE_FALSE(d.report.findings.empty());
  CHECK(d.report.findings.front().family == "gyro.g_sensitivity");
  check_heldout_gains(d);
}

TEST_CASE("Diagnosis of the MPU-6050 recording: no name the held-out data contradict",
          "[diagnosis][handheld][measured]") {
  const HandheldDiagnosis d = diagnose_recording("config/measured/mpu6050-calibration/session.ini");
  check_heldout_gains(d);
}
