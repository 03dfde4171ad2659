// The one reader of results (report/result.hpp read_result_file): every coefficient against its
// family's physical range (models/coefficient_families.hpp plausible_max), sigmas finite and
// positive, units those results give; the override of --force recorded by export and report.
#include <catch2/catch.hpp>
#include <fstream>

#include "helpers.hpp"
#include "models/coefficient_families.hpp"
#include "models/imu_error_model.hpp"
#include "models/units.hpp"
#include "report/certificate.hpp"
#include "report/firmware_export.hpp"
#include "report/result.hpp"

using namespace sinscal;

namespace {
const std::string kGolden = "tests/golden/seed8-closed-form.json";

nlohmann::json golden() {
  std::ifstream in(test::source_path(kGolden));
  return nlohmann::json::parse(in);
}

std::string write(const std::string& name, const nlohmann::json& j) {
  const std::string path = test::temp_dir("result_read") + "/" + name;
  std::ofstream(path) << j.dump(2);
  return path;
}

ResultCoefficient estimate(double value, std::optional<double> sigma, const std::string& name) {
  ResultCoefficient c;
  c.value = value;
  c.sigma = sigma;
  c.unit = coefficient_info(name).unit;
  return c;
}
}  // namespace

TEST_CASE("Result range: every family has a physical range, above its default prior",
          "[result_read]") {
  for (const auto& f : coefficient_families()) {
    INFO(f.name);
    CHECK(f.plausible_max > 0.0);
    CHECK(f.default_prior < f.plausible_max);  // a prior-sized coefficient is plausible
  }
  // The base ranges in the units results give them: a gyro bias of 100 deg/s, an accelerometer
  // bias of 1 g, a scale-factor error of 20 %, a misalignment of 10 deg.
  CHECK(coefficient_family_info("gyro.bias").plausible_max / units::deg_per_h == Approx(360000.0));
  CHECK(coefficient_family_info("accel.bias").plausible_max / units::ug == Approx(1e6));
  CHECK(coefficient_family_info("gyro.scale").plausible_max / units::ppm == Approx(2e5));
  CHECK(coefficient_family_info("accel.misalignment").plausible_max / units::arcsec ==
        Approx(36000.0));
}

TEST_CASE("Result range: absurd values, sigmas and missing sigmas are named", "[result_read]") {
  // In the result's units (deg/h): the range is 360000 deg/h, not 360000 rad/s.
  CHECK(check_plausible("gyro.bias.x", estimate(0.3, 0.002, "gyro.bias.x"), true).empty());
  CHECK(check_plausible("gyro.bias.x", estimate(3.5e5, 1.0, "gyro.bias.x"), true).empty());
  CHECK_THAT(
      check_plausible("gyro.bias.x", estimate(3.7e5, 1.0, "gyro.bias.x"), true),
      Catch::Contains("beyond the physical range of gyro.bias") && Catch::Contains("360000 deg/h"));
  CHECK_THAT(check_plausible("gyro.bias.x", estimate(1e308, 1.0, "gyro.bias.x"), true),
             Catch::Contains("value 1e+308 deg/h"));
  // A scale factor of -1 (-100 %): the sensor reads nothing. 10 % is a poor MEMS, not absurd.
  CHECK_THAT(check_plausible("accel.scale.y", estimate(-1e6, 10.0, "accel.scale.y"), true),
             Catch::Contains("value -1e+06 ppm"));
  CHECK(check_plausible("accel.scale.y", estimate(-1e5, 10.0, "accel.scale.y"), true).empty());
  CHECK_THAT(
      check_plausible("gyro.misalignment.xy", estimate(1.0, 1e308, "gyro.misalignment.xy"), true),
      Catch::Contains("sigma 1e+308 arcsec"));
  CHECK_THAT(check_plausible("accel.bias.z", estimate(5.0, 0.0, "accel.bias.z"), true),
             Catch::Contains("sigma 0"));
  CHECK_THAT(check_plausible("accel.bias.z", estimate(5.0, std::nullopt, "accel.bias.z"), true),
             Catch::Contains("no sigma"));
  // Truth files have no sigma; coefficients fixed by convention have neither.
  CHECK(
      check_plausible("accel.bias.z", estimate(5.0, std::nullopt, "accel.bias.z"), false).empty());
  ResultCoefficient fixed;
  fixed.fixed_by_convention = true;
  CHECK(check_plausible("accel.misalignment.xy", fixed, true).empty());
  // Thermal: the bias may change by the base range over 100 C, no more.
  CHECK(check_plausible("gyro.bias_temp1.x", estimate(3000.0, 1.0, "gyro.bias_temp1.x"), true)
            .empty());
  CHECK_FALSE(check_plausible("gyro.bias_temp1.x", estimate(4000.0, 1.0, "gyro.bias_temp1.x"), true)
                  .empty());
}

TEST_CASE("Result range: the reader refuses, names the file and coefficient, --force records",
          "[result_read]") {
  const ResultFile good = read_result_file(test::source_path(kGolden));
  CHECK(good.forced.empty());
  CHECK(good.coefficients.size() == 24);

  nlohmann::json j = golden();
  j["coefficients"]["gyro.bias.y"]["value"] = 1e308;
  const std::string huge = write("huge.json", j);
  CHECK_THROWS_WITH(read_result_file(huge),
                    Catch::Contains("huge.json: coefficient 'gyro.bias.y': value 1e+308") &&
                        Catch::Contains("--force"));
  const ResultFile forced = read_result_file(huge, true);
  REQUIRE(forced.forced.size() == 1);
  CHECK_THAT(forced.forced[0], Catch::StartsWith("gyro.bias.y: value 1e+308 deg/h"));
  const FirmwareExport e = read_result_for_export(huge, {true});
  const std::string header = render_export(e, ExportFormat::CHeader);
  CHECK_THAT(header, Catch::Contains("WARNING (--force): implausible coefficient exported as "
                                     "given: gyro.bias.y: value 1e+308"));
  CHECK_THAT(render_export(e, ExportFormat::Json), Catch::Contains("implausible coefficient"));
  CHECK_THROWS_WITH(read_result_for_export(huge), Catch::Contains("gyro.bias.y"));

  // Malformed: refused even with --force.
  j = golden();
  j["coefficients"]["gyro.bias.z"]["unit"] = "rad/s";
  const std::string rad = write("rad.json", j);
  CHECK_THROWS_WITH(read_result_file(rad, true),
                    Catch::Contains("rad.json: coefficient 'gyro.bias.z' is in 'rad/s'") &&
                        Catch::Contains("'deg/h'"));
  j = golden();
  j["coefficients"]["gyro.bais.x"] = j["coefficients"]["gyro.bias.x"];
  CHECK_THROWS_WITH(read_result_file(write("typo.json", j), true),
                    Catch::Contains("unknown coefficient 'gyro.bais.x'"));
  j = golden();
  j["coefficients"]["accel.bias.x"]["sigma"] = -1.0;
  CHECK_THROWS_WITH(read_result_file(write("negative.json", j), true),
                    Catch::Contains("'accel.bias.x': a sigma must be a finite number > 0"));

  // An estimate without a sigma: refused in a result, accepted in a truth file.
  j = golden();
  j["coefficients"]["accel.scale.x"].erase("sigma");
  CHECK_THROWS_WITH(read_result_file(write("nosigma.json", j)),
                    Catch::Contains("'accel.scale.x': no sigma"));
  j.erase("method");
  j["note"] = "simulate";
  CHECK(read_result_file(write("truth.json", j)).forced.empty());
}

TEST_CASE("Certificate: the expanded uncertainty U = k sigma beside every value",
          "[result_read][certificate]") {
  CertificateOptions o;
  o.result_path = test::source_path(kGolden);
  for (const double k : {2.0, 3.0}) {
    o.coverage_factor = k;
    const Certificate c = read_certificate(o);
    const std::string html = certificate_html(c);
    CHECK_THAT(html, Catch::Contains(k == 2.0 ? "U (k = 2)" : "U (k = 3)"));
    int rows = 0;
    for (const auto& [name, r] : c.coefficients) {
      if (!r.sigma || !r.observable) continue;
      INFO(name);
      char u[64];
      std::snprintf(u, sizeof u, "<td class=\"num u\">± %.4f</td>", k * *r.sigma);
      const auto row = html.find("<tr><td>" + name + "</td>");
      REQUIRE(row != std::string::npos);
      CHECK(html.substr(row, 300).find(u) != std::string::npos);
      ++rows;
    }
    CHECK(rows == 24);
  }
  o.coverage_factor = 0.5;
  CHECK_THROWS_WITH(read_certificate(o), Catch::Contains("coverage factor"));
}
