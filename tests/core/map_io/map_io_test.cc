// Tests for the Moving AI readers (core/map_io/map_io.h): maps and scenarios,
// and, when the shared benchmark folder is present, every benchmark map and
// scenario file. The ROS map_server readers: ros_map_test.cc. Runs from the
// repository root.
#include "core/map_io/map_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_replace.h"
#include "core/map/grid.h"
#include "gtest/gtest.h"

#include "tests/core/map_io/map_io_test_util.h"

namespace pathd {
namespace {

using namespace testing_map_io;  // NOLINT: test helpers

// ------------------------------------------------------------ Moving AI ----

TEST(MovingAiMapTest, ParsesDimensionsAndCosts) {
  absl::StatusOr<Grid> grid = ParseMovingAiMap(kTinyMap, "tiny.map");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->width(), 4);
  EXPECT_EQ(grid->height(), 3);
  // File order is kept: row 0 is the first grid line.
  EXPECT_EQ(grid->cost(0, 0), kFreeCost);    // '.'
  EXPECT_EQ(grid->cost(1, 0), kLethalCost);  // '@'
  EXPECT_EQ(grid->cost(1, 1), kLethalCost);  // 'T'
  EXPECT_EQ(grid->cost(3, 1), kFreeCost);    // 'G'
  EXPECT_EQ(grid->cost(0, 2), kFreeCost);    // 'S'
  EXPECT_EQ(grid->cost(3, 2), kLethalCost);  // 'W'
  EXPECT_EQ(grid->resolution(), 1.0);
  EXPECT_EQ(grid->origin().x, 0.0);
  EXPECT_EQ(grid->origin().y, 0.0);
}

TEST(MovingAiMapTest, AcceptsCrlfAndMissingFinalNewline) {
  std::string crlf = absl::StrReplaceAll(kTinyMap, {{"\n", "\r\n"}});
  crlf.resize(crlf.size() - 2);  // like Berlin_0_512.map
  absl::StatusOr<Grid> grid = ParseMovingAiMap(crlf, "crlf.map");
  ASSERT_TRUE(grid.ok()) << grid.status();
  absl::StatusOr<Grid> reference = ParseMovingAiMap(kTinyMap, "tiny.map");
  ASSERT_TRUE(reference.ok());
  EXPECT_EQ(grid->cells(), reference->cells());

  std::string lf(kTinyMap);
  lf.pop_back();
  grid = ParseMovingAiMap(lf, "lf.map");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cells(), reference->cells());
}

TEST(MovingAiMapTest, AcceptsHeaderTrailingWhitespaceAndTrailingBlankLines) {
  const std::string text =
      "type octile \t\nheight 1  \nwidth 2\r\nmap \n.@\n\n\r\n";
  absl::StatusOr<Grid> grid = ParseMovingAiMap(text, "t.map");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->width(), 2);
  EXPECT_EQ(grid->height(), 1);
}

TEST(MovingAiMapTest, RejectsTruncatedHeader) {
  ExpectInvalid(ParseMovingAiMap("", "t.map").status(),
                {"t.map:1:", "truncated header", "type octile"});
  ExpectInvalid(ParseMovingAiMap("type octile\n", "t.map").status(),
                {"t.map:2:", "truncated header", "height"});
  ExpectInvalid(ParseMovingAiMap("type octile\nheight 3\n", "t.map").status(),
                {"t.map:3:", "truncated header", "width"});
  ExpectInvalid(
      ParseMovingAiMap("type octile\nheight 3\nwidth 4", "t.map").status(),
      {"t.map:4:", "truncated header", "map"});
}

TEST(MovingAiMapTest, RejectsMalformedHeaderLines) {
  ExpectInvalid(
      ParseMovingAiMap("type tile\nheight 1\nwidth 1\nmap\n.\n", "t.map")
          .status(),
      {"t.map:1:", "type octile"});
  ExpectInvalid(
      ParseMovingAiMap("type octile\nwidth 1\nheight 1\nmap\n.\n", "t.map")
          .status(),
      {"t.map:2:", "height comes before width"});
  ExpectInvalid(
      ParseMovingAiMap("type octile\nheight 1\nwidth 1\nmapp\n.\n", "t.map")
          .status(),
      {"t.map:4:", "expected 'map'"});
  ExpectInvalid(
      ParseMovingAiMap(" type octile\nheight 1\nwidth 1\nmap\n.\n", "t.map")
          .status(),
      {"t.map:1:"});
}

TEST(MovingAiMapTest, RejectsBadNumbers) {
  for (const char* height :
       {"abc", "-3", "0", "99999999999", "3 4", "", "1.5", "65537", "+3"}) {
    SCOPED_TRACE(height);
    const std::string text =
        absl::StrCat("type octile\nheight ", height, "\nwidth 4\nmap\n");
    ExpectInvalid(ParseMovingAiMap(text, "t.map").status(), {"t.map:2:"});
  }
  ExpectInvalid(
      ParseMovingAiMap("type octile\nheight 1\nwidth abc\nmap\n.\n", "t.map")
          .status(),
      {"t.map:3:", "'abc' is not an integer"});
  ExpectInvalid(ParseMovingAiMap(
                    "type octile\nheight 99999999999\nwidth 1\nmap\n", "t.map")
                    .status(),
                {"out of range 1..65536"});
}

TEST(MovingAiMapTest, RejectsWrongRowLength) {
  const std::string text =
      "type octile\nheight 3\nwidth 4\nmap\n....\n...\n....\n";
  ExpectInvalid(ParseMovingAiMap(text, "t.map").status(),
                {"t.map:6: row 2 has 3 characters, expected 4"});
  // Trailing whitespace on a grid row is not forgiven: it would be a cell.
  ExpectInvalid(
      ParseMovingAiMap("type octile\nheight 1\nwidth 2\nmap\n.. \n", "t.map")
          .status(),
      {"t.map:5: row 1 has 3 characters, expected 2"});
}

TEST(MovingAiMapTest, RejectsBadCharacters) {
  const std::string text =
      "type octile\nheight 3\nwidth 4\nmap\n....\n....\n.x..\n";
  ExpectInvalid(ParseMovingAiMap(text, "t.map").status(),
                {"t.map:7:", "column 2", "'x'", "(1, 2)"});
  // Non-printable bytes are shown escaped.
  const std::string nul("type octile\nheight 1\nwidth 2\nmap\n.\0\n", 36);
  ExpectInvalid(ParseMovingAiMap(nul, "t.map").status(),
                {"t.map:5:", "column 2", "'\\x00'"});
  // A bare '\r' inside a row is not a line ending.
  ExpectInvalid(
      ParseMovingAiMap("type octile\nheight 1\nwidth 3\nmap\n.\r.\n", "t.map")
          .status(),
      {"t.map:5:", "column 2"});
}

TEST(MovingAiMapTest, RejectsTooFewAndTooManyRows) {
  ExpectInvalid(
      ParseMovingAiMap("type octile\nheight 3\nwidth 2\nmap\n..\n..\n", "t.map")
          .status(),
      {"t.map:7:", "file ends after 2 of 3 rows"});
  ExpectInvalid(
      ParseMovingAiMap("type octile\nheight 1\nwidth 2\nmap\n..\n..\n", "t.map")
          .status(),
      {"t.map:6:", "unexpected row"});
  ExpectInvalid(ParseMovingAiMap(
                    "type octile\nheight 1\nwidth 2\nmap\n..\n\n..\n", "t.map")
                    .status(),
                {"t.map:7:", "unexpected row"});
}

TEST(MovingAiMapTest, RejectsHugeDimensionsBeforeAllocating) {
  // No rows follow: an error about rows would mean the reader went on.
  ExpectInvalid(ParseMovingAiMap(
                    "type octile\nheight 100000\nwidth 100000\nmap\n", "t.map")
                    .status(),
                {"t.map:2:", "100000", "out of range"});
  ExpectTooBig(
      ParseMovingAiMap("type octile\nheight 65536\nwidth 65536\nmap\n", "t.map")
          .status(),
      {"t.map:3:", "exceeds the limit of 268435456 cells"});
  ExpectTooBig(ParseMovingAiMap(kTinyMap, "t.map", /*max_cells=*/11).status(),
               {"t.map:3:", "4 x 3 = 12 cells exceeds the limit of 11 cells"});
  EXPECT_TRUE(ParseMovingAiMap(kTinyMap, "t.map", /*max_cells=*/12).ok());
}

TEST(MovingAiMapTest, ReadsFilesAndNamesMissingOnes) {
  absl::StatusOr<Grid> grid = ReadMovingAiMapFile(TestDataPath("tiny.map"));
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->width(), 4);
  EXPECT_EQ(grid->cost(1, 0), kLethalCost);

  grid = ReadMapFile(TestDataPath("tiny.map"));
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->height(), 3);

  const std::string missing = TestDataPath("no_such.map");
  EXPECT_EQ(ReadMovingAiMapFile(missing).status(),
            absl::NotFoundError(absl::StrCat(missing, ": no such file")));
  EXPECT_EQ(ReadMapFile(missing).status().code(), absl::StatusCode::kNotFound);
  ExpectInvalid(ReadMapFile(TestDataPath("p2.pgm")).status(),
                {"p2.pgm", "unknown map file type"});
  // A folder is not a map.
  EXPECT_FALSE(ReadFileToString(kTestData).ok());
}

TEST(MovingAiMapTest, ReadsBundledMaps) {
  absl::StatusOr<Grid> arena = ReadMapFile("maps/arena2.map");
  ASSERT_TRUE(arena.ok()) << arena.status();
  EXPECT_EQ(arena->width(), 281);
  EXPECT_EQ(arena->height(), 209);
  absl::StatusOr<ScenarioFile> scen =
      ReadMovingAiScenarioFileWithVersion("maps/arena2.map.scen");
  ASSERT_TRUE(scen.ok()) << scen.status();
  EXPECT_EQ(scen->version, "1");
  EXPECT_EQ(scen->scenarios.size(), 929u);
}

// ------------------------------------------------------------ scenarios ----

TEST(MovingAiScenarioTest, ParsesVersion1) {
  const std::string text =
      "version 1\n"
      "0\tmaps/dao/arena2.map\t281\t209\t69\t126\t72\t123\t4.24264\r\n"
      "\n"
      "too few fields\n"
      "1\tmaps/dao/arena2.map\t281\t209\t133\t77\t141\t66\t14.3137\n"
      "\n";
  absl::StatusOr<ScenarioFile> file = ParseMovingAiScenarioFile(text, "a.scen");
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->version, "1");
  ASSERT_EQ(file->scenarios.size(), 2u);
  const Scenario& s = file->scenarios[1];
  EXPECT_EQ(s.bucket, 1);
  EXPECT_EQ(s.map, "maps/dao/arena2.map");
  EXPECT_EQ(s.map_width, 281);
  EXPECT_EQ(s.map_height, 209);
  EXPECT_EQ(s.start, (Cell{133, 77}));
  EXPECT_EQ(s.goal, (Cell{141, 66}));
  EXPECT_DOUBLE_EQ(s.optimal_length, 14.3137);
  EXPECT_EQ(s.optimal_text, "14.3137");
  EXPECT_EQ(s.line, 5);
  EXPECT_EQ(file->scenarios[0].optimal_text, "4.24264");

  absl::StatusOr<std::vector<Scenario>> plain =
      ParseMovingAiScenarios(text, "a.scen");
  ASSERT_TRUE(plain.ok()) << plain.status();
  EXPECT_EQ(plain->size(), 2u);
}

TEST(MovingAiScenarioTest, ParsesVersion10WithSpaces) {
  const std::string text =
      "version 1.0\n"
      "0 maps/bgmaps/AR0011SR.map 512 512 10 20 12 22 2.83\n";
  absl::StatusOr<ScenarioFile> file =
      ParseMovingAiScenarioFile(text, "bg.scen");
  ASSERT_TRUE(file.ok()) << file.status();
  EXPECT_EQ(file->version, "1.0");
  ASSERT_EQ(file->scenarios.size(), 1u);
  EXPECT_EQ(file->scenarios[0].goal, (Cell{12, 22}));
  EXPECT_EQ(file->scenarios[0].line, 2);
}

TEST(MovingAiScenarioTest, ReadsFile) {
  absl::StatusOr<ScenarioFile> file =
      ReadMovingAiScenarioFileWithVersion(TestDataPath("tiny.map.scen"));
  ASSERT_TRUE(file.ok()) << file.status();
  ASSERT_EQ(file->scenarios.size(), 2u);
  EXPECT_EQ(file->scenarios[0].line, 3);
  absl::StatusOr<std::vector<Scenario>> list =
      ReadMovingAiScenarioFile(TestDataPath("tiny.map.scen"));
  ASSERT_TRUE(list.ok()) << list.status();
  EXPECT_EQ(list->size(), 2u);
  EXPECT_EQ(ReadMovingAiScenarioFile("nope.scen").status().code(),
            absl::StatusCode::kNotFound);
}

TEST(MovingAiScenarioTest, RejectsBadVersionLine) {
  for (const char* text : {"", "version 2\n", "version\n",
                           "1 a 1 1 0 0 0 0 1\n", "version 1 extra\n"}) {
    SCOPED_TRACE(text);
    ExpectInvalid(ParseMovingAiScenarios(text, "x.scen").status(),
                  {"x.scen:1:", "version 1"});
  }
}

TEST(MovingAiScenarioTest, RejectsMalformedLines) {
  const auto parse = [](const std::string& line) {
    return ParseMovingAiScenarios(absl::StrCat("version 1\n\n", line, "\n"),
                                  "x.scen")
        .status();
  };
  ExpectInvalid(parse("0 m 4 3 a 0 1 1 1.5"), {"x.scen:3:", "field 5", "'a'"});
  ExpectInvalid(parse("0 m 4 3 0 0 1 1 abc"), {"x.scen:3:", "field 9"});
  ExpectInvalid(parse("0 m 4 3 0 0 1 1 nan"), {"x.scen:3:", "field 9"});
  ExpectInvalid(parse("0 m 4 3 0 0 1 1 -2"), {"x.scen:3:", "field 9"});
  ExpectInvalid(parse("0 m 4 3 0 0 1 1 1.5 extra"), {"x.scen:3:", "9 fields"});
  ExpectInvalid(parse("0 m 4 3 0 0 4 1 1.5"), {"x.scen:3:", "goal (4, 1)"});
  ExpectInvalid(parse("0 m 4 3 0 -1 1 1 1.5"), {"x.scen:3:", "start (0, -1)"});
  ExpectInvalid(parse("0 m 0 3 0 0 0 0 1.5"), {"x.scen:3:", "map size"});
  ExpectInvalid(parse("0 m 4 99999999999 0 0 0 0 1.5"),
                {"x.scen:3:", "field 4"});
}

TEST(ScenarioToleranceTest, SixSignificantDigits) {
  Scenario s;
  s.optimal_text = "320.764";
  s.optimal_length = 320.764;
  const double tolerance = ScenarioTolerance(s, "1");
  EXPECT_NEAR(tolerance, 0.0005 + 1e-5, 1e-12);
  // An exact 320.764502 stored as 320.764 is within the tolerance.
  EXPECT_LE(std::abs(320.764502 - s.optimal_length), tolerance);
  EXPECT_GT(std::abs(320.764 + 1e-3 - s.optimal_length), tolerance);

  s.optimal_text = "1";
  s.optimal_length = 1;
  EXPECT_NEAR(ScenarioTolerance(s, "1"), 0.5e-5 + 1e-5, 1e-15);
  s.optimal_text = "1177.2";
  s.optimal_length = 1177.2;
  EXPECT_NEAR(ScenarioTolerance(s, "1"), 0.005 + 1e-5, 1e-12);
  s.optimal_text = "0";
  s.optimal_length = 0;
  EXPECT_EQ(ScenarioTolerance(s, "1"), 1e-5);
}

TEST(ScenarioToleranceTest, EightDecimalsAndVersion10) {
  Scenario s;
  s.optimal_text = "2.41421356";
  s.optimal_length = 2.41421356;
  EXPECT_EQ(ScenarioTolerance(s, "1"), 1e-6);
  s.optimal_text = "244.95";
  s.optimal_length = 244.95;
  EXPECT_EQ(ScenarioTolerance(s, "1.0"), 0.005 + 1e-9);
  EXPECT_LE(std::abs(244.954 - s.optimal_length), ScenarioTolerance(s, "1.0"));
  EXPECT_GT(std::abs(244.956 - s.optimal_length), ScenarioTolerance(s, "1.0"));
}

// ------------------------------------------------------ benchmark files ----

// Every shared benchmark map and its scenarios load, agree on dimensions, and
// put every start and goal on a free cell.
TEST(MovingAiBenchmarkTest, AllMapsAndScenariosLoad) {
  if (!std::filesystem::is_directory(kBenchmarks)) {
    GTEST_SKIP()
        << kBenchmarks << " not found (run from the repository root with "
        << "the shared benchmarks beside it); skipping benchmark files";
  }
  std::vector<std::filesystem::path> maps;
  for (const auto& entry :
       std::filesystem::recursive_directory_iterator(kBenchmarks)) {
    if (entry.is_regular_file() && entry.path().extension() == ".map") {
      maps.push_back(entry.path());
    }
  }
  std::sort(maps.begin(), maps.end());
  ASSERT_FALSE(maps.empty()) << "no .map files under " << kBenchmarks;
  int64_t total_scenarios = 0;
  for (const std::filesystem::path& map_path : maps) {
    SCOPED_TRACE(map_path.string());
    absl::StatusOr<Grid> grid = ReadMovingAiMapFile(map_path.string());
    ASSERT_TRUE(grid.ok()) << grid.status();
    const std::string scen_path = map_path.string() + ".scen";
    absl::StatusOr<ScenarioFile> file =
        ReadMovingAiScenarioFileWithVersion(scen_path);
    ASSERT_TRUE(file.ok()) << file.status();
    EXPECT_FALSE(file->scenarios.empty());
    for (const Scenario& s : file->scenarios) {
      ASSERT_EQ(s.map_width, grid->width()) << scen_path << ":" << s.line;
      ASSERT_EQ(s.map_height, grid->height()) << scen_path << ":" << s.line;
      ASSERT_EQ(grid->cost(s.start), kFreeCost) << scen_path << ":" << s.line;
      ASSERT_EQ(grid->cost(s.goal), kFreeCost) << scen_path << ":" << s.line;
      // Each file's stated precision gives a sane tolerance.
      const double tolerance = ScenarioTolerance(s, file->version);
      ASSERT_GT(tolerance, 0.0);
      ASSERT_LE(tolerance, 0.0051 + 1e-5 * s.optimal_length) << s.optimal_text;
    }
    total_scenarios += static_cast<int64_t>(file->scenarios.size());
  }
  // The README counts 54,406 nine-field lines in its 20 files.
  if (maps.size() == 20) {
    EXPECT_EQ(total_scenarios, 54406);
  }
}

}  // namespace
}  // namespace pathd
