// Tests for the map readers (core/map_io/map_io.h): Moving AI maps and scenarios, ROS
// map_server YAML + PGM, and, when the shared benchmark folder is present,
// every benchmark map and scenario file. Runs from the repository root.
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

namespace pathd {
namespace {

constexpr char kTestData[] = "tests/testdata/map_io";
constexpr char kBenchmarks[] = "../shared/benchmarks/movingai";

// 4 wide, 3 high; one of each character class.
constexpr char kTinyMap[] =
    "type octile\n"
    "height 3\n"
    "width 4\n"
    "map\n"
    ".@..\n"
    ".T.G\n"
    "S..W\n";

std::string TestDataPath(std::string_view name) {
  return absl::StrCat(kTestData, "/", std::string(name));
}

// Writes a file under the test's temporary folder and returns its path.
std::string WriteTempFile(std::string_view name, std::string_view contents) {
  const std::string path =
      absl::StrCat(::testing::TempDir(), "/map_io_test_", std::string(name));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
  out.close();
  EXPECT_TRUE(out.good()) << path;
  return path;
}

// Expects INVALID_ARGUMENT whose message contains every fragment.
// A size limit: RESOURCE_EXHAUSTED, so the server can tell it from a syntax
// error and answer as its --max_map_cells contract says.
void ExpectTooBig(const absl::Status& status,
                  std::initializer_list<std::string_view> fragments) {
  EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted) << status;
  for (std::string_view fragment : fragments) {
    EXPECT_NE(std::string(status.message()).find(fragment), std::string::npos)
        << "'" << fragment << "' not in: " << status;
  }
}

void ExpectInvalid(const absl::Status& status,
                   std::initializer_list<std::string_view> fragments) {
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << status;
  for (std::string_view fragment : fragments) {
    EXPECT_NE(std::string(status.message()).find(fragment), std::string::npos)
        << "'" << fragment << "' not in: " << status;
  }
}

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
  // The README's example: exact 320.764502 stored as 320.764.
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

// ------------------------------------------------------------- ROS YAML ----

TEST(RosMapYamlTest, ParsesAllKeys) {
  absl::StatusOr<RosMapMetadata> m = ParseRosMapYaml(
      "image: maps/floor.pgm\n"
      "resolution: 0.05\n"
      "origin: [-10.0, -5.5, 0.5]\n"
      "negate: 1\n"
      "occupied_thresh: 0.7\n"
      "free_thresh: 0.2\n"
      "mode: scale\n"
      "some_future_key: {a: 1}\n",
      "floor.yaml");
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_EQ(m->image, "maps/floor.pgm");
  EXPECT_EQ(m->resolution, 0.05);
  EXPECT_EQ(m->origin.x, -10.0);
  EXPECT_EQ(m->origin.y, -5.5);
  EXPECT_EQ(m->origin.yaw, 0.5);
  EXPECT_TRUE(m->negate);
  EXPECT_EQ(m->occupied_thresh, 0.7);
  EXPECT_EQ(m->free_thresh, 0.2);
  EXPECT_EQ(m->mode, RosMapMetadata::Mode::kScale);
}

TEST(RosMapYamlTest, DefaultsForOptionalKeys) {
  absl::StatusOr<RosMapMetadata> m = ParseRosMapYaml(
      "image: a.pgm\nresolution: 1\norigin: [0, 0, 0]\n", "a.yaml");
  ASSERT_TRUE(m.ok()) << m.status();
  EXPECT_FALSE(m->negate);
  EXPECT_EQ(m->occupied_thresh, 0.65);
  EXPECT_EQ(m->free_thresh, 0.196);
  EXPECT_EQ(m->mode, RosMapMetadata::Mode::kTrinary);
}

TEST(RosMapYamlTest, NegateAcceptsNumbersAndBooleans) {
  for (const auto& [text, expected] : std::vector<std::pair<std::string, bool>>{
           {"0", false}, {"1", true}, {"true", true}, {"false", false}}) {
    absl::StatusOr<RosMapMetadata> m = ParseRosMapYaml(
        absl::StrCat("image: a.pgm\nresolution: 1\norigin: [0, 0, 0]\nnegate: ",
                     text),
        "a.yaml");
    ASSERT_TRUE(m.ok()) << text << ": " << m.status();
    EXPECT_EQ(m->negate, expected) << text;
  }
}

TEST(RosMapYamlTest, RejectsBadYaml) {
  const std::string base =
      "image: a.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  // yaml-cpp's own line is reported for syntax errors.
  ExpectInvalid(
      ParseRosMapYaml("image: a.pgm\nresolution: 0.05\norigin: [0, 0\n",
                      "bad.yaml")
          .status(),
      {"bad.yaml:", "invalid YAML"});
  ExpectInvalid(
      ParseRosMapYaml("image: a.pgm\n  resolution: : :\n", "bad.yaml").status(),
      {"bad.yaml:2:", "invalid YAML"});
  ExpectInvalid(ParseRosMapYaml("", "e.yaml").status(), {"e.yaml", "mapping"});
  ExpectInvalid(ParseRosMapYaml("just a string", "e.yaml").status(),
                {"mapping"});
  ExpectInvalid(
      ParseRosMapYaml("resolution: 1\norigin: [0, 0, 0]\n", "m.yaml").status(),
      {"m.yaml", "'image'"});
  ExpectInvalid(
      ParseRosMapYaml("image: a\norigin: [0, 0, 0]\n", "m.yaml").status(),
      {"m.yaml", "'resolution'"});
  ExpectInvalid(ParseRosMapYaml("image: a\nresolution: 1\n", "m.yaml").status(),
                {"m.yaml", "'origin'"});
  ExpectInvalid(
      ParseRosMapYaml("image: [a, b]\nresolution: 1\norigin: [0, 0, 0]\n",
                      "m.yaml")
          .status(),
      {"m.yaml:1:", "'image'"});
  ExpectInvalid(
      ParseRosMapYaml("image: a\nresolution: -0.05\norigin: [0, 0, 0]\n",
                      "m.yaml")
          .status(),
      {"m.yaml:2:", "'resolution'", "positive"});
  for (const char* resolution : {"0", ".inf", ".nan", "abc", "[1]"}) {
    SCOPED_TRACE(resolution);
    ExpectInvalid(
        ParseRosMapYaml(absl::StrCat("image: a\nresolution: ", resolution,
                                     "\norigin: [0, 0, 0]\n"),
                        "m.yaml")
            .status(),
        {"m.yaml:2:", "'resolution'"});
  }
  ExpectInvalid(
      ParseRosMapYaml("image: a\nresolution: 1\norigin: [0, 0]\n", "m.yaml")
          .status(),
      {"m.yaml:3:", "'origin'", "3 numbers", "got 2"});
  ExpectInvalid(
      ParseRosMapYaml("image: a\nresolution: 1\norigin: 5\n", "m.yaml")
          .status(),
      {"m.yaml:3:", "'origin'"});
  ExpectInvalid(
      ParseRosMapYaml("image: a\nresolution: 1\norigin: [0, x, 0]\n", "m.yaml")
          .status(),
      {"m.yaml:3:", "'origin'"});
  ExpectInvalid(ParseRosMapYaml(base + "negate: 2\n", "m.yaml").status(),
                {"m.yaml:4:", "'negate'"});
  ExpectInvalid(
      ParseRosMapYaml(base + "occupied_thresh: 1.5\n", "m.yaml").status(),
      {"m.yaml:4:", "'occupied_thresh'"});
  ExpectInvalid(
      ParseRosMapYaml(base + "free_thresh: -0.1\n", "m.yaml").status(),
      {"m.yaml:4:", "'free_thresh'"});
  ExpectInvalid(ParseRosMapYaml(
                    base + "free_thresh: 0.7\noccupied_thresh: 0.6\n", "m.yaml")
                    .status(),
                {"m.yaml", "'free_thresh'", "less than 'occupied_thresh'"});
  ExpectInvalid(ParseRosMapYaml(base + "mode: fancy\n", "m.yaml").status(),
                {"m.yaml:4:", "'mode'", "'fancy'"});
}

// Issue 15: finite but absurd values (a denormal resolution, an origin near
// DBL_MAX) were accepted and made every world coordinate meaningless.
TEST(RosMapYamlTest, RejectsAbsurdResolutionAndOriginNamingTheField) {
  for (const char* resolution : {"1e-320", "1e-7", "1e7", "1e308"}) {
    SCOPED_TRACE(resolution);
    ExpectInvalid(
        ParseRosMapYaml(absl::StrCat("image: a\nresolution: ", resolution,
                                     "\norigin: [0, 0, 0]\n"),
                        "m.yaml")
            .status(),
        {"m.yaml:2:", "'resolution'", "metres per cell"});
  }
  for (const char* origin :
       {"[1e308, -1e308, 0]", "[0, -1e10, 0]", "[2e9, 0, 0]", "[0, 0, 1e300]"}) {
    SCOPED_TRACE(origin);
    ExpectInvalid(ParseRosMapYaml(absl::StrCat("image: a\nresolution: 0.05\n"
                                               "origin: ",
                                               origin, "\n"),
                                  "m.yaml")
                      .status(),
                  {"m.yaml:3", "'origin'", "within"});
  }
  // The bounds themselves are fine.
  EXPECT_TRUE(ParseRosMapYaml("image: a\nresolution: 1e-6\n"
                              "origin: [-1e9, 1e9, -3.14]\n",
                              "m.yaml")
                  .ok());
  EXPECT_TRUE(
      ParseRosMapYaml("image: a\nresolution: 1e6\norigin: [0, 0, 0]\n", "m.yaml")
          .ok());
}

// ------------------------------------------------------------- ROS PGM ----

RosMapMetadata Metadata() {
  RosMapMetadata m;
  m.image = "x.pgm";
  m.resolution = 0.05;
  return m;
}

// A P5 image with the given samples (top row first).
std::string P5(int width, int height, int maxval,
               const std::vector<int>& samples) {
  std::string pgm =
      absl::StrCat("P5\n", width, " ", height, "\n", maxval, "\n");
  for (int v : samples) {
    if (maxval > 255) pgm.push_back(static_cast<char>(v >> 8));
    pgm.push_back(static_cast<char>(v & 0xff));
  }
  return pgm;
}

TEST(RosMapTest, ReadsP2FixtureWithRowFlipAndPlacement) {
  absl::StatusOr<Grid> grid = ReadRosMapFile(TestDataPath("p2.yaml"));
  ASSERT_TRUE(grid.ok()) << grid.status();
  ASSERT_EQ(grid->width(), 3);
  ASSERT_EQ(grid->height(), 2);
  // Image top row "0 254 205" is grid row 1.
  EXPECT_EQ(grid->cost(0, 1), kLethalCost);
  EXPECT_EQ(grid->cost(1, 1), kFreeCost);
  EXPECT_EQ(grid->cost(2, 1), kUnknownCost);  // map_server's grey 205
  // Image bottom row "255 100 0" is grid row 0.
  EXPECT_EQ(grid->cost(0, 0), kFreeCost);
  EXPECT_EQ(grid->cost(1, 0), kUnknownCost);
  EXPECT_EQ(grid->cost(2, 0), kLethalCost);
  EXPECT_EQ(grid->resolution(), 0.05);
  EXPECT_EQ(grid->origin().x, -1.0);
  EXPECT_EQ(grid->origin().y, 2.0);
  EXPECT_EQ(grid->origin().yaw, 0.0);
  // The bottom-left cell's centre is half a cell from the origin.
  const WorldPoint centre = grid->CellCenter(Cell{0, 0});
  EXPECT_NEAR(centre.x, -0.975, 1e-12);
  EXPECT_NEAR(centre.y, 2.025, 1e-12);

  absl::StatusOr<Grid> by_extension = ReadMapFile(TestDataPath("p2.yaml"));
  ASSERT_TRUE(by_extension.ok()) << by_extension.status();
  EXPECT_EQ(by_extension->cells(), grid->cells());
}

TEST(RosMapTest, ReadsP5Fixtures) {
  // 8-bit, negate: white is occupied.
  absl::StatusOr<Grid> grid = ReadRosMapFile(TestDataPath("p5.yaml"));
  ASSERT_TRUE(grid.ok()) << grid.status();
  ASSERT_EQ(grid->width(), 3);
  ASSERT_EQ(grid->height(), 1);
  EXPECT_EQ(grid->cost(0, 0), kFreeCost);
  EXPECT_EQ(grid->cost(1, 0), kUnknownCost);
  EXPECT_EQ(grid->cost(2, 0), kLethalCost);
  EXPECT_EQ(grid->resolution(), 0.025);

  // 16-bit big-endian, image in a subfolder of the YAML's folder.
  grid = ReadRosMapFile(TestDataPath("p5_16.yaml"));
  ASSERT_TRUE(grid.ok()) << grid.status();
  ASSERT_EQ(grid->width(), 2);
  ASSERT_EQ(grid->height(), 2);
  EXPECT_EQ(grid->cost(0, 1), kLethalCost);   // top row: black
  EXPECT_EQ(grid->cost(1, 1), kFreeCost);     //          white
  EXPECT_EQ(grid->cost(0, 0), kUnknownCost);  // bottom row: mid grey
  EXPECT_EQ(grid->cost(1, 0), kFreeCost);
  EXPECT_EQ(grid->origin().x, 0.5);
  EXPECT_EQ(grid->origin().y, -0.5);
  EXPECT_EQ(grid->origin().yaw, 0.25);
}

TEST(RosMapTest, ResolvesAbsoluteImagePathsAsIs) {
  const std::string pgm_path = WriteTempFile("abs.pgm", "P2 1 1 1 0\n");
  const std::string yaml_path = WriteTempFile(
      "abs.yaml",
      absl::StrCat("image: ", std::filesystem::absolute(pgm_path).string(),
                   "\nresolution: 1\norigin: [0, 0, 0]\n"));
  absl::StatusOr<Grid> grid = ReadRosMapFile(yaml_path);
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cost(0, 0), kLethalCost);
}

TEST(RosMapTest, MissingFilesAreNotFoundAndNamed) {
  EXPECT_EQ(ReadRosMapFile(TestDataPath("nope.yaml")).status().code(),
            absl::StatusCode::kNotFound);
  const std::string yaml_path =
      WriteTempFile("missing_image.yaml",
                    "image: missing.pgm\nresolution: 1\norigin: [0, 0, 0]\n");
  const absl::Status status = ReadRosMapFile(yaml_path).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kNotFound);
  const std::string image_path =
      (std::filesystem::path(yaml_path).parent_path() / "missing.pgm").string();
  EXPECT_NE(std::string(status.message()).find(image_path), std::string::npos)
      << status;
}

// The same ranges hold for metadata that did not come from a YAML file.
TEST(RosMapTest, RejectsAbsurdMetadataNamingTheField) {
  RosMapMetadata m = Metadata();
  m.resolution = 1e-320;
  ExpectInvalid(ParseRosMap(m, "P2 1 1 255\n255\n", "t.pgm").status(),
                {"t.pgm", "'resolution'"});
  m = Metadata();
  m.origin.x = 1e308;
  m.origin.y = -1e308;
  ExpectInvalid(ParseRosMap(m, "P2 1 1 255\n255\n", "t.pgm").status(),
                {"t.pgm", "'origin'"});
}

TEST(RosMapTest, TrinaryThresholdsAreStrict) {
  RosMapMetadata m = Metadata();
  m.occupied_thresh = 0.6;
  m.free_thresh = 0.2;
  // maxval 10: p = (10 - v) / 10. p == occupied or free is neither.
  absl::StatusOr<Grid> grid =
      ParseRosMap(m, "P2 6 1 10\n10 9 8 4 3 0\n", "t.pgm");
  ASSERT_TRUE(grid.ok()) << grid.status();
  const std::vector<uint8_t> expected = {kFreeCost,    kFreeCost,
                                         kUnknownCost, kUnknownCost,
                                         kLethalCost,  kLethalCost};
  // p: 0, 0.1, 0.2, 0.6, 0.7, 1.0
  EXPECT_EQ(grid->cells(), expected);
}

TEST(RosMapTest, ScaleModeIsLinearBetweenThresholds) {
  RosMapMetadata m = Metadata();
  m.mode = RosMapMetadata::Mode::kScale;
  m.occupied_thresh = 0.8;
  m.free_thresh = 0.2;
  // maxval 100, p = (100 - v) / 100: 0.1, 0.2, 0.35, 0.8, 0.9.
  absl::StatusOr<Grid> grid =
      ParseRosMap(m, "P2 5 1 100 90 80 65 20 10", "s.pgm");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cost(0, 0), kFreeCost);
  EXPECT_EQ(grid->cost(1, 0), 1);
  EXPECT_EQ(grid->cost(2, 0), 64);  // 1 + round(0.25 * 251)
  EXPECT_EQ(grid->cost(3, 0), kMaxTraversableCost);
  EXPECT_EQ(grid->cost(4, 0), kLethalCost);
}

TEST(RosMapTest, NegateInvertsOccupancy) {
  RosMapMetadata m = Metadata();
  m.negate = true;
  absl::StatusOr<Grid> grid = ParseRosMap(m, P5(2, 1, 255, {0, 255}), "n.pgm");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cost(0, 0), kFreeCost);
  EXPECT_EQ(grid->cost(1, 0), kLethalCost);
  m.negate = false;
  grid = ParseRosMap(m, P5(2, 1, 255, {0, 255}), "n.pgm");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cost(0, 0), kLethalCost);
  EXPECT_EQ(grid->cost(1, 0), kFreeCost);
}

TEST(RosMapTest, RawModeKeepsValuesClampedTo255) {
  RosMapMetadata m = Metadata();
  m.mode = RosMapMetadata::Mode::kRaw;
  absl::StatusOr<Grid> grid =
      ParseRosMap(m, P5(4, 1, 1000, {0, 100, 255, 1000}), "r.pgm");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cells(), (std::vector<uint8_t>{0, 100, 255, 255}));
}

TEST(RosMapTest, RowFlipAndPlacementForP5) {
  RosMapMetadata m = Metadata();
  m.resolution = 0.5;
  m.origin = GridOrigin{3.0, 4.0, 0.0};
  // Three rows: black, white, black-white.
  absl::StatusOr<Grid> grid =
      ParseRosMap(m, P5(2, 3, 255, {0, 0, 255, 255, 0, 255}), "f.pgm");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cells(),
            (std::vector<uint8_t>{kLethalCost, kFreeCost,  // bottom
                                  kFreeCost, kFreeCost,    //
                                  kLethalCost, kLethalCost}));
  absl::StatusOr<Cell> cell = grid->WorldToCell(WorldPoint{3.1, 4.1});
  ASSERT_TRUE(cell.ok()) << cell.status();
  EXPECT_EQ(*cell, (Cell{0, 0}));
  EXPECT_EQ(grid->cost(*cell), kLethalCost);  // the image's bottom-left pixel
}

TEST(RosMapTest, P5CommentAfterMaxvalAndTrailingBytes) {
  absl::StatusOr<Grid> grid = ParseRosMap(
      Metadata(), std::string("P5 2 1 255#c\n\x00\xff\n", 16), "c.pgm");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cells(), (std::vector<uint8_t>{kLethalCost, kFreeCost}));
}

TEST(RosMapTest, RejectsBadPgms) {
  const RosMapMetadata m = Metadata();
  const auto parse = [&](std::string_view pgm) {
    return ParseRosMap(m, pgm, "b.pgm").status();
  };
  ExpectInvalid(parse(""), {"b.pgm", "bad magic"});
  ExpectInvalid(parse("P6 1 1 255\n\x01\x02\x03"),
                {"b.pgm", "bad magic", "P6"});
  ExpectInvalid(parse("\x89PNG\r\n"), {"b.pgm", "bad magic"});
  ExpectInvalid(parse("P22 1 1 255 0"), {"b.pgm", "bad magic"});
  ExpectInvalid(parse("P2"), {"b.pgm:1:", "missing width"});
  ExpectInvalid(parse("P2\n# only a comment\n3"),
                {"b.pgm:3:", "missing height"});
  ExpectInvalid(parse("P2\n3 2\n"), {"b.pgm:3:", "missing maxval"});
  ExpectInvalid(parse("P2\n3 x\n255\n"), {"b.pgm:2:", "height 'x'"});
  ExpectInvalid(parse("P5\n-3 2\n255\n"), {"b.pgm:2:", "width '-3'"});
  ExpectInvalid(parse("P2 1 1 0\n0\n"), {"b.pgm:1:", "maxval '0'", "1..65535"});
  ExpectInvalid(parse(std::string("P5 1 1 65536\n\0\0", 15)),
                {"maxval '65536'"});
  ExpectInvalid(parse("P5 0 1 255\n"), {"width '0'"});
  ExpectInvalid(parse("P5 65537 1 255\n"), {"width '65537'", "1..65536"});
  ExpectTooBig(parse("P5 65536 65536 255\n"),
               {"exceeds the limit of 268435456"});
  ExpectTooBig(
      ParseRosMap(m, "P2 4 3 255\n", "b.pgm", /*max_cells=*/11).status(),
      {"b.pgm:1:", "4 x 3 = 12 pixels exceeds the limit of 11"});
  ExpectInvalid(parse(std::string("P5 2 2 255\n\0\0\0", 14)),
                {"b.pgm", "truncated pixel data", "needs 4 bytes, found 3"});
  ExpectInvalid(parse(P5(2, 1, 1000, {1, 2}).substr(0, 15)),
                {"truncated pixel data", "needs 4 bytes"});
  ExpectInvalid(parse(P5(2, 1, 1000, {1, 1001})),
                {"(1, 0)", "1001 exceeds maxval 1000"});
  ExpectInvalid(parse(P5(2, 1, 100, {1, 200})), {"200 exceeds maxval 100"});
  ExpectInvalid(
      parse("P2 2 2 255\n0 0\n0\n"),
      {"b.pgm:3:", "truncated pixel data", "expected 4 values, found 3"});
  ExpectInvalid(parse("P2 2 2 255\n0 0\n0 256\n"),
                {"b.pgm:3:", "256 exceeds maxval 255"});
  ExpectInvalid(parse("P2 2 1 255\n0 x\n"),
                {"b.pgm:2:", "'x' is not a number"});
  ExpectInvalid(parse("P2 2 1 255\n0 -1\n"),
                {"b.pgm:2:", "'-1' is not a number"});
  ExpectInvalid(parse("P2 2 1 255\n0 0\n0\n"), {"b.pgm:3:", "unexpected data"});
}

TEST(RosMapTest, RejectsInvalidMetadata) {
  RosMapMetadata m = Metadata();
  m.resolution = 0.0;
  ExpectInvalid(ParseRosMap(m, "P2 1 1 1 0", "m.pgm").status(),
                {"m.pgm", "resolution"});
  m = Metadata();
  m.free_thresh = 0.9;
  ExpectInvalid(ParseRosMap(m, "P2 1 1 1 0", "m.pgm").status(),
                {"m.pgm", "free_thresh"});
  m = Metadata();
  m.origin.x = std::nan("");
  ExpectInvalid(ParseRosMap(m, "P2 1 1 1 0", "m.pgm").status(),
                {"m.pgm", "origin"});
}

TEST(RosMapTest, ReportsBadPgmThroughYamlWithImagePath) {
  const std::string pgm_path =
      WriteTempFile("bad_image.pgm", "P2 2 2 255\n0 0\n");
  const std::string yaml_path =
      WriteTempFile("bad_image.yaml",
                    "image: map_io_test_bad_image.pgm\nresolution: 1\n"
                    "origin: [0, 0, 0]\n");
  ExpectInvalid(ReadRosMapFile(yaml_path).status(),
                {pgm_path.substr(pgm_path.rfind('/')), "truncated pixel data"});
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
