// Outputs that never replace an input (report/output.hpp), resolved through links; the real cause
// of a file that cannot be written; earlier outputs recognised file by file; the same data given
// twice (report/duplicates.hpp); the thermal table's bound (report/thermal_output.hpp).
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "helpers.hpp"
#include "report/duplicates.hpp"
#include "report/output.hpp"
#include "report/thermal_output.hpp"

using namespace sinscal;
namespace fs = std::filesystem;
using Catch::Contains;

namespace {
std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}
}  // namespace

TEST_CASE("Protected inputs: no write replaces one, through a link or into its folder",
          "[output]") {
  const std::string dir = test::temp_dir("safe_output_protect");
  test::write_file(dir + "/log.csv", "1,2,3\n");
  fs::create_symlink(dir + "/log.csv", dir + "/page.html");
  protect_inputs({{"log", dir + "/log.csv"}});
  CHECK_THROWS_WITH(write_atomically(dir + "/page.html", [](std::ostream& o) { o << "x"; }),
                    Contains("page.html is the log") && Contains("never replaces an input"));
  CHECK(read_text(dir + "/log.csv") == "1,2,3\n");
  CHECK_THROWS_WITH(open_append_log(dir + "/log.csv"), Contains("is the log"));
  CHECK_THROWS_WITH(refuse_protected("--out", dir, true), Contains("holds the log"));
  CHECK_NOTHROW(write_atomically(dir + "/other.txt", [](std::ostream& o) { o << "x"; }));
}

TEST_CASE("A file that cannot be created: the real cause", "[output]") {
  const std::string dir = test::temp_dir("safe_output_cause");
  CHECK_THROWS_WITH(check_writable(dir + "/no/r.json"),
                    Contains("its directory") && Contains("/no does not exist"));
  test::write_file(dir + "/file", "x");
  CHECK_THROWS_WITH(check_writable(dir + "/file/r.json"), Contains("is not a directory"));
  CHECK_THROWS_WITH(check_writable(dir), Contains("it is a directory"));
  if (::geteuid() != 0) {  // root writes into a read-only folder
    fs::create_directory(dir + "/ro");
    fs::permissions(dir + "/ro", fs::perms::owner_write, fs::perm_options::remove);
    CHECK_THROWS_WITH(check_writable(dir + "/ro/r.json"), Contains("is not writable"));
    CHECK_THROWS_WITH(write_atomically(dir + "/ro/r.json", [](std::ostream& o) { o << "x"; }),
                      Contains("is not writable"));
    fs::permissions(dir + "/ro", fs::perms::owner_write, fs::perm_options::add);
  }
}

TEST_CASE("A monitor log: every line in the file as soon as it is written", "[output]") {
  const std::string dir = test::temp_dir("safe_output_log");
  std::ofstream log = open_append_log(dir + "/m.jsonl");
  log << "{\"t\": 1}\n";
  CHECK(read_text(dir + "/m.jsonl") == "{\"t\": 1}\n");  // before any close or flush
  log << "{\"t\": 2}\n";
  CHECK(read_text(dir + "/m.jsonl") == "{\"t\": 1}\n{\"t\": 2}\n");
}

TEST_CASE("An earlier output's files are its marker's, in every folder", "[output]") {
  const std::string dir = test::temp_dir("safe_output_marker") + "/out";
  write_directory_whole(
      dir, ".marker",
      [](const std::string& d) {
        fs::create_directory(d + "/soak-1");
        test::write_file(d + "/soak-1/imu.csv", "1\n");
        test::write_file(d + "/chamber.ini", "[thermal]\n");
      },
      false);
  CHECK(read_text(dir + "/.marker") == "chamber.ini\nsoak-1/imu.csv\n");
  std::vector<std::string> foreign;
  CHECK(directory_state(dir, ".marker", foreign) == DirectoryState::EarlierOutput);
  test::write_file(dir + "/soak-1/notes.txt", "mine\n");
  CHECK(directory_state(dir, ".marker", foreign) == DirectoryState::Foreign);
  CHECK(foreign == std::vector<std::string>{"soak-1/notes.txt"});
  fs::remove(dir + "/soak-1/notes.txt");
  fs::create_directory(dir + "/mine");
  CHECK(directory_state(dir, ".marker", foreign) == DirectoryState::Foreign);
  CHECK(foreign == std::vector<std::string>{"mine/"});
}

TEST_CASE("The same data given twice: by path, through a link, as a copy", "[output]") {
  const std::string dir = test::temp_dir("safe_output_duplicates");
  test::write_file(dir + "/a.csv", "1,2,3\n4,5,6\n");
  test::write_file(dir + "/b.csv", "1,2,3\n4,5,7\n");  // same size, other bytes
  fs::copy_file(dir + "/a.csv", dir + "/copy.csv");
  fs::create_symlink(dir + "/a.csv", dir + "/link.csv");
  auto set = [&](const std::string& name, const std::string& log) {
    return DataSet{name, {{"session", dir + "/" + name + ".ini"}, {"log", dir + "/" + log}}};
  };
  CHECK_NOTHROW(refuse_duplicate_data({set("s1", "a.csv"), set("s2", "b.csv")}));
  CHECK_THROWS_WITH(refuse_duplicate_data({set("s1", "a.csv"), set("s2", "link.csv")}),
                    Contains("s2 and s1 are the same data") && Contains("the same file"));
  CHECK_THROWS_WITH(refuse_duplicate_data({set("s1", "a.csv"), set("s2", "copy.csv")}),
                    Contains("the same bytes (SHA-256"));
  CHECK_THROWS_WITH(refuse_duplicate_data({set("s1", "a.csv"), set("s1", "b.csv")}),
                    Contains("s1.ini") && Contains("the same file"));
  // One plan or profile shared by the sets is not the same data.
  const DataSet p1{"s1", {{"plan", dir + "/a.csv"}}}, p2{"s2", {{"plan", dir + "/a.csv"}}};
  CHECK_NOTHROW(refuse_duplicate_data({p1, p2}));
}

TEST_CASE("The thermal table: bounded before it is written, whatever the step", "[output]") {
  const std::string dir = test::temp_dir("safe_output_thermal_table");
  const ThermalFit fit;
  for (double step : {1e-5, 1e-9, 0.0, -1.0})
    CHECK_THROWS_WITH(write_thermal_table(dir + "/t.csv", fit, -40.0, 60.0, step),
                      Contains("t.csv") && Contains("rows"));
  CHECK_FALSE(fs::exists(dir + "/t.csv"));
  CHECK_NOTHROW(write_thermal_table(dir + "/t.csv", fit, -40.0, 60.0, 5.0));
}
