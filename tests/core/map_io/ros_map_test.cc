// Tests for the ROS map_server readers (core/map_io/map_io.h): YAML metadata
// and PGM images (P2 and P5). Runs from the repository root.
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

}  // namespace
}  // namespace pathd
