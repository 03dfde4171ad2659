// The calibration certificate (report/certificate.hpp): the page's escaping, every coefficient
// with its value, sigma and unit, what a result without provenance says, the hashes and the
// encodings it relies on, and bad input named with file and cause.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "helpers.hpp"
#include "report/certificate.hpp"
#include "report/coefficient_table.hpp"
#include "report/provenance.hpp"
#include "report/sha256.hpp"

using namespace sinscal;

namespace {
std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}
}  // namespace

TEST_CASE("Certificate: SHA-256 and base64 of the reference vectors", "[certificate]") {
  CHECK(sha256_hex("") == "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  CHECK(sha256_hex("abc") == "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  CHECK(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq") ==
        "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  const std::string million(1000000, 'a');  // crosses many 64 KiB reads of sha256_file
  const std::string dir = test::temp_dir("certificate_sha");
  std::ofstream(dir + "/a.bin", std::ios::binary) << million;
  std::uintmax_t bytes = 0;
  CHECK(sha256_file(dir + "/a.bin", &bytes) ==
        "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  CHECK(bytes == 1000000);
  CHECK_THROWS_WITH(sha256_file(dir + "/none.bin"), Catch::Contains("none.bin: cannot open"));
  CHECK(base64("").empty());
  CHECK(base64("f") == "Zg==");
  CHECK(base64("fo") == "Zm8=");
  CHECK(base64("foo") == "Zm9v");
  CHECK(base64("foobar") == "Zm9vYmFy");
  CHECK(base64(std::string("\xff\x00\x80", 3)) == "/wCA");
  CHECK(shell_command_line({"sinscal", "report", "--out", "a b.html", "it's"}) ==
        "sinscal report --out 'a b.html' 'it'\\''s'");
}

TEST_CASE("Certificate: HTML special characters in names are escaped", "[certificate]") {
  CHECK(html_escaped("<b>&\"x'") == "&lt;b&gt;&amp;&quot;x&#39;");
  Certificate c;
  c.unit_name = "FOG <unit> & \"A\"";
  c.identity = {{"Session", "<script>alert(1)</script>"}};
  c.files.push_back({"log", "dir/<imu>.csv", std::string(64, 'a'), 10, "unchanged"});
  c.verdict_title = "Converged";
  c.verdict_reasons = {"a < b"};
  CertificateSection s;
  s.title = "R&D";
  s.table = {{"a<b"}, {{"x>y"}}};
  c.sections.push_back(s);
  c.coefficients["gyro.bias.x"] = {0.5, 0.01, "deg/h", true, false};
  const std::string html = certificate_html(c);
  CHECK(html.find("<script>") == std::string::npos);
  CHECK(html.find("&lt;script&gt;alert(1)&lt;/script&gt;") != std::string::npos);
  CHECK(html.find("FOG &lt;unit&gt; &amp; &quot;A&quot;") != std::string::npos);
  CHECK(html.find("dir/&lt;imu&gt;.csv") != std::string::npos);
  CHECK(html.find("R&amp;D") != std::string::npos);
  CHECK(html.find("a &lt; b") != std::string::npos);
  CHECK(html.find("x&gt;y") != std::string::npos);
  // Self-contained: no script, nothing fetched.
  CHECK(html.find("<script") == std::string::npos);
  CHECK(html.find("http://") == std::string::npos);
  CHECK(html.find("https://") == std::string::npos);
  CHECK(html.find("@media print") != std::string::npos);
  CHECK(html.find("size: A4") != std::string::npos);
}

TEST_CASE("Certificate: every coefficient of a result with its value, sigma and unit",
          "[certificate]") {
  const std::string path = test::source_path("tests/golden/seed8-closed-form.json");
  CertificateOptions o;
  o.result_path = path;
  const Certificate c = read_certificate(o);
  const ResultCoefficients want = read_result_json(path);
  REQUIRE(c.coefficients.size() == want.size());
  const std::string html = certificate_html(c);
  for (const CoefficientRow& r : coefficient_rows(want)) {
    INFO(r.name);
    const std::string row = "<tr><td>" + r.name + "</td>";
    REQUIRE(count(html, row) == 1);
    const std::string tail = html.substr(html.find(row), 400);
    if (r.kind == CoefficientRow::Kind::Estimated) {
      CHECK(tail.find(">" + r.value + "<") != std::string::npos);
      CHECK(tail.find("<td class=\"num sigma\">" + r.sigma + "<") != std::string::npos);
    } else {
      CHECK(tail.find(r.value) != std::string::npos);
    }
    CHECK(tail.find("<td>" + html_escaped(r.unit) + "</td></tr>") != std::string::npos);
  }
  for (const char* unit : {"deg/h", "ug", "ppm", "arcsec"})
    CHECK(html.find("<td>" + std::string(unit) + "</td>") != std::string::npos);
  // Written before results recorded their inputs: said so, no hash invented.
  CHECK(c.files.empty());
  CHECK_THAT(c.files_note, Catch::Contains("not available"));
  CHECK(html.find("not recorded") != std::string::npos);
  // The closed form's per-dwell residuals are on the page.
  bool dwells = false;
  for (const auto& s : c.sections) dwells |= s.title.find("per dwell") != std::string::npos;
  CHECK(dwells);
}

TEST_CASE("Certificate: bad input is named with the file and the cause", "[certificate]") {
  const std::string dir = test::temp_dir("certificate_bad");
  CertificateOptions o;
  o.result_path = dir + "/none.json";
  CHECK_THROWS_WITH(read_certificate(o), Catch::Contains("none.json: cannot open"));
  std::ofstream(dir + "/text.json") << "not json";
  o.result_path = dir + "/text.json";
  CHECK_THROWS_WITH(read_certificate(o), Catch::Contains("text.json: not a sinscal result file"));
  std::ofstream(dir + "/truth.json") << R"({"note": "x", "coefficients": {}})";
  o.result_path = dir + "/truth.json";
  CHECK_THROWS_WITH(read_certificate(o), Catch::Contains("truth.json: a truth file"));
  std::ofstream(dir + "/odd.json")
      << R"({"method": {"name": "kf"}, "coefficients": {"gyro.wobble.x": {"value": 1}}})";
  o.result_path = dir + "/odd.json";
  CHECK_THROWS_WITH(read_certificate(o), Catch::Contains("unknown coefficient 'gyro.wobble.x'"));
  o.result_path = test::source_path("tests/golden/seed8-closed-form.json");
  o.diagnosis_dir = dir;
  CHECK_THROWS_WITH(read_certificate(o), Catch::Contains("diagnosis.json: cannot open"));
  std::ofstream(dir + "/diagnosis.json") << R"({"session": "s"})";
  CHECK_THROWS_WITH(read_certificate(o), Catch::Contains("not a sinscal diagnosis"));
}
