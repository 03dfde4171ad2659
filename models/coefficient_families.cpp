#include "models/coefficient_families.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

#include "models/imu_error_model.hpp"
#include "models/units.hpp"

namespace sinscal {

namespace {

// The physical ranges (CoefficientFamily::plausible_max, SI), generous for the coarsest sensors
// calibrated here (consumer MEMS: a gyro zero-rate offset of tens of deg/s, an accelerometer offset
// of 150 mg, sensitivity errors of a few percent, cross-axis sensitivity of 2 %), so that only a
// figure no sensor can have is beyond them: a gyro bias of 100 deg/s, an accelerometer bias of
// 1 g, a scale-factor error of 20 % (a scale of -1, i.e. -100 %, is a sensor that reads nothing),
// a misalignment of 10 deg (the table frame's includes the IMU's mounting). The thermal and drift
// terms: the same change over kSpan degrees C or one hour; the extended ones: see each entry.
constexpr double kMaxGyroBias = 100.0 * units::deg_per_s;
constexpr double kMaxAccelBias = units::g0;
constexpr double kMaxScale = 0.2;
constexpr double kMaxMisalignment = 10.0 * units::deg;
constexpr double kSpan = 100.0;  // deg C

// Row and column of the k-th off-diagonal entry in the order xy xz yx yz zx zy.
int off_row(int k) { return k / 2; }
int off_col(int k) {
  const int i = k / 2, j = k % 2;
  return j < i ? j : j + 1;
}

// Thermal terms (models/imu_error_model.hpp), after the others.
void add_thermal_families(std::vector<CoefficientFamily>& t) {
  const std::vector<std::string> kAxes = {"x", "y", "z"};
  const std::vector<std::string> kOffDiagonal = {"xy", "xz", "yx", "yz", "zx", "zy"};
  using namespace units;
  using F = CoefficientFamily;
  using O = FamilyOutput;
  // Bias and scale factor polynomials in T - T0 of
  // degree 1 to 3 (terms thermal, thermal2, thermal3), misalignment linear in T - T0, and the gyro
  // bias in the rate of change of temperature (term thermal).
  const std::string chamber =
      "soaks at several temperatures, or a chamber ramp, with a temperature column in the log";
  const char* const power[3] = {"C", "C^2", "C^3"};
  const char* const degree_name[3] = {"linear", "quadratic", "cubic"};
  const char* const terms[3] = {"thermal", "thermal2", "thermal3"};
  const double bias_prior[2][3] = {{0.1 * deg_per_h, 0.01 * deg_per_h, 0.001 * deg_per_h},
                                   {50 * ug, 1 * ug, 0.05 * ug}};
  const double scale_prior[3] = {20 * ppm, 1 * ppm, 0.05 * ppm};
  for (int d = 0; d < 3; ++d) {
    const std::string n = std::to_string(d + 1), per = power[d];
    const std::string degree = degree_name[d];
    using Value = double& (*)(ImuErrorModel&, int);
    static const Value gyro_bias[3] = {
        [](ImuErrorModel& m, int k) -> double& { return m.gyro.bias_temp(k, 0); },
        [](ImuErrorModel& m, int k) -> double& { return m.gyro.bias_temp(k, 1); },
        [](ImuErrorModel& m, int k) -> double& { return m.gyro.bias_temp(k, 2); }};
    static const Value accel_bias[3] = {
        [](ImuErrorModel& m, int k) -> double& { return m.accel.bias_temp(k, 0); },
        [](ImuErrorModel& m, int k) -> double& { return m.accel.bias_temp(k, 1); },
        [](ImuErrorModel& m, int k) -> double& { return m.accel.bias_temp(k, 2); }};
    static const Value gyro_scale[3] = {
        [](ImuErrorModel& m, int k) -> double& { return m.gyro.scale_temp(k, 0); },
        [](ImuErrorModel& m, int k) -> double& { return m.gyro.scale_temp(k, 1); },
        [](ImuErrorModel& m, int k) -> double& { return m.gyro.scale_temp(k, 2); }};
    static const Value accel_scale[3] = {
        [](ImuErrorModel& m, int k) -> double& { return m.accel.scale_temp(k, 0); },
        [](ImuErrorModel& m, int k) -> double& { return m.accel.scale_temp(k, 1); },
        [](ImuErrorModel& m, int k) -> double& { return m.accel.scale_temp(k, 2); }};
    t.push_back(F{"gyro.bias_temp" + n,
                  "gyro.bias_temp" + n,
                  kAxes,
                  {{"deg/h/" + per, deg_per_h}, {"deg/s/" + per, deg_per_s}, {"rad/s/" + per, 1.0}},
                  O::Gyro,
                  false,
                  terms[d],
                  bias_prior[0][d],
                  false,
                  "gyro bias, " + degree + " in the temperature",
                  gyro_bias[d],
                  chamber,
                  kMaxGyroBias / std::pow(kSpan, d + 1)});
    t.push_back(F{"accel.bias_temp" + n,
                  "accel.bias_temp" + n,
                  kAxes,
                  {{"ug/" + per, ug}, {"mg/" + per, mg}, {"m/s^2/" + per, 1.0}},
                  O::Accel,
                  false,
                  terms[d],
                  bias_prior[1][d],
                  false,
                  "accelerometer bias, " + degree + " in the temperature",
                  accel_bias[d],
                  chamber,
                  kMaxAccelBias / std::pow(kSpan, d + 1)});
    t.push_back(F{"gyro.scale_temp" + n,
                  "gyro.scale_temp" + n,
                  kAxes,
                  {{"ppm/" + per, ppm}, {"1/" + per, 1.0}},
                  O::Gyro,
                  false,
                  terms[d],
                  scale_prior[d],
                  false,
                  "gyro scale factor, " + degree + " in the temperature",
                  gyro_scale[d],
                  chamber,
                  kMaxScale / std::pow(kSpan, d + 1)});
    t.push_back(F{"accel.scale_temp" + n,
                  "accel.scale_temp" + n,
                  kAxes,
                  {{"ppm/" + per, ppm}, {"1/" + per, 1.0}},
                  O::Accel,
                  false,
                  terms[d],
                  scale_prior[d],
                  false,
                  "accelerometer scale factor, " + degree + " in the temperature",
                  accel_scale[d],
                  chamber,
                  kMaxScale / std::pow(kSpan, d + 1)});
    if (d > 0) continue;
    const std::vector<UnitToken> angle_per_c = {{"arcsec/C", arcsec}, {"rad/C", 1.0}};
    t.push_back(F{"gyro.misalignment_temp1", "gyro.misalignment_temp1", kOffDiagonal, angle_per_c,
                  O::Gyro, false, terms[0], 1 * arcsec, false,
                  "gyro misalignment, linear in the temperature",
                  [](ImuErrorModel& m, int k) -> double& {
                    return m.gyro.misalignment_temp(off_row(k), off_col(k));
                  },
                  chamber, kMaxMisalignment / kSpan});
    t.push_back(F{"accel.misalignment_temp1", "accel.misalignment_temp1", kOffDiagonal, angle_per_c,
                  O::Accel, false, terms[0], 1 * arcsec, false,
                  "accelerometer misalignment, linear in the temperature",
                  [](ImuErrorModel& m, int k) -> double& {
                    return m.accel.misalignment_temp(off_row(k), off_col(k));
                  },
                  chamber, kMaxMisalignment / kSpan});
    t.push_back(F{"gyro.bias_temp_rate",
                  "gyro.bias_temp_rate",
                  kAxes,
                  {{"deg/h/(C/min)", deg_per_h * 60.0}, {"rad/s/(C/s)", 1.0}},
                  O::Gyro,
                  false,
                  terms[0],
                  1 * deg_per_h * 60.0,
                  false,
                  "gyro bias in the rate of change of temperature",
                  [](ImuErrorModel& m, int k) -> double& { return m.gyro.bias_temp_rate(k); },
                  "a chamber ramp (the temperature changing while the plan runs)",
                  kMaxGyroBias / (1.0 / 60.0)});
  }
}

std::vector<CoefficientFamily> make_families() {
  // Local, not namespace-scope: the table may be built during another file's static
  // initialization.
  const std::vector<std::string> kAxes = {"x", "y", "z"};
  const std::vector<std::string> kOffDiagonal = {"xy", "xz", "yx", "yz", "zx", "zy"};
  const std::vector<std::string> kMatrix = {"xx", "xy", "xz", "yx", "yy", "yz", "zx", "zy", "zz"};
  const std::vector<std::string> kArms = {"x.x", "x.y", "x.z", "y.x", "y.y",
                                          "y.z", "z.x", "z.y", "z.z"};
  using namespace units;
  using F = CoefficientFamily;
  using O = FamilyOutput;
  const std::vector<UnitToken> rate = {{"deg/h", deg_per_h}, {"deg/s", deg_per_s}, {"rad/s", 1.0}};
  const std::vector<UnitToken> accel = {{"ug", ug}, {"mg", mg}, {"g", g0}, {"m/s^2", 1.0}};
  const std::vector<UnitToken> ratio = {{"ppm", ppm}, {"1", 1.0}};
  const std::vector<UnitToken> angle = {
      {"arcsec", arcsec}, {"arcmin", arcmin}, {"deg", deg}, {"mrad", mrad}, {"rad", 1.0}};
  std::vector<F> t;
  // Base: bias, scale factor and misalignment of each triad.
  t.push_back(F{"gyro.bias", "gyro.bias", kAxes, rate, O::Gyro, true, "", 1.0 * deg_per_h, true,
                "gyro bias", [](ImuErrorModel& m, int k) -> double& { return m.gyro.bias(k); }, "",
                kMaxGyroBias});
  t.push_back(F{"gyro.scale", "gyro.scale", kAxes, ratio, O::Gyro, true, "", 300 * ppm, false,
                "gyro scale-factor error",
                [](ImuErrorModel& m, int k) -> double& { return m.gyro.scale(k); }, "", kMaxScale});
  t.push_back(F{"gyro.misalignment", "gyro.misalignment", kOffDiagonal, angle, O::Gyro, true, "",
                300 * arcsec, false, "gyro misalignment (axis i towards body axis j)",
                [](ImuErrorModel& m, int k) -> double& {
                  return m.gyro.misalignment(off_row(k), off_col(k));
                },
                "", kMaxMisalignment});
  t.push_back(F{"accel.bias", "accel.bias", kAxes, accel, O::Accel, true, "", 1000 * ug, true,
                "accelerometer bias",
                [](ImuErrorModel& m, int k) -> double& { return m.accel.bias(k); }, "",
                kMaxAccelBias});
  t.push_back(F{"accel.scale", "accel.scale", kAxes, ratio, O::Accel, true, "", 300 * ppm, false,
                "accelerometer scale-factor error",
                [](ImuErrorModel& m, int k) -> double& { return m.accel.scale(k); }, "",
                kMaxScale});
  t.push_back(F{"accel.misalignment", "accel.misalignment", kOffDiagonal, angle, O::Accel, true, "",
                300 * arcsec, false, "accelerometer misalignment (axis i towards body axis j)",
                [](ImuErrorModel& m, int k) -> double& {
                  return m.accel.misalignment(off_row(k), off_col(k));
                },
                "", kMaxMisalignment});
  // Extended terms.
  t.push_back(F{"accel.k2",
                "accel.k2",
                kAxes,
                {{"ug/g^2", ug_per_g2}, {"1/(m/s^2)", 1.0}},
                O::Accel,
                false,
                "k2",
                100 * ug_per_g2,
                false,
                "accelerometer quadratic scale factor",
                [](ImuErrorModel& m, int k) -> double& { return m.accel.k2(k); },
                "each axis horizontal and at two or more specific-force levels (e.g. along gravity "
                "and at 45 deg): one level makes K2 look like the scale asymmetry",
                1e5 * ug_per_g2});  // 0.1 per g: 10 % at 1 g
  t.push_back(F{"gyro.scale_asym", "gyro.scale_asym", kAxes, ratio, O::Gyro, false, "scale_asym",
                300 * ppm, false, "gyro scale-factor asymmetry",
                [](ImuErrorModel& m, int k) -> double& { return m.gyro.scale_asym(k); },
                "each gyro axis turned both ways at a known rate (a rotation plan)", kMaxScale});
  t.push_back(F{"accel.scale_asym", "accel.scale_asym", kAxes, ratio, O::Accel, false, "scale_asym",
                300 * ppm, false, "accelerometer scale-factor asymmetry",
                [](ImuErrorModel& m, int k) -> double& { return m.accel.scale_asym(k); },
                "each accelerometer axis both up and down, at two or more specific-force levels "
                "(to tell it from K2)",
                kMaxScale});
  t.push_back(
      F{"gyro.g_sensitivity",
        "gyro.g_sensitivity",
        kMatrix,
        {{"deg/h/g", deg_per_h_per_g}, {"deg/s/g", deg_per_s / g0}, {"rad/s/(m/s^2)", 1.0}},
        O::Gyro,
        false,
        "g_sensitivity",
        0.1 * deg_per_h_per_g,
        false,
        "gyro g-sensitivity (gyro axis i, specific force along j)",
        [](ImuErrorModel& m, int k) -> double& { return m.gyro_g_sensitivity(k / 3, k % 3); },
        "orientations with gravity along each axis (static), or turns",
        1.0 * deg_per_s / g0});  // MEMS: 0.1 deg/s/g
  t.push_back(
      F{"accel.lever_arm",
        "accel.lever_arm",
        kArms,
        {{"mm", mm}, {"cm", cm}, {"m", 1.0}},
        O::Accel,
        false,
        "lever_arm",
        0.1,
        false,
        "inner lever arm (accelerometer i's proof mass, component j)",
        [](ImuErrorModel& m, int k) -> double& { return m.accel_lever_arm_b(k % 3, k / 3); },
        "turns with rate and angular acceleration (a rotation plan)",
        1.0});  // m: a proof mass a metre from the reference point is not in the IMU
  t.push_back(F{"time_delay",
                "timing.time_delay",
                {},
                {{"ms", ms}, {"us", us}, {"s", 1.0}, {"min", 60.0}, {"h", hour}},
                O::Delay,
                false,
                "time_delay",
                0.01,
                false,
                "gyro-to-accelerometer time delay (accelerometer late is positive)",
                [](ImuErrorModel& m, int) -> double& { return m.time_delay; },
                "turns (a rotation plan): the delay only acts while the attitude changes",
                1.0});  // s: a second between gyro and accelerometer samples
  t.push_back(F{"gyro.bias_drift",
                "gyro.bias_drift",
                kAxes,
                {{"deg/h/h", deg_per_h / hour}, {"deg/s/h", deg_per_s / hour}, {"rad/s^2", 1.0}},
                O::Gyro,
                false,
                "bias_drift",
                1.0 * deg_per_h / hour,
                false,
                "gyro bias drift (linear in the time since the start of the plan)",
                [](ImuErrorModel& m, int k) -> double& { return m.gyro.bias_drift(k); },
                "orientations revisited later in the session",
                kMaxGyroBias / hour});
  t.push_back(F{"accel.bias_drift",
                "accel.bias_drift",
                kAxes,
                {{"ug/h", ug / hour}, {"mg/h", mg / hour}, {"m/s^3", 1.0}},
                O::Accel,
                false,
                "bias_drift",
                1000 * ug / hour,
                false,
                "accelerometer bias drift (linear in the time since the start of the plan)",
                [](ImuErrorModel& m, int k) -> double& { return m.accel.bias_drift(k); },
                "orientations revisited later in the session",
                kMaxAccelBias / hour});
  add_thermal_families(t);
  return t;
}

}  // namespace

std::string CoefficientFamily::coefficient_name(int k) const {
  return components.empty() ? name : name + "." + components[static_cast<std::size_t>(k)];
}

const std::vector<CoefficientFamily>& coefficient_families() {
  static const std::vector<CoefficientFamily> table = make_families();
  return table;
}

const CoefficientFamily& coefficient_family_info(const std::string& family) {
  std::string known;
  for (const auto& f : coefficient_families()) {
    if (f.name == family) return f;
    known += (known.empty() ? "" : ", ") + f.name;
  }
  throw std::invalid_argument("unknown coefficient family '" + family + "' (known: " + known + ")");
}

std::string coefficient_family(const std::string& coefficient) {
  for (const auto& f : coefficient_families()) {
    if (coefficient == f.name && f.components.empty()) return f.name;
    if (coefficient.size() > f.name.size() + 1 &&
        coefficient.compare(0, f.name.size(), f.name) == 0 && coefficient[f.name.size()] == '.')
      return f.name;
  }
  throw std::invalid_argument("unknown coefficient '" + coefficient + "'");
}

std::vector<std::pair<std::string, std::vector<std::string>>> extended_terms() {
  std::vector<std::pair<std::string, std::vector<std::string>>> out;
  for (const auto& f : coefficient_families()) {
    if (f.base) continue;
    auto it = out.begin();
    while (it != out.end() && it->first != f.term) ++it;
    if (it == out.end()) {
      out.emplace_back(f.term, std::vector<std::string>{});
      it = out.end() - 1;
    }
    it->second.push_back(f.name);
  }
  return out;
}

std::string extended_terms_help() {
  std::string out;
  for (const auto& [term, families] : extended_terms()) {
    out += (out.empty() ? "" : "; ") + term + " (";
    for (std::size_t i = 0; i < families.size(); ++i)
      out += (i ? ", " : "") + coefficient_family_info(families[i]).help;
    out += ")";
  }
  return out;
}

}  // namespace sinscal
