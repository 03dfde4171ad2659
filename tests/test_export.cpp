// sinscal export (report/firmware_export.hpp): the numbers a firmware applies, read back from the
// JSON export and from the C header (compiled with the system C compiler into
// tests/export/apply.c), applied to the raw outputs of a simulated unit and compared with the
// simulator's true omega_ib_b and f_ib_b, within the sigma the coefficients' sigmas give.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "filter/six_face/six_face.hpp"
#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/units.hpp"
#include "report/firmware_export.hpp"
#include "report/result.hpp"
#include "report/six_face_result.hpp"
#include "rig/ferraris.hpp"
#include "rig/session.hpp"
#include "skip.hpp"

using namespace sinscal;

namespace {

using Json = nlohmann::json;
using Eigen::Matrix3d;
using Eigen::Vector3d;

int run(const std::string& command) { return std::system((command + " > /dev/null").c_str()); }

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The export as the firmware reads it: absent terms are zero.
struct ExportedTriad {
  Vector3d b = Vector3d::Zero(), asym = Vector3d::Zero(), k2 = Vector3d::Zero(),
           drift = Vector3d::Zero();
  Matrix3d C = Matrix3d::Identity(), A = Matrix3d::Identity();
};
struct Exported {
  ExportedTriad gyro, accel;
  Matrix3d G = Matrix3d::Zero();
  Matrix3d arms = Matrix3d::Zero();  // row i: r_i
  double tau = 0.0;
};

Vector3d vec(const Json& j, const char* key) {
  if (!j.contains(key)) return Vector3d::Zero();
  return {j[key][0].get<double>(), j[key][1].get<double>(), j[key][2].get<double>()};
}
Matrix3d mat(const Json& j, const char* key) {
  Matrix3d m = Matrix3d::Zero();
  if (!j.contains(key)) return m;
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k) m(i, k) = j[key][i][k].get<double>();
  return m;
}

Exported parse_export(const Json& j) {
  Exported e;
  auto triad = [](const Json& t) {
    ExportedTriad r;
    r.b = vec(t, "bias");
    r.asym = vec(t, "scale_asym");
    r.k2 = vec(t, "k2");
    r.drift = vec(t, "bias_drift");
    r.C = mat(t, "correction_matrix");
    r.A = mat(t, "model_matrix");
    return r;
  };
  e.gyro = triad(j.at("gyro"));
  e.accel = triad(j.at("accel"));
  e.G = mat(j["gyro"], "g_sensitivity");
  e.arms = mat(j["accel"], "lever_arm");
  if (j.contains("time_delay")) e.tau = j["time_delay"]["value"].get<double>();
  return e;
}

// What a correct export of `m` holds, from the model itself.
Exported exported_of(const ImuErrorModel& m) {
  Exported e;
  auto triad = [](const TriadErrors& t) {
    ExportedTriad r;
    r.b = t.bias;
    r.asym = t.scale_asym;
    r.k2 = t.k2;
    r.drift = t.bias_drift;
    r.A = t.linear();
    r.C = r.A.inverse();
    return r;
  };
  e.gyro = triad(m.gyro);
  e.accel = triad(m.accel);
  e.G = m.gyro_g_sensitivity;
  e.arms = m.accel_lever_arm_b.transpose();
  e.tau = m.time_delay;
  return e;
}

// Raw outputs as rates (increments / dt), t the middle of each interval.
struct Raw {
  double dt = 0.0;
  std::vector<double> t;
  std::vector<Vector3d> gyro, accel;
};

Raw raw_of(const std::vector<ImuSample>& samples, double dt) {
  Raw r;
  r.dt = dt;
  for (const auto& s : samples) {
    r.t.push_back(s.t - 0.5 * dt);
    r.gyro.push_back(s.dtheta_b / dt);
    r.accel.push_back(s.dv_b / dt);
  }
  return r;
}

// The formula of the export (docs/formats.md "Firmware export"), step by step.
void apply(const Exported& e, const Raw& raw, std::vector<Vector3d>& w, std::vector<Vector3d>& f) {
  const auto n = static_cast<long>(raw.t.size());
  std::vector<Vector3d> ya(raw.t.size());
  w.assign(raw.t.size(), Vector3d::Zero());
  f.assign(raw.t.size(), Vector3d::Zero());
  for (long k = 0; k < n; ++k) {
    const auto K = static_cast<std::size_t>(k);
    // 0. the accelerometer output at t + tau
    const double pos = static_cast<double>(k) + e.tau / raw.dt;
    const long j = std::clamp(static_cast<long>(std::floor(pos)), 0L, n - 2);
    const double frac = pos - static_cast<double>(j);
    const auto J = static_cast<std::size_t>(j);
    ya[K] = raw.accel[J] + frac * (raw.accel[J + 1] - raw.accel[J]);
    // 1. gyros, the g-sensitivity on the accelerometers' linear estimate
    const Vector3d f0 = e.accel.C * (ya[K] - e.accel.b - e.accel.drift * raw.t[K]);
    const Vector3d ug = raw.gyro[K] - e.gyro.b - e.gyro.drift * raw.t[K] - e.G * f0;
    const Vector3d vg = e.gyro.C * ug;
    w[K] = e.gyro.C * (ug - e.gyro.asym.cwiseProduct(vg.cwiseAbs()));
  }
  for (long k = 0; k < n; ++k) {
    const auto a = static_cast<std::size_t>(std::max(k - 1, 0L));
    const auto b = static_cast<std::size_t>(std::min(k + 1, n - 1));
    const auto K = static_cast<std::size_t>(k);
    // 2. the size effect
    const Vector3d wd = (w[b] - w[a]) / (static_cast<double>(b - a) * raw.dt);
    Vector3d s;
    for (int i = 0; i < 3; ++i) {
      const Vector3d r = e.arms.row(i).transpose();
      s(i) = e.accel.A.row(i).dot(wd.cross(r) + w[K].cross(w[K].cross(r)));
    }
    // 3. accelerometers
    const Vector3d ua = ya[K] - e.accel.b - e.accel.drift * raw.t[K] - s;
    const Vector3d va = e.accel.C * ua;
    f[K] = e.accel.C * (ua - e.accel.asym.cwiseProduct(va.cwiseAbs()) -
                        e.accel.k2.cwiseProduct(va.cwiseAbs2()));
  }
}

// A model with every family on (sizes of a navigation-grade unit, MEMS-size asymmetry).
ImuErrorModel full_model() {
  ImuErrorModel m =
      SensorProfile::load(test::source_path("config/sensors/nav-fog-extended.ini")).draw(7);
  m.gyro.scale_asym = Vector3d(300, -200, 100) * units::ppm;
  m.accel.scale_asym = Vector3d(-150, 250, 50) * units::ppm;
  m.gyro_g_sensitivity << 0.1, -0.05, 0.02, 0.03, 0.2, -0.1, -0.07, 0.04, 0.15;
  m.gyro_g_sensitivity *= units::deg_per_h_per_g;
  m.gyro.bias_drift = Vector3d(0.01, -0.02, 0.03) * units::deg_per_h / units::hour;
  m.accel.bias_drift = Vector3d(5, -3, 2) * units::ug / units::hour;
  return m;
}

// A result file of `m` with every coefficient, sigma 1 % of the value's unit.
void write_result(const std::string& path, const ImuErrorModel& m,
                  const nlohmann::ordered_json& extra) {
  ResultCoefficients rc;
  for (const auto& [name, v] : m.coefficients()) {
    ResultCoefficient c;
    c.value = v;
    c.sigma = 0.01;
    c.unit = coefficient_info(name).unit;
    rc[name] = c;
  }
  write_result_json(path, rc, extra);
}

nlohmann::ordered_json kf_method() {
  return {{"method", {{"name", "kf"}, {"body_frame", "table"}}}};
}

bool have_cc() { return std::system("command -v cc > /dev/null 2>&1") == 0; }

// Compiles tests/export/apply.c with `header`, runs it on `raw`, reads its output.
bool run_c_apply(const std::string& dir, const std::string& header, const Raw& raw,
                 std::vector<Vector3d>& w, std::vector<Vector3d>& f) {
  const std::string exe = dir + "/apply";
  const std::string compile =
      "cc -std=c99 -Wall -Wextra -Wpedantic -Werror -O2 "
      "-DSINSCAL_EXPORT_HEADER='\"" +
      header + "\"' -o " + exe + " " + test::source_path("tests/export/apply.c") + " -lm";
  if (std::system(compile.c_str()) != 0) return false;
  {
    std::ofstream in(dir + "/raw.txt");
    in.precision(17);
    in << raw.t.size() << " " << raw.dt << "\n";
    for (std::size_t k = 0; k < raw.t.size(); ++k)
      in << raw.t[k] << " " << raw.gyro[k].transpose() << " " << raw.accel[k].transpose() << "\n";
  }
  if (std::system((exe + " < " + dir + "/raw.txt > " + dir + "/out.txt").c_str()) != 0)
    return false;
  std::ifstream out(dir + "/out.txt");
  w.clear();
  f.clear();
  Vector3d a, b;
  while (out >> a(0) >> a(1) >> a(2) >> b(0) >> b(1) >> b(2)) {
    w.push_back(a);
    f.push_back(b);
  }
  return w.size() == raw.t.size();
}

}  // namespace

TEST_CASE("Export: the result's numbers, the correction matrices, every format", "[export]") {
  const std::string dir = test::temp_dir("export_formats");
  const ImuErrorModel m = full_model();
  write_result(dir + "/r.json", m, kf_method());
  const FirmwareExport e = read_result_for_export(dir + "/r.json");
  CHECK(e.method == "kf");
  CHECK(e.body_frame == "table platform");
  // Every family but the thermal ones (zero here: the export has no temperature compensation).
  std::size_t non_thermal = 0;
  for (const auto& f : coefficient_families()) non_thermal += f.thermal() ? 0 : 1;
  CHECK(e.families.size() == non_thermal);
  CHECK((e.model.vector() - m.vector()).cwiseAbs().maxCoeff() <=
        1e-12 * m.vector().cwiseAbs().maxCoeff());

  const Json j = Json::parse(render_export(e, ExportFormat::Json));
  CHECK(j["body_frame"] == "table platform");
  CHECK(j["units"]["angular_rate"] == "rad/s");
  const Exported x = parse_export(j);
  CHECK((x.gyro.C * m.gyro.linear() - Matrix3d::Identity()).norm() < 1e-14);
  CHECK((x.accel.C * m.accel.linear() - Matrix3d::Identity()).norm() < 1e-14);
  CHECK((x.gyro.b - m.gyro.bias).norm() == 0.0);
  CHECK((x.arms - m.accel_lever_arm_b.transpose()).norm() == 0.0);
  CHECK(x.tau == m.time_delay);
  // Sigmas in SI: 0.01 of each coefficient's result unit.
  CHECK(j["gyro"]["bias_sigma"][0].get<double>() == Approx(0.01 * units::deg_per_h));
  CHECK(j["accel"]["model_matrix_sigma"][0][1].get<double>() == Approx(0.01 * units::arcsec));

  SECTION("the firmware form inverts the model to its stated first-order accuracy") {
    // Constant inputs (rates, specific forces, a turn at constant rate): no delay or omega_dot.
    const Json acc = j["accuracy"];
    for (const auto& [w_true, f_true] :
         {std::pair{Vector3d(1e-5, -2e-5, 7e-5), Vector3d(0.1, -0.2, -9.8)},
          std::pair{Vector3d(0.3, -0.2, 0.1), Vector3d(6.9, -6.9, 0.3)},
          std::pair{Vector3d(-1.0, 0.5, 2.0), Vector3d(-20.0, 5.0, 12.0)}}) {
      KinematicSample s;
      s.omega_ib_b = w_true;
      s.f_ib_b = f_true;
      s.t = 600.0;
      Raw raw;
      raw.dt = 0.01;
      for (int k = 0; k < 3; ++k) {
        raw.t.push_back(s.t);
        raw.gyro.push_back(m.gyro_output(s));
        raw.accel.push_back(m.accel_output(s));
      }
      std::vector<Vector3d> w, f;
      apply(x, raw, w, f);
      // Second order in the nonlinear terms (accuracy in the export) and |G| |C s|.
      const double fx = f_true.cwiseAbs().maxCoeff();
      const double bound_f = (acc["accel_nonlinear_error_at_1g_m_per_s2"].get<double>() + 1e-15) *
                             std::pow(std::max(fx / units::g0, 1.0), 3.0) * 3.0;
      CAPTURE(w_true.transpose(), f_true.transpose(), bound_f);
      CHECK((f[1] - f_true).cwiseAbs().maxCoeff() <= bound_f + 1e-13 * fx);
      // What G f0 leaves out: |G| |f - f0|, f0 lacking the size effect s = w x (w x r) (|r| <=
      // 0.1 m) and the nonlinear terms (|a| + |k2| |f|) |f|.
      const double lacking = w_true.squaredNorm() * 0.1 + (300e-6 + 3e-6 * fx) * fx;
      const double bound_w = 3.0 * (300e-6 * 300e-6) * w_true.cwiseAbs().maxCoeff() +
                             m.gyro_g_sensitivity.norm() * lacking + 1e-15;
      CHECK((w[1] - w_true).cwiseAbs().maxCoeff() <= bound_w);
    }
  }
  SECTION("YAML: the same data (parsed back with Python's yaml: skipped without it)") {
    const std::string yaml = render_export(e, ExportFormat::Yaml);
    CHECK(yaml.find("correction_matrix:\n    - [") != std::string::npos);
    CHECK(yaml.find("body_frame: \"table platform\"") != std::string::npos);
    test::write_file(dir + "/e.yaml", yaml);
    test::write_file(dir + "/e.json", render_export(e, ExportFormat::Json));
    if (std::system("python3 -c 'import yaml' > /dev/null 2>&1") != 0) {
      test::skip(
          "python3 with yaml not installed (apt-get install python3-yaml): the YAML export "
          "is not parsed back");
    } else {
      CHECK(std::system(("python3 -c 'import json, sys, yaml; "
                         "a = yaml.safe_load(open(sys.argv[1])); b = json.load(open(sys.argv[2])); "
                         "sys.exit(0 if a == b else 1)' " +
                         dir + "/e.yaml " + dir + "/e.json")
                            .c_str()) == 0);
    }
  }
  SECTION("C header: compiles with -Wall -Wextra -Wpedantic -Werror and gives the JSON's numbers") {
    if (!have_cc()) {
      test::skip("no C compiler 'cc' on this machine: the C header is not compiled");
      return;
    }
    const std::string header = dir + "/sinscal_calibration.h";
    test::write_file(header, render_export(e, ExportFormat::CHeader));
    KinematicSample s;
    Raw raw;
    raw.dt = 0.01;
    for (int k = 0; k < 5; ++k) {
      s.t = 0.01 * k;
      s.omega_ib_b = Vector3d(0.3, -0.2, 0.1) * (1.0 + 0.1 * k);
      s.f_ib_b = Vector3d(1.0, -2.0, -9.5) + 0.01 * k * Vector3d::Ones();
      raw.t.push_back(s.t);
      raw.gyro.push_back(m.gyro_output(s));
      raw.accel.push_back(m.accel_output(s));
    }
    std::vector<Vector3d> wc, fc, wj, fj;
    REQUIRE(run_c_apply(dir, header, raw, wc, fc));
    apply(x, raw, wj, fj);
    for (std::size_t k = 0; k < wc.size(); ++k) {
      CHECK((wc[k] - wj[k]).norm() <= 1e-15 * (1.0 + wj[k].norm()));
      CHECK((fc[k] - fj[k]).norm() <= 1e-14 * (1.0 + fj[k].norm()));
    }
  }
}

TEST_CASE("Export: what a result lacks or failed is refused with file and cause", "[export]") {
  const std::string dir = test::temp_dir("export_refused");
  const ImuErrorModel m = full_model();
  auto refused = [&](const std::string& name, const std::string& text, const std::string& cause) {
    const std::string path = dir + "/" + name;
    test::write_file(path, text);
    CAPTURE(name);
    CHECK_THROWS_WITH(read_result_for_export(path),
                      Catch::Contains(path) && Catch::Contains(cause));
  };
  refused("not.json", "gyro.bias.x = 1\n", "not a sinscal result file (not JSON");
  refused("nocoef.json", "{\"method\": {\"name\": \"kf\"}}", "no \"coefficients\" object");
  write_result(dir + "/truth.json", m, {{"note", "simulate ..."}});
  CHECK_THROWS_WITH(read_result_for_export(dir + "/truth.json"),
                    Catch::Contains("a truth file (simulate's), not a calibration result"));
  write_result(dir + "/nomethod.json", m, nlohmann::ordered_json::object());
  CHECK_THROWS_WITH(read_result_for_export(dir + "/nomethod.json"),
                    Catch::Contains("no \"method\" section"));

  write_result(dir + "/ok.json", m, kf_method());
  const Json full = Json::parse(read_text(dir + "/ok.json"));
  auto variant = [&](const std::string& name, const std::function<void(Json&)>& change) {
    Json v = full;
    change(v);
    const std::string path = dir + "/" + name;
    test::write_file(path, v.dump(2));
    return path;
  };
  auto cause = [](const std::string& path, const std::string& text, bool force = false) {
    FirmwareExportOptions o;
    o.force = force;
    CAPTURE(path, force);
    CHECK_THROWS_WITH(read_result_for_export(path, o),
                      Catch::Contains(path) && Catch::Contains(text));
  };
  cause(variant("unknown.json",
                [](Json& v) {
                  v["coefficients"]["gyro.wobble.x"] = {{"value", 1}};
                }),
        "unknown coefficient 'gyro.wobble.x'", true);
  cause(variant("unit.json", [](Json& v) { v["coefficients"]["gyro.bias.x"]["unit"] = "deg/s"; }),
        "'gyro.bias.x' is in 'deg/s', results give it in 'deg/h'", true);
  cause(variant("missing.json", [](Json& v) { v["coefficients"].erase("accel.scale.y"); }),
        "coefficients missing (accel.scale.y)", true);
  cause(variant("partial.json", [](Json& v) { v["coefficients"].erase("accel.lever_arm.z.x"); }),
        "coefficients missing (accel.lever_arm.z.x)", true);
  cause(variant("nan.json", [](Json& v) { v["coefficients"]["gyro.bias.y"].erase("value"); }),
        "'gyro.bias.y' has no finite value", true);
  cause(variant("type.json",
                [](Json& v) { v["coefficients"]["gyro.bias.y"]["fixed_by_convention"] = "yes"; }),
        "'gyro.bias.y': \"fixed_by_convention\" must be true or false", true);
  cause(variant("sigma.json", [](Json& v) { v["coefficients"]["gyro.bias.y"]["sigma"] = -1; }),
        "'gyro.bias.y': a sigma must be a finite number > 0", true);

  // Failed verdicts: refused, exported with --force and a warning.
  const std::string gate = variant("gate.json", [](Json& v) {
    v["plausibility"] = {
        {"passed", false},
        {"checks", Json::array({Json{{"check", "Earth rate"}, {"passed", false}}})}};
  });
  cause(gate, "the plausibility gate failed (Earth rate)");
  cause(gate, "--force exports it anyway");
  cause(variant("diverged.json",
                [](Json& v) {
                  v["diverged"] = {{"reason", "NIS"}};
                }),
        "the filter diverged (NIS)");
  cause(variant("stopped.json",
                [](Json& v) {
                  v["stopped"] = {{"reason", "imu.csv:30: NaN"}};
                }),
        "the run stopped before the end of the data (imu.csv:30: NaN)");
  cause(variant("notconv.json", [](Json& v) { v["method"]["converged"] = false; }),
        "the solution did not converge");
  FirmwareExportOptions force;
  force.force = true;
  const FirmwareExport forced = read_result_for_export(gate, force);
  REQUIRE(forced.warnings.size() == 1);
  CHECK(render_export(forced, ExportFormat::CHeader).find("WARNING (--force)") !=
        std::string::npos);

  // Unobservable coefficients: refused; with --force zero, listed, their sigma kept.
  const std::string unobs = variant("unobs.json", [](Json& v) {
    v["coefficients"]["gyro.scale.z"] = {{"observable", false}, {"sigma", 44.1}, {"unit", "ppm"}};
  });
  cause(unobs,
        "1 coefficients are not determined by the data (\"observable\": false): gyro.scale.z");
  const FirmwareExport zero = read_result_for_export(unobs, force);
  CHECK(zero.model.gyro.scale.z() == 0.0);
  CHECK(zero.sigma.gyro.scale.z() == Approx(44.1 * units::ppm));
  CHECK(zero.unobservable == std::vector<std::string>{"gyro.scale.z"});
  const Json zj = Json::parse(render_export(zero, ExportFormat::Json));
  CHECK(zj["unobservable_exported_as_zero"][0] == "gyro.scale.z");
  // Coefficients fixed by the body frame's convention are zero and listed, not refused.
  const std::string triad = variant("triad.json", [](Json& v) {
    v["method"]["body_frame"] = "accelerometer triad";
    for (const char* c :
         {"accel.misalignment.xy", "accel.misalignment.xz", "accel.misalignment.yz"})
      v["coefficients"][c] = {{"value", 0}, {"fixed_by_convention", true}, {"unit", "arcsec"}};
  });
  const FirmwareExport t = read_result_for_export(triad);
  CHECK(t.reference_point.find("the IMU reference point") == 0);
  CHECK(t.body_frame == "accelerometer triad");
  // The lever-arm reference: the compensated outputs are at that accelerometer's proof mass.
  const FirmwareExport ref = read_result_for_export(variant("reference.json", [](Json& v) {
    for (const char* c : {"accel.lever_arm.y.x", "accel.lever_arm.y.y", "accel.lever_arm.y.z"})
      v["coefficients"][c] = {{"value", 0}, {"fixed_by_convention", true}, {"unit", "mm"}};
  }));
  CHECK(ref.reference_point.find("the proof mass of the y accelerometer") == 0);
  CHECK(ref.model.accel_lever_arm_b.col(1).isZero(0.0));
  CHECK(t.fixed_by_convention.size() == 3);
  CHECK(t.model.accel.misalignment(0, 1) == 0.0);
}

namespace {

// Block means of the compensated outputs against the truth, and the sigma of each block's mean
// that the coefficients' sigmas give (first order, coefficients independent: a result file has
// no covariance): the output error J dtheta of the model's Jacobian, taken to the input by C.
struct BlockCheck {
  double max_z = 0.0, rms_z = 0.0;  // |mean residual| / sigma over blocks and axes
  double max_excess = 0.0;          // largest |mean residual| - 4 sigma - form error (<= 0: ok)
  std::size_t blocks = 0;
};

struct BlockTruth {
  std::vector<Vector3d> w_true, f_true;            // block means of the truth
  std::vector<Eigen::Matrix<double, 6, 1>> sigma;  // of the compensated block means
};

// `truth` and the motion in the body frame of the simulation; the result's body frame r has
// x_b = C_r_b x_r.
BlockTruth block_truth(const Motion& motion, const Raw& truth, const FirmwareExport& e,
                       const Matrix3d& C_r_b, std::size_t block) {
  const Matrix3d C_b_r = C_r_b.transpose();
  BlockTruth bt;
  const Eigen::VectorXd sig = e.sigma.vector();
  const Matrix3d Cg = e.model.gyro.linear().inverse(), Ca = e.model.accel.linear().inverse();
  for (std::size_t b0 = block; b0 + 2 * block <= truth.t.size(); b0 += block) {
    Vector3d w = Vector3d::Zero(), f = Vector3d::Zero();
    Eigen::Matrix<double, 6, Eigen::Dynamic> M =
        Eigen::Matrix<double, 6, Eigen::Dynamic>::Zero(6, sig.size());
    for (std::size_t k = b0; k < b0 + block; ++k) {
      w += C_b_r * truth.gyro[k] / static_cast<double>(block);
      f += C_b_r * truth.accel[k] / static_cast<double>(block);
      KinematicSample s = motion.at(truth.t[k]).imu;
      s.t = truth.t[k];
      s.omega_ib_b = C_b_r * s.omega_ib_b;
      s.omega_dot_ib_b = C_b_r * s.omega_dot_ib_b;
      s.f_ib_b = C_b_r * s.f_ib_b;
      const double h = 1e-3;
      const Vector3d f_dot =
          C_b_r * (motion.at(truth.t[k] + h).imu.f_ib_b - motion.at(truth.t[k] - h).imu.f_ib_b) /
          (2 * h);
      const auto J = e.model.jacobian(s, f_dot);
      M.topRows<3>() += Cg * J.topRows<3>() / static_cast<double>(block);
      M.bottomRows<3>() += Ca * J.bottomRows<3>() / static_cast<double>(block);
    }
    bt.w_true.push_back(w);
    bt.f_true.push_back(f);
    Eigen::Matrix<double, 6, 1> s;
    for (int i = 0; i < 6; ++i) s(i) = M.row(i).cwiseProduct(sig.transpose()).norm();
    bt.sigma.push_back(s);
  }
  return bt;
}

std::vector<Eigen::Matrix<double, 6, 1>> block_residuals(const std::vector<Vector3d>& w,
                                                         const std::vector<Vector3d>& f,
                                                         const BlockTruth& bt, std::size_t block) {
  std::vector<Eigen::Matrix<double, 6, 1>> out;
  for (std::size_t b = 0; b < bt.w_true.size(); ++b) {
    Eigen::Matrix<double, 6, 1> r = Eigen::Matrix<double, 6, 1>::Zero();
    const std::size_t b0 = (b + 1) * block;
    for (std::size_t k = b0; k < b0 + block; ++k) {
      r.head<3>() += w[k] / static_cast<double>(block);
      r.tail<3>() += f[k] / static_cast<double>(block);
    }
    r.head<3>() -= bt.w_true[b];
    r.tail<3>() -= bt.f_true[b];
    out.push_back(r);
  }
  return out;
}

BlockCheck check_blocks(const std::vector<Eigen::Matrix<double, 6, 1>>& residual,
                        const std::vector<Eigen::Matrix<double, 6, 1>>& form,
                        const BlockTruth& bt) {
  BlockCheck c;
  double sum = 0.0;
  for (std::size_t b = 0; b < residual.size(); ++b)
    for (int i = 0; i < 6; ++i) {
      const double z = std::abs(residual[b](i)) / bt.sigma[b](i);
      c.max_z = std::max(c.max_z, z);
      sum += z * z;
      c.max_excess = std::max(
          c.max_excess, std::abs(residual[b](i)) - 4.0 * bt.sigma[b](i) - std::abs(form[b](i)));
    }
  c.blocks = residual.size();
  c.rms_z = std::sqrt(sum / (6.0 * static_cast<double>(residual.size())));
  return c;
}

}  // namespace

namespace {

// A calibrated simulation, exported (JSON and C header by the command line) and applied to the
// unit's raw outputs without noise: the block means against the truth.
struct RoundTrip {
  std::string dir;
  FirmwareExport e;
  Exported x;
  Raw raw;
  BlockTruth bt;
  std::vector<Eigen::Matrix<double, 6, 1>> form;  // the formula's own error (true coefficients)
  double form_max = 0.0;
  std::size_t block = 0;
  BlockCheck check(const Exported& exported) const {
    std::vector<Vector3d> w, f;
    apply(exported, raw, w, f);
    return check_blocks(block_residuals(w, f, bt, block), form, bt);
  }
};

// `dir`/result.json calibrated from a simulation of `motion` with the sensor errors `sensor`
// (the simulation's body frame b); the result's frame r has x_b = C_r_b x_r, `truth_r` is the
// truth in it.
RoundTrip round_trip(const std::string& dir, const Motion& motion, const ImuErrorModel& sensor,
                     const ImuErrorModel& truth_r, const Matrix3d& C_r_b, double rate_hz) {
  const std::string bin = SINSCAL_BINARY;
  RoundTrip rt;
  rt.dir = dir;
  REQUIRE(run(bin + " export --result " + dir + "/result.json --format json --out " + dir +
              "/export.json") == 0);
  REQUIRE(run(bin + " export " + dir + "/result.json --format c-header --out " + dir +
              "/sinscal_calibration.h") == 0);
  rt.e = read_result_for_export(dir + "/result.json");
  rt.x = parse_export(Json::parse(read_text(dir + "/export.json")));
  const double dt = 1.0 / rate_hz;
  rt.raw = raw_of(test::simulate(motion, sensor, rate_hz), dt);
  const Raw truth = raw_of(test::simulate(motion, ImuErrorModel{}, rate_hz), dt);
  rt.block = static_cast<std::size_t>(std::lround(0.5 * rate_hz));  // 0.5 s: the differences of
  rt.bt = block_truth(motion, truth, rt.e, C_r_b, rt.block);        // steps 0 and 2 telescope
  // The form's own error: the true coefficients through the same formula (taken from the model
  // here, not from the export, so that a fault of the export cannot hide in it).
  std::vector<Vector3d> w, f;
  apply(exported_of(truth_r), rt.raw, w, f);
  rt.form = block_residuals(w, f, rt.bt, rt.block);
  for (const auto& r : rt.form)
    rt.form_max = std::max(rt.form_max, r.tail<3>().cwiseAbs().maxCoeff());
  return rt;
}

// The JSON export and the compiled C header both within the sigma of the coefficients.
void check_round_trip(const RoundTrip& rt, const std::string& what) {
  const BlockCheck c = rt.check(rt.x);
  INFO(what << ", JSON export: " << c.blocks << " blocks of 0.5 s, |residual| / sigma: max "
            << c.max_z << ", RMS " << c.rms_z << "; form error (true coefficients) up to "
            << rt.form_max << " m/s^2");
  CHECK(c.max_excess <= 0.0);
  if (!have_cc()) {
    test::skip("no C compiler 'cc' on this machine: the C header is not compiled");
    return;
  }
  std::vector<Vector3d> wc, fc, w, f;
  REQUIRE(run_c_apply(rt.dir, rt.dir + "/sinscal_calibration.h", rt.raw, wc, fc));
  const BlockCheck cc = check_blocks(block_residuals(wc, fc, rt.bt, rt.block), rt.form, rt.bt);
  INFO("C header: max |residual| / sigma " << cc.max_z << ", RMS " << cc.rms_z);
  CHECK(cc.max_excess <= 0.0);
  apply(rt.x, rt.raw, w, f);
  double diff = 0.0;
  for (std::size_t k = 0; k < wc.size(); ++k)
    diff = std::max(diff, std::max((wc[k] - w[k]).norm(), (fc[k] - f[k]).norm()));
  CHECK(diff <= 1e-12);
}

}  // namespace

TEST_CASE("Export: a unit calibrated by the Kalman filter, exported and applied matches the truth",
          "[export][cli][long]") {
  const std::string dir = test::temp_dir("export_roundtrip_kf");
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/rot19.ini");
  spec.data_sensor_path = test::source_path("config/sensors/nav-fog-extended.ini");
  spec.rate_hz = 50.0;
  spec.seed = 3;
  const SimulatedSession sim = simulate_session(dir + "/session", spec);
  REQUIRE(run(std::string(SINSCAL_BINARY) + " calibrate --method kf --session " + sim.session_path +
              " --out " + dir + "/result.json") == 0);
  const Motion motion = build_motion(sim.plan, sim.plan.site);
  const RoundTrip rt =
      round_trip(dir, motion, sim.truth, sim.truth, Matrix3d::Identity(), spec.rate_hz);
  check_round_trip(rt, "kf, rot19, nav-fog-extended");
  // The test sees a sign flipped in the export: each of these fails it.
  for (int flip = 0; flip < 6; ++flip) {
    Exported bad = rt.x;
    if (flip == 0) bad.gyro.C = rt.x.gyro.A;  // A exported instead of A^-1
    if (flip == 1) bad.accel.C = rt.x.accel.A;
    if (flip == 2) bad.accel.b = -rt.x.accel.b;  // +b
    if (flip == 3) bad.tau = -rt.x.tau;
    if (flip == 4) bad.arms = -rt.x.arms;
    if (flip == 5) bad.accel.k2 = -rt.x.accel.k2;
    CAPTURE(flip);
    CHECK(rt.check(bad).max_excess > 0.0);
  }
}

TEST_CASE("Export: a unit calibrated by the closed form, exported and applied matches the truth",
          "[export][cli][long]") {
  const std::string dir = test::temp_dir("export_roundtrip_cf");
  SessionSimulation spec;
  spec.plan_path = test::source_path("config/plans/seed8.ini");
  spec.data_sensor_path = test::source_path("config/sensors/nav-fog.ini");
  spec.rate_hz = 20.0;
  spec.seed = 5;
  const SimulatedSession sim = simulate_session(dir + "/session", spec);
  REQUIRE(run(std::string(SINSCAL_BINARY) + " calibrate --method closed-form --session " +
              sim.session_path + " --out " + dir + "/result.json") == 0);
  const Motion motion = build_motion(sim.plan, sim.plan.site);
  check_round_trip(
      round_trip(dir, motion, sim.truth, sim.truth, Matrix3d::Identity(), spec.rate_hz),
      "closed form, seed8, nav-fog");
}

TEST_CASE("Export: a hand-held unit calibrated table-free, exported and applied matches the truth",
          "[export][cli][long]") {
  // A MEMS unit (percent scale factors, degrees of misalignment, tens of mg of bias) turned by
  // hand between 37 poses, logged in SI; the result's frame is the accelerometer triad's.
  const std::string dir = test::temp_dir("export_roundtrip_table_free");
  SensorProfile mems;
  mems.ranges["gyro.bias"] = test::range(0.5 * units::deg_per_s, 1.0 * units::deg_per_s);
  mems.ranges["gyro.scale"] = test::range(0.01, 0.03);
  mems.ranges["gyro.misalignment"] = test::range(300 * units::arcsec, 3000 * units::arcsec);
  mems.ranges["accel.bias"] = test::range(5 * units::mg, 40 * units::mg);
  mems.ranges["accel.scale"] = test::range(0.01, 0.03);
  mems.ranges["accel.misalignment"] = test::range(300 * units::arcsec, 3000 * units::arcsec);
  mems.noise.gyro.white = 0.3 * units::deg_per_sqrt_h;
  mems.noise.accel.white = 150 * units::ug_per_sqrt_hz;
  const ImuErrorModel sensor = mems.draw(21);
  Site site;
  site.lat_rad = 45.0 * units::deg;
  site.h_m = 100.0;
  const Motion motion = handheld_motion(site, HandheldOptions{}, 22);
  const double rate = 100.0;
  {
    std::ofstream a(dir + "/acc.txt"), g(dir + "/gyro.txt");
    a.precision(12);
    g.precision(12);
    for (const auto& r :
         readings_from_samples(test::simulate(motion, sensor, rate, &mems.noise, 23))) {
      a << r.t << " " << r.accel.transpose() << "\n";
      g << r.t << " " << r.gyro.transpose() << "\n";
    }
  }
  test::write_file(dir + "/session.ini",
                   "[session]\nname = handheld\nrate = 100 Hz\n\n[site]\nlatitude = 45 deg\n"
                   "height = 100 m\n\n[log]\nformat = custom\naccel_file = acc.txt\n"
                   "gyro_file = gyro.txt\ndelimiter = whitespace\naccel = rate\n"
                   "accel_unit = m/s^2\ngyro = rate\ngyro_unit = rad/s\n");
  REQUIRE(run(std::string(SINSCAL_BINARY) + " calibrate --method table-free --session " + dir +
              "/session.ini --out " + dir + "/result.json") == 0);
  Matrix3d C_a_b;
  const ImuErrorModel truth_a = in_accel_triad_frame(sensor, &C_a_b);
  const RoundTrip rt = round_trip(dir, motion, sensor, truth_a, C_a_b, rate);
  CHECK(rt.e.body_frame == "accelerometer triad");
  CHECK(rt.e.fixed_by_convention.size() == 3);
  check_round_trip(rt, "table-free, hand-held MEMS");
}

TEST_CASE("Export: a unit calibrated on six faces, exported and applied matches the truth",
          "[export]") {
  // A simulated Ferraris session of the MEMS profile's base terms, calibrated, its result file
  // written as calibrate writes it; the frame is the box's faces (the simulation's body frame).
  const std::string dir = test::temp_dir("export_roundtrip_six_face");
  const SensorProfile prof = SensorProfile::load(test::source_path("config/sensors/mems.ini"));
  Site site;
  site.lat_rad = 49.6 * units::deg;
  site.h_m = 280.0;
  const FerrarisOptions fo;
  const FerrarisSession session = ferraris_session(site, fo, 4);
  ImuErrorModel truth = prof.draw(41);
  for (auto& [info, value] : truth.coefficient_refs())
    if (!coefficient_family_info(info.family).base) *value = 0.0;
  const double rate = 100.0;
  PartAccumulator parts({"x_rot", "y_rot", "z_rot"});
  for (const auto& s : test::simulate(session.motion, truth, rate, &prof.noise, 43))
    parts.push(s, session.label_at(s.t - 0.5 * s.dt));
  SixFaceOptions o;
  o.site = site;
  o.declared.face_accuracy = fo.face_tilt;
  o.declared.turn_accuracy = fo.turn_angle_error;
  o.gyro_bias_instability = prof.noise.gyro.bias_instability;
  o.accel_bias_instability = prof.noise.accel.bias_instability;
  const SixFaceResult r = six_face_calibrate(parts.parts(), o);
  write_result_json(dir + "/result.json", result_coefficients(r),
                    result_sections(r, o, LogFormat{}));
  const RoundTrip rt = round_trip(dir, session.motion, truth, truth, Matrix3d::Identity(), rate);
  CHECK(rt.e.body_frame == "box faces");
  check_round_trip(rt, "six-face, Ferraris session, MEMS");
}
