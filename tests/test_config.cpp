// The INI layer (models/config.hpp): syntax errors with file and line, comments, whole numbers
// and quantities checked for range, and files with many sections.
#include <catch2/catch.hpp>
#include <climits>
#include <cmath>
#include <filesystem>
#include <string>

#include "helpers.hpp"
#include "models/config.hpp"
#include "models/units.hpp"
#include "rig/plan.hpp"

using namespace sinscal;

namespace {

// The message of the ConfigError that parsing `text` as "t.ini" throws ("no error" if none).
std::string parse_error(const std::string& text) {
  try {
    IniFile ini("t.ini", text);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

// The message of the ConfigError that `get` throws on a file holding `text`.
template <typename Get>
std::string get_error(const std::string& text, Get get) {
  const IniFile ini("t.ini", text);
  try {
    get(ini);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

const std::string kPlanHead =
    "[plan]\ntype = orientations\nconvention = paper\nmove_rate = 15 deg/s\n"
    "move_acceleration = 15 deg/s^2\n";

std::string orientations(int count) {
  // The paper's eight orientations, over and over: every one reachable by the default table.
  static const char* const angles[8] = {"0 0 45",  "90 45 0",   "180 0 315", "270 315 0",
                                        "0 0 225", "90 45 180", "180 0 135", "90 225 0"};
  std::string text;
  for (int i = 1; i <= count; ++i) {
    std::istringstream in(angles[(i - 1) % 8]);
    std::string h, p, r;
    in >> h >> p >> r;
    text += "[orientation." + std::to_string(i) + "]\nheading = " + h + " deg\npitch = " + p +
            " deg\nroll = " + r + " deg\ndwell = 2 s\n";
  }
  return text;
}

}  // namespace

TEST_CASE("INI: a line with a formatter placeholder is a plain error, no hang", "[config]") {
  // Boost.Program_options looped forever formatting the message of this line.
  CHECK_THAT(parse_error("[plan]\n%invalid_line%\n"),
             Catch::Contains("t.ini:2") && Catch::Contains("%invalid_line%"));
  CHECK_THAT(parse_error("[a]\nx = 1\n%invalid_line% %canonical_option% %1%\n"),
             Catch::Contains("t.ini:3") && Catch::Contains("%canonical_option%"));
  // Through the plan loader too.
  try {
    Plan::parse("p.ini", kPlanHead + "%invalid_line%\n");
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK_THAT(e.what(), Catch::Contains("p.ini:6") && Catch::Contains("%invalid_line%"));
  }
}

TEST_CASE("INI: every syntax error names file, line and cause", "[config]") {
  CHECK_THAT(parse_error("[a]\nx = 1\njust words\n"), Catch::Contains("t.ini:3") &&
                                                          Catch::Contains("'key = value'") &&
                                                          Catch::Contains("just words"));
  CHECK_THAT(parse_error("# a comment\n\n[a\nx = 1\n"),
             Catch::Contains("t.ini:3") && Catch::Contains("closing ']'"));
  CHECK_THAT(parse_error("[a]\nx = 1\n[ ]\ny = 2\n"),
             Catch::Contains("t.ini:3") && Catch::Contains("empty section name"));
  CHECK_THAT(parse_error("[a]\n[b]]\n"),
             Catch::Contains("t.ini:2") && Catch::Contains("section name"));
  CHECK_THAT(parse_error("x = 1\n[a]\n"),
             Catch::Contains("t.ini:1") && Catch::Contains("before the first [section]"));
  CHECK_THAT(parse_error("[a]\n = 1\n"),
             Catch::Contains("t.ini:2") && Catch::Contains("without a key"));
  CHECK_THAT(parse_error("[a]\nx = 1\n\n[b]\nx = 2\n[a]\nx = 3\n"),
             Catch::Contains("t.ini:7") && Catch::Contains("'x' in [a] is given twice") &&
                 Catch::Contains("first at line 2"));
  // Line numbers count every line (blank, comment, CRLF), the last without a newline too.
  CHECK_THAT(parse_error("[a]\r\n# c\r\n\r\nx = 1\r\nbad"), Catch::Contains("t.ini:5"));
  // Long and control-character text is shortened in the message.
  const std::string message = parse_error("[a]\n" + std::string(500, 'z') + "\x01\n");
  CHECK_THAT(message, Catch::Contains("t.ini:2") && Catch::Contains("...'"));
  CHECK(message.size() < 200);
  CHECK(message.find('\x01') == std::string::npos);
}

TEST_CASE("INI: comments, spaces and values as before", "[config]") {
  const IniFile ini("t.ini",
                    "\xEF\xBB\xBF# heading comment\n"
                    "[ plan ]   # a section with a comment\n"
                    "name = seed8   # a value with a comment\n"
                    "description = a = b, c\t \n"
                    "empty =\n"
                    "\t  spaced   key   =   v  \r\n"
                    "hash = before#after\n"
                    "[targets]\n"
                    "gyro.bias = 0.1 deg/h\n"
                    "[plan]\n"
                    "type = orientations\n");
  CHECK(ini.get_string("plan.name") == "seed8");
  CHECK(ini.get_string("plan.description") == "a = b, c");
  CHECK(ini.get_string("plan.empty") == "");
  CHECK(ini.get_string("plan.spaced   key") == "v");
  CHECK(ini.get_string("plan.hash") == "before");  // '#' always starts a comment
  CHECK(ini.get_string("plan.type") == "orientations");
  CHECK(ini.has("targets.gyro.bias"));
  CHECK(ini.line_of("targets.gyro.bias") == 9);
  CHECK(ini.line_of("plan.type") == 11);
  CHECK(ini.line_of("plan.nothing") == 0);
  CHECK(ini.keys() == std::vector<std::string>{"plan.name", "plan.description", "plan.empty",
                                               "plan.spaced   key", "plan.hash",
                                               "targets.gyro.bias", "plan.type"});
  CHECK(ini.sections() == std::vector<std::string>{"plan", "targets"});
  CHECK(ini.has_section("targets"));
  CHECK_FALSE(ini.has_section("gyro"));
  CHECK(ini.where("plan.type") == "t.ini:11: 'plan.type': ");
  // An empty file, or only comments, has no keys.
  CHECK(IniFile("e.ini", "").keys().empty());
  CHECK(IniFile("e.ini", "# only\n\n   # comments\n").keys().empty());
}

TEST_CASE("INI: the bundled configs read as with Boost.Program_options", "[config]") {
  const IniFile seed8(test::source_path("config/plans/seed8.ini"));
  CHECK(seed8.get_string("plan.description") == "paper 8-orientation plan, 180 s static dwells");
  CHECK(seed8.sections_with_prefix("orientation.").size() == 8);
  CHECK(seed8.get_quantity("orientation.8.pitch", QuantityKind::Angle, "deg") ==
        Approx(225 * units::deg));
  int files = 0;
  for (const char* dir : {"config/plans", "config/sensors"})
    for (const auto& f : std::filesystem::directory_iterator(test::source_path(dir))) {
      CAPTURE(f.path().string());
      const IniFile ini(f.path().string());
      CHECK_FALSE(ini.keys().empty());
      for (const auto& key : ini.keys()) {
        CHECK(ini.line_of(key) > 0);
        // No value of a bundled file holds a comment or surrounding space.
        const std::string v = ini.get_string(key);
        CHECK(v.find('#') == std::string::npos);
        CHECK((v.empty() || (v.front() != ' ' && v.back() != ' ')));
      }
      ++files;
    }
  CHECK(files >= 5);
}

TEST_CASE("INI: missing keys and unknown keys name file, line and section", "[config]") {
  const std::string text = "[a]\nx = 1\n[b.c]\ny = 2\n[d]\nsub.key = 3\n";
  CHECK_THAT(
      get_error(text, [](const IniFile& i) { i.get_string("b.c.z"); }),
      Catch::Contains("t.ini:3") && Catch::Contains("[b.c]") && Catch::Contains("missing key 'z'"));
  CHECK_THAT(
      get_error(text, [](const IniFile& i) { i.get_string("e.z"); }),
      Catch::Contains("t.ini") && Catch::Contains("'e.z'") && Catch::Contains("no [e] section"));
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.check_keys("a", {"w"}); }),
             Catch::Contains("t.ini:2") && Catch::Contains("unknown key in [a]") &&
                 Catch::Contains("known: w"));
  // A key with dots belongs to its section (it was missed before).
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.check_keys("d", {"sub"}); }),
             Catch::Contains("t.ini:6") && Catch::Contains("'d.sub.key'"));
  CHECK(get_error(text, [](const IniFile& i) {
          i.check_keys("a", {"x"});
          i.check_keys("b.c", {"y", "q"});
          i.check_keys("d", {"sub.key"});
          i.check_keys("absent", {});
        }) == "no error");
}

TEST_CASE("INI: whole numbers are range-checked before conversion", "[config]") {
  const std::string text =
      "[log]\nbig = 1e10\nneg = -1\nfrac = 2.5\nmax = 2147483647\nover = 2147483648\n"
      "min = -2147483648\nunder = -2147483649\nexp = 1e3\ninf = inf\nword = three\n"
      "three = 3.0\n";
  const IniFile ini("t.ini", text);
  CHECK(ini.get_int("log.max", 0) == INT_MAX);
  CHECK(ini.get_int("log.min", 0) == INT_MIN);
  CHECK(ini.get_int("log.exp", 0) == 1000);
  CHECK(ini.get_int("log.three", 0, 0, 10) == 3);
  CHECK(ini.get_int("log.neg", 0) == -1);
  CHECK(ini.get_int("log.absent", 7, 0, 5) == 7);
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.get_int("log.big", 0); }),
             Catch::Contains("t.ini:2") && Catch::Contains("'log.big'") &&
                 Catch::Contains("out of range"));
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.get_int("log.neg", 0, 0, INT_MAX); }),
             Catch::Contains("t.ini:3") && Catch::Contains("at least 0"));
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.get_int("log.exp", 0, INT_MIN, 999); }),
             Catch::Contains("t.ini:9") && Catch::Contains("at most 999"));
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.get_int("log.frac", 0, 0, 10); }),
             Catch::Contains("t.ini:4") && Catch::Contains("whole number"));
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.get_int("log.over", 0); }),
             Catch::Contains("t.ini:6") && Catch::Contains("out of range"));
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.get_int("log.under", 0); }),
             Catch::Contains("t.ini:8") && Catch::Contains("out of range"));
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.get_int("log.inf", 0); }),
             Catch::Contains("t.ini:10") && Catch::Contains("not a finite number"));
  CHECK_THAT(get_error(text, [](const IniFile& i) { i.get_int("log.word", 0); }),
             Catch::Contains("t.ini:11") && Catch::Contains("'three'"));
  CHECK_THROWS_AS(ini.get_int("log.max", 0, 1, 0), std::invalid_argument);
}

TEST_CASE("INI: quantities must be finite, as written and in SI", "[config]") {
  const std::string text =
      "[s]\ninf = inf\nnan = nan deg\nhuge = 1e999\nhuge_unit = 1e999 deg\nover = 1e308 g\n"
      "neg_inf = 1 -inf\nok = 1e300 ug\nunit = 5 deg/h\n";
  const IniFile ini("t.ini", text);
  CHECK(ini.get_quantity("s.ok", QuantityKind::Acceleration, "m/s^2") == Approx(1e300 * units::ug));
  CHECK(ini.get_quantity("s.unit", QuantityKind::AngularRate, "rad/s") ==
        Approx(5 * units::deg_per_h));
  auto quantity_error = [&](const std::string& key, QuantityKind kind, const std::string& unit) {
    return get_error(text, [&](const IniFile& i) { i.get_quantities("s." + key, kind, unit); });
  };
  CHECK_THAT(quantity_error("inf", QuantityKind::Angle, "deg"),
             Catch::Contains("t.ini:2") && Catch::Contains("'inf' is not a finite number"));
  CHECK_THAT(quantity_error("nan", QuantityKind::Angle, "deg"),
             Catch::Contains("t.ini:3") && Catch::Contains("'nan' is not a finite number"));
  CHECK_THAT(quantity_error("huge", QuantityKind::Angle, "deg"),
             Catch::Contains("t.ini:4") && Catch::Contains("'1e999' is not a finite number"));
  CHECK_THAT(quantity_error("huge_unit", QuantityKind::Angle, "deg"),
             Catch::Contains("t.ini:5") && Catch::Contains("'1e999' is not a finite number"));
  CHECK_THAT(quantity_error("over", QuantityKind::Acceleration, "m/s^2"),
             Catch::Contains("t.ini:6") && Catch::Contains("out of range"));
  CHECK_THAT(quantity_error("neg_inf", QuantityKind::Angle, "deg"),
             Catch::Contains("t.ini:7") && Catch::Contains("'-inf' is not a finite number"));
  CHECK_THAT(
      get_error(text,
                [](const IniFile& i) { i.get_quantity("s.inf", QuantityKind::Angle, "deg", 1.0); }),
      Catch::Contains("t.ini:2"));
  // The parser itself, without a file.
  CHECK_THROWS_WITH(parse_quantities("1 nan", QuantityKind::Angle, "deg"),
                    Catch::Contains("'nan' is not a finite number"));
  CHECK_THROWS_WITH(parse_quantities("2 x3", QuantityKind::Angle, "deg"),
                    Catch::Contains("unit 'x3'"));
  CHECK_THROWS_WITH(parse_quantities("x3 deg", QuantityKind::Angle, "deg"),
                    Catch::Contains("'x3' is not a number"));
  CHECK(parse_quantities("1 2 3", QuantityKind::Ratio, "ppm").size() == 3);
}

TEST_CASE("INI: 8,000 sections load, in order, every key checked", "[config]") {
  // Key checking and lookups were O(sections x keys); this file took minutes with them. Timing
  // figures are in the change's report, not here: the test checks what is loaded.
  const int n = 8000;
  const std::string text = kPlanHead + orientations(n) + "[orientation.8001]\nheading = 0\n";
  const IniFile ini("big.ini", text);
  const auto sections = ini.sections_with_prefix("orientation.");
  REQUIRE(sections.size() == static_cast<std::size_t>(n) + 1);
  CHECK(sections.front() == "orientation.1");
  CHECK(sections[4999] == "orientation.5000");
  for (std::size_t i = 0; i + 1 < sections.size(); ++i)
    ini.check_keys(sections[i], {"heading", "pitch", "roll", "dwell"});
  CHECK(ini.keys().size() == 4u + 4u * n + 1u);
  const std::size_t last = 5 + 5 * static_cast<std::size_t>(n) + 2;
  CHECK(ini.line_of("orientation.8001.heading") == last);
  CHECK_THROWS_WITH(ini.check_keys("orientation.8001", {"pitch"}),
                    Catch::Contains("big.ini:" + std::to_string(last)));

  const Plan plan = Plan::parse("big.ini", kPlanHead + orientations(n));
  REQUIRE(plan.orientations.size() == static_cast<std::size_t>(n));
  CHECK(plan.orientations.back().label == "8000");
  CHECK(plan.orientations.back().angles.pitch == Approx(225 * units::deg));
}
