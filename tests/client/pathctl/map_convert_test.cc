// maps import / export conversions: PNG occupancy images read with
// map_server's rules (the same cells as the PGM of the same picture), Moving
// AI and map_server files written back, and round trips of the bundled maps.
#include "client/pathctl/map_convert.h"

#include <png.h>

#include <csetjmp>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "client/pathctl/png_io.h"
#include "core/map_io/map_io.h"
#include "gtest/gtest.h"

namespace pathd::pathctl {
namespace {

namespace fs = std::filesystem;

// An RGBA PNG of `rgba` pixels (4 bytes each), `width` per row, top row first.
std::string RgbaPng(int32_t width, int32_t height, std::vector<uint8_t> rgba) {
  Image image;
  image.width = width;
  image.height = height;
  image.channels = 4;
  image.pixels = std::move(rgba);
  return *EncodePng(image);
}

// A binary PGM of grey levels, the counterpart of a grey PNG.
std::string GreyPgm(int32_t width, int32_t height,
                    const std::vector<uint8_t>& grey) {
  std::string pgm =
      "P5\n" + std::to_string(width) + " " + std::to_string(height) + "\n255\n";
  pgm.append(grey.begin(), grey.end());
  return pgm;
}

RosMapMetadata Metadata(
    RosMapMetadata::Mode mode = RosMapMetadata::Mode::kTrinary) {
  RosMapMetadata metadata;
  metadata.resolution = 0.05;
  metadata.origin = GridOrigin{1.5, -2.0, 0.25};
  metadata.mode = mode;
  return metadata;
}

fs::path TempPath(const std::string& name) {
  return fs::path(::testing::TempDir()) / name;
}

TEST(GridFromOccupancyPngTest, MapServerRulesAndBottomRowFirst) {
  // 3x2, top row: black (occupied), white (free), 205 grey (unknown);
  // bottom row: red (mean 85: p = 0.667, occupied), (100,200,254) (mean 184:
  // p = 0.278, unknown), near-white (250: free).
  const std::string png =
      RgbaPng(3, 2, {0,   0, 0, 255, 255, 255, 255, 255, 205, 205, 205, 255,
                     255, 0, 0, 255, 100, 200, 254, 255, 250, 250, 250, 255});
  const absl::StatusOr<Grid> grid =
      GridFromOccupancyPng(png, Metadata(), "m.png");
  ASSERT_TRUE(grid.ok()) << grid.status();
  ASSERT_EQ(grid->width(), 3);
  ASSERT_EQ(grid->height(), 2);
  EXPECT_EQ(grid->cells(),
            (std::vector<uint8_t>{kLethalCost, kUnknownCost, kFreeCost,
                                  kLethalCost, kFreeCost, kUnknownCost}));
  EXPECT_DOUBLE_EQ(grid->resolution(), 0.05);
  EXPECT_DOUBLE_EQ(grid->origin().x, 1.5);
  EXPECT_DOUBLE_EQ(grid->origin().y, -2.0);
  EXPECT_DOUBLE_EQ(grid->origin().yaw, 0.25);

  RosMapMetadata negated = Metadata();
  negated.negate = true;
  const Grid inverted = *GridFromOccupancyPng(png, negated, "m.png");
  EXPECT_EQ(inverted.cost(0, 1), kFreeCost);    // black
  EXPECT_EQ(inverted.cost(1, 1), kLethalCost);  // white
}

TEST(GridFromOccupancyPngTest, EveryGreyLevelGivesThePgmCells) {
  // 256 pixels, one per grey level, in every mode: the PNG path and core's
  // PGM reader must agree cell for cell.
  std::vector<uint8_t> grey(256), rgba;
  for (int v = 0; v < 256; ++v) {
    grey[v] = static_cast<uint8_t>(v);
    rgba.insert(rgba.end(), {grey[v], grey[v], grey[v], 255});
  }
  const std::string png = RgbaPng(16, 16, rgba);
  const std::string pgm = GreyPgm(16, 16, grey);
  for (const auto mode :
       {RosMapMetadata::Mode::kTrinary, RosMapMetadata::Mode::kScale,
        RosMapMetadata::Mode::kRaw}) {
    for (const bool negate : {false, true}) {
      RosMapMetadata metadata = Metadata(mode);
      metadata.negate = negate;
      const absl::StatusOr<Grid> from_png =
          GridFromOccupancyPng(png, metadata, "g.png");
      const absl::StatusOr<Grid> from_pgm = ParseRosMap(metadata, pgm, "g.pgm");
      ASSERT_TRUE(from_png.ok()) << from_png.status();
      ASSERT_TRUE(from_pgm.ok()) << from_pgm.status();
      EXPECT_EQ(from_png->cells(), from_pgm->cells())
          << "mode " << static_cast<int>(mode) << " negate " << negate;
    }
  }
}

TEST(GridFromOccupancyPngTest,
     TransparentPixelsAreUnknownOnlyBetweenThresholdsInScaleMode) {
  // Transparent: white, black, mid grey; then an opaque mid grey.
  const std::string png = RgbaPng(
      4, 1,
      {255, 255, 255, 0, 0, 0, 0, 0, 128, 128, 128, 0, 128, 128, 128, 255});
  const Grid scale = *GridFromOccupancyPng(
      png, Metadata(RosMapMetadata::Mode::kScale), "t.png");
  EXPECT_EQ(scale.cost(0, 0), kFreeCost);
  EXPECT_EQ(scale.cost(1, 0), kLethalCost);
  EXPECT_EQ(scale.cost(2, 0), kUnknownCost);
  EXPECT_GT(scale.cost(3, 0), kFreeCost);
  EXPECT_LE(scale.cost(3, 0), kMaxTraversableCost);
  const Grid trinary = *GridFromOccupancyPng(png, Metadata(), "t.png");
  EXPECT_EQ(trinary.cells(),
            (std::vector<uint8_t>{kFreeCost, kLethalCost, kUnknownCost,
                                  kUnknownCost}));
}

// Writes a 16-bit greyscale PNG without gAMA/sRGB chunks (as image editors
// and map tools do) through libpng's classic API.
std::string Grey16Png(const std::vector<uint16_t>& samples) {
  const fs::path path = TempPath("grey16.png");
  FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) return "";
  png_structp png =
      png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(file);
    return "";
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(samples.size()), 1, 16,
               PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  std::vector<uint8_t> row;
  for (uint16_t s : samples)
    row.insert(row.end(), {uint8_t(s >> 8), uint8_t(s & 0xff)});
  png_write_row(png, row.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
  return *ReadFileToString(path.string());
}

TEST(GridFromOccupancyPngTest, SixteenBitSamplesAreScaledNotGammaConverted) {
  // 20000/65535 is grey 78 (p = 0.69: occupied); read as linear light and
  // gamma-encoded it would become about 151 (p = 0.41: unknown).
  const std::string png = Grey16Png({20000, 65535, 0});
  ASSERT_FALSE(png.empty());
  const absl::StatusOr<Grid> grid =
      GridFromOccupancyPng(png, Metadata(), "g16.png");
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->cells(),
            (std::vector<uint8_t>{kLethalCost, kFreeCost, kLethalCost}));
}

TEST(GridFromOccupancyPngTest, BadDataAndTooManyPixelsNameTheFile) {
  const absl::Status bad =
      GridFromOccupancyPng("P5 nope", Metadata(), "bad.png").status();
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.message().find("bad.png"), absl::string_view::npos) << bad;
  const std::string png = RgbaPng(4, 4, std::vector<uint8_t>(64, 255));
  EXPECT_EQ(
      GridFromOccupancyPng(png, Metadata(), "big.png", 15).status().code(),
      absl::StatusCode::kInvalidArgument);
  RosMapMetadata inverted = Metadata();
  inverted.free_thresh = 0.9;
  EXPECT_EQ(GridFromOccupancyPng(png, inverted, "t.png").status().code(),
            absl::StatusCode::kInvalidArgument);
}

// 5x2: row 0 free, 1, 252, inscribed, lethal; row 1 unknown then free.
Grid EveryKindGrid() {
  Grid grid = *Grid::FromCells(
      5, 2, {0, 1, 252, kInscribedCost, kLethalCost, kUnknownCost, 0, 0, 0, 0});
  grid.set_resolution(0.1);
  grid.set_origin(GridOrigin{-3.0, -2.0, 0.0});
  return grid;
}

TEST(ExportTest, MovingAiTextAndItsLosses) {
  ExportLoss loss;
  const std::string text = ToMovingAiText(EveryKindGrid(), &loss);
  EXPECT_EQ(text,
            "type octile\nheight 2\nwidth 5\nmap\n"
            ".SS@@\n"
            "O....\n");
  EXPECT_EQ(loss.weighted, 2);
  EXPECT_EQ(loss.inscribed, 1);
  EXPECT_EQ(loss.unknown, 1);
  const Grid back = *ParseMovingAiMap(text, "export.map");
  EXPECT_EQ(back.cells(),
            (std::vector<uint8_t>{0, 0, 0, kLethalCost, kLethalCost,
                                  kLethalCost, 0, 0, 0, 0}));
}

TEST(ExportTest, RosMapFilesReadBackWithMapServerRules) {
  ExportLoss loss;
  const RosMapFiles files =
      ToRosMapFiles(EveryKindGrid(), "every kind.pgm", &loss);
  EXPECT_EQ(loss.weighted, 2);
  EXPECT_EQ(loss.inscribed, 1);
  EXPECT_EQ(loss.unknown, 0);
  EXPECT_EQ(
      files.yaml,
      "image: every kind.pgm\nresolution: 0.1\norigin: [-3, -2, 0]\nnegate: 0\n"
      "occupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n");
  // Top image row is grid row 1.
  EXPECT_EQ(
      files.pgm,
      std::string("P5\n5 2\n255\n") +
          std::string({char(205), char(254), char(254), char(254), char(254),
                       char(254), char(254), char(254), char(0), char(0)}));
  const RosMapMetadata metadata = *ParseRosMapYaml(files.yaml, "every.yaml");
  EXPECT_EQ(metadata.image, "every kind.pgm");
  EXPECT_EQ(metadata.mode, RosMapMetadata::Mode::kTrinary);
  const Grid back = *ParseRosMap(metadata, files.pgm, "every.pgm");
  EXPECT_EQ(back.cells(),
            (std::vector<uint8_t>{0, 0, 0, kLethalCost, kLethalCost,
                                  kUnknownCost, 0, 0, 0, 0}));
  EXPECT_DOUBLE_EQ(back.resolution(), 0.1);
  EXPECT_DOUBLE_EQ(back.origin().x, -3.0);
}

TEST(ExportTest, UnknownExtensionIsRefused) {
  const absl::Status status =
      ExportMapFile(EveryKindGrid(), TempPath("x.png").string()).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("x.png"), absl::string_view::npos) << status;
}

// What a cost reads back as from each format.
uint8_t ThroughMovingAi(uint8_t cost) {
  return cost <= kMaxTraversableCost ? kFreeCost : kLethalCost;
}
uint8_t ThroughTrinary(uint8_t cost) {
  if (cost <= kMaxTraversableCost) return kFreeCost;
  return cost == kUnknownCost ? kUnknownCost : kLethalCost;
}

TEST(RoundTripTest, BundledMapsExportAndReadBackTheSameCells) {
  for (const char* name : {"maps/arena2.map", "maps/wavefront16.map",
                           "maps/dstar_example.map", "maps/warehouse.yaml",
                           "maps/depot.yaml"}) {
    SCOPED_TRACE(name);
    const absl::StatusOr<Grid> original = ReadMapFile(name);
    ASSERT_TRUE(original.ok()) << original.status();
    for (const char* extension : {".map", ".yaml"}) {
      SCOPED_TRACE(extension);
      const std::string path =
          TempPath(std::string("round_trip") + extension).string();
      ASSERT_TRUE(ExportMapFile(*original, path).ok());
      const absl::StatusOr<Grid> back = ReadMapFile(path);
      ASSERT_TRUE(back.ok()) << back.status();
      ASSERT_EQ(back->width(), original->width());
      ASSERT_EQ(back->height(), original->height());
      const bool yaml = std::string(extension) == ".yaml";
      std::vector<uint8_t> expected = original->cells();
      for (uint8_t& cost : expected)
        cost = yaml ? ThroughTrinary(cost) : ThroughMovingAi(cost);
      EXPECT_EQ(back->cells(), expected);
      if (yaml) {
        EXPECT_DOUBLE_EQ(back->resolution(), original->resolution());
        EXPECT_DOUBLE_EQ(back->origin().x, original->origin().x);
        EXPECT_DOUBLE_EQ(back->origin().y, original->origin().y);
        // Free, lethal and unknown are the whole representable subset: the
        // bundled maps hold nothing else and come back unchanged.
        EXPECT_EQ(back->cells(), original->cells());
      }
    }
  }
}

TEST(SetImportSourceTest, EachKindFillsTheRequest) {
  v1::CreateMapRequest request;
  ASSERT_EQ(
      *SetImportSource("maps/wavefront16.map", PngImportOptions{}, &request),
      ImportKind::kMovingAi);
  EXPECT_TRUE(request.has_movingai_text());

  request.Clear();
  ASSERT_EQ(
      *SetImportSource("maps/warehouse.yaml", PngImportOptions{}, &request),
      ImportKind::kRosYaml);
  EXPECT_TRUE(request.has_ros_map());

  // A PNG alone: cells decoded here, the options' resolution.
  const fs::path dir = TempPath("import");
  fs::create_directories(dir);
  const std::string png = RgbaPng(2, 1, {0, 0, 0, 255, 255, 255, 255, 255});
  {
    FILE* f = std::fopen((dir / "room.png").c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(png.data(), 1, png.size(), f);
    std::fclose(f);
  }
  PngImportOptions options;
  options.resolution = 0.25;
  request.Clear();
  ASSERT_EQ(*SetImportSource((dir / "room.png").string(), options, &request),
            ImportKind::kPng);
  ASSERT_TRUE(request.has_raw());
  EXPECT_EQ(request.raw().width(), 2);
  EXPECT_EQ(request.raw().cells(),
            std::string({char(kLethalCost), char(kFreeCost)}));
  EXPECT_DOUBLE_EQ(request.resolution(), 0.25);

  // A YAML naming the PNG: its own resolution and origin.
  {
    FILE* f = std::fopen((dir / "room.yaml").c_str(), "wb");
    ASSERT_NE(f, nullptr);
    const std::string yaml =
        "image: room.png\nresolution: 0.5\norigin: [2.0, 3.0, 0.0]\nnegate: "
        "1\n";
    std::fwrite(yaml.data(), 1, yaml.size(), f);
    std::fclose(f);
  }
  request.Clear();
  ASSERT_EQ(*SetImportSource((dir / "room.yaml").string(), PngImportOptions{},
                             &request),
            ImportKind::kRosYamlPng);
  EXPECT_EQ(request.raw().cells(),
            std::string({char(kFreeCost), char(kLethalCost)}));
  EXPECT_DOUBLE_EQ(request.resolution(), 0.5);
  EXPECT_DOUBLE_EQ(request.origin().x(), 2.0);
  EXPECT_DOUBLE_EQ(request.origin().y(), 3.0);

  EXPECT_EQ(SetImportSource("maps/x.bmp", PngImportOptions{}, &request)
                .status()
                .code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(SetImportSource((dir / "missing.png").string(), PngImportOptions{},
                            &request)
                .status()
                .code(),
            absl::StatusCode::kNotFound);
}

}  // namespace
}  // namespace pathd::pathctl
