// pathctl render's drawing: colours of known cells, the path, markers and
// expanded cells in the RGB image, the text form, size limits, and PNG files
// read back with libpng.
#include "client/pathctl/render.h"

#include <png.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "client/pathctl/png_io.h"
#include "gtest/gtest.h"

namespace pathd::pathctl {
namespace {

Rgb PixelAt(const Image& image, int32_t x, int32_t y) {
  const size_t i = (static_cast<size_t>(y) * image.width + x) * image.channels;
  return Rgb{image.pixels[i], image.pixels[i + 1], image.pixels[i + 2]};
}

int64_t CountPixels(const Image& image, Rgb colour) {
  int64_t count = 0;
  for (int32_t y = 0; y < image.height; ++y) {
    for (int32_t x = 0; x < image.width; ++x)
      count += PixelAt(image, x, y) == colour;
  }
  return count;
}

// 6x4: row 0 free, (1,1) lethal, (2,1) unknown, (3,1) cost 100, (4,1)
// inscribed; rows 2 and 3 free.
Grid SampleGrid() {
  Grid grid = *Grid::Create(6, 4);
  grid.set_cost(1, 1, kLethalCost);
  grid.set_cost(2, 1, kUnknownCost);
  grid.set_cost(3, 1, 100);
  grid.set_cost(4, 1, kInscribedCost);
  return grid;
}

TEST(CostColourTest, FreeWhiteLethalBlackUnknownTintedWeightedGreyByCost) {
  EXPECT_EQ(CostColour(kFreeCost), (Rgb{255, 255, 255}));
  EXPECT_EQ(CostColour(kLethalCost), (Rgb{0, 0, 0}));
  EXPECT_EQ(CostColour(kUnknownCost), kUnknownColour);
  EXPECT_NE(kUnknownColour.r, kUnknownColour.b) << "unknown must not be a grey";
  EXPECT_EQ(CostColour(1), (Rgb{230, 230, 230}));
  EXPECT_EQ(CostColour(kMaxTraversableCost), (Rgb{80, 80, 80}));
  for (int cost = 2; cost <= kMaxTraversableCost; ++cost) {
    const Rgb c = CostColour(static_cast<uint8_t>(cost));
    EXPECT_EQ(c.r, c.g);
    EXPECT_EQ(c.g, c.b);
    EXPECT_LE(c.r, CostColour(static_cast<uint8_t>(cost - 1)).r) << cost;
  }
  EXPECT_GT(CostColour(kInscribedCost).r, 0);
  EXPECT_LT(CostColour(kInscribedCost).r, CostColour(kMaxTraversableCost).r);
}

TEST(DefaultScaleTest, SmallMapsLargeLargeMapsOnePixel) {
  EXPECT_EQ(DefaultScale(5, 4), 16);
  EXPECT_EQ(DefaultScale(16, 16), 16);
  EXPECT_EQ(DefaultScale(281, 209), 3);
  EXPECT_EQ(DefaultScale(60, 40), 16);
  EXPECT_EQ(DefaultScale(1024, 10), 1);
  EXPECT_EQ(DefaultScale(4000, 4000), 1);
}

TEST(RenderImageTest, CellsHaveTheirCostColourAtTheScale) {
  const Grid grid = SampleGrid();
  RenderOptions options;
  options.scale = 10;
  const absl::StatusOr<Image> image = RenderImage(grid, PlanOverlay{}, options);
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->width, 60);
  EXPECT_EQ(image->height, 40);
  EXPECT_EQ(image->channels, 3);
  // Every pixel of a cell: its corners and centre.
  for (const auto& [x, y] :
       std::vector<std::pair<int, int>>{{0, 0}, {9, 9}, {5, 5}}) {
    EXPECT_EQ(PixelAt(*image, 10 + x, 10 + y), kLethalColour);
    EXPECT_EQ(PixelAt(*image, 20 + x, 10 + y), kUnknownColour);
    EXPECT_EQ(PixelAt(*image, 30 + x, 10 + y), CostColour(100));
    EXPECT_EQ(PixelAt(*image, 40 + x, 10 + y), kInscribedColour);
    EXPECT_EQ(PixelAt(*image, 0 + x, 0 + y), kFreeColour);
  }
  EXPECT_EQ(CountPixels(*image, kLethalColour), 100);
  EXPECT_EQ(CountPixels(*image, kFreeColour), 20 * 100);
}

TEST(DownsampleGridTest, EachBlockKeepsItsMostBlockingCost) {
  // 5 x 3 cells in blocks of 2 x 2: 3 x 2 blocks, the last ones partial.
  Grid grid = *Grid::Create(5, 3);
  grid.set_resolution(0.05);
  grid.set_cost(1, 1, kLethalCost);      // block (0, 0): lethal beats
  grid.set_cost(0, 0, kUnknownCost);     // unknown and
  grid.set_cost(1, 0, 200);              // a weighted cost
  grid.set_cost(2, 0, 7);                // block (1, 0): the higher weight
  grid.set_cost(3, 1, 90);
  grid.set_cost(4, 2, kInscribedCost);   // block (2, 1), partial
  const Grid small = DownsampleGrid(grid, 2);
  ASSERT_EQ(small.width(), 3);
  ASSERT_EQ(small.height(), 2);
  EXPECT_DOUBLE_EQ(small.resolution(), 0.1);
  EXPECT_EQ(small.cost(0, 0), kLethalCost);
  EXPECT_EQ(small.cost(1, 0), 90);
  EXPECT_EQ(small.cost(2, 0), kFreeCost);
  EXPECT_EQ(small.cost(0, 1), kFreeCost);
  EXPECT_EQ(small.cost(2, 1), kInscribedCost);
}

TEST(RenderImageTest, MapsOverTheLargestSideAreDrawnDownsampled) {
  // 9000 cells wide: blocks of 3 x 3 make a 3000-pixel picture; a one-cell
  // wall at x = 8000 stays drawn, and so does the path's start.
  Grid grid = *Grid::Create(9000, 4);
  for (int32_t y = 0; y < 4; ++y) grid.set_cost(8000, y, kLethalCost);
  PlanOverlay overlay;
  overlay.start = Cell{30, 1};
  const absl::StatusOr<Image> image = RenderImage(grid, overlay, RenderOptions{});
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->width, 3000);
  EXPECT_EQ(image->height, 2);
  EXPECT_EQ(PixelAt(*image, 8000 / 3, 0), kLethalColour);
  EXPECT_EQ(PixelAt(*image, 8000 / 3, 1), kLethalColour);
  EXPECT_EQ(PixelAt(*image, 100, 0), kFreeColour);
  EXPECT_EQ(PixelAt(*image, 10, 0), kStartColour);
  // An explicit scale is not downsampled: 9000 x 4 at 1 pixel per cell.
  RenderOptions one;
  one.scale = 1;
  EXPECT_EQ(RenderImage(grid, PlanOverlay{}, one)->width, 9000);
}

TEST(RenderImageTest, YUpDrawsRowZeroAtTheBottom) {
  Grid grid = *Grid::Create(3, 2);
  grid.set_cost(0, 0, kLethalCost);
  RenderOptions options;
  options.scale = 4;
  options.y_up = true;
  const Image image = *RenderImage(grid, PlanOverlay{}, options);
  EXPECT_EQ(PixelAt(image, 0, 7), kLethalColour);  // bottom-left
  EXPECT_EQ(PixelAt(image, 0, 0), kFreeColour);
  options.y_up = false;
  EXPECT_EQ(PixelAt(*RenderImage(grid, PlanOverlay{}, options), 0, 0),
            kLethalColour);
}

TEST(RenderImageTest, PathMarkersAndExpandedCellsAreDrawn) {
  const Grid grid = SampleGrid();
  PlanOverlay overlay;
  // Along row 3 from (0,3) to (5,3), then up to (5,0).
  overlay.path = {{0, 3}, {1, 3}, {2, 3}, {3, 3}, {4, 3},
                  {5, 3}, {5, 2}, {5, 1}, {5, 0}};
  overlay.start = Cell{0, 3};
  overlay.goal = Cell{5, 0};
  overlay.expanded = {{0, 2}, {1, 2}, {3, 1}};
  RenderOptions options;
  options.scale = 12;
  const Image image = *RenderImage(grid, overlay, options);
  // Centres: the path between the markers, the markers at the ends.
  EXPECT_EQ(PixelAt(image, 2 * 12 + 6, 3 * 12 + 6), kPathColour);
  EXPECT_EQ(PixelAt(image, 5 * 12 + 6, 2 * 12 + 6), kPathColour);
  EXPECT_EQ(PixelAt(image, 0 * 12 + 6, 3 * 12 + 6), kStartColour);
  EXPECT_EQ(PixelAt(image, 5 * 12 + 6, 0 * 12 + 6), kGoalColour);
  // The path is narrower than a cell: its cells' corners keep their colour.
  EXPECT_EQ(PixelAt(image, 2 * 12, 3 * 12), kFreeColour);
  // Expanded cells: the cost colour half-way to the tint.
  const Rgb free_expanded = PixelAt(image, 0, 2 * 12);
  EXPECT_EQ(free_expanded, (Rgb{255, 213, 128}));
  const Rgb weighted_expanded = PixelAt(image, 3 * 12, 12);
  const Rgb weighted = CostColour(100);
  EXPECT_EQ(weighted_expanded.r, (weighted.r + kExpandedTint.r + 1) / 2);
  EXPECT_EQ(weighted_expanded.b, (weighted.b + kExpandedTint.b + 1) / 2);
  // Unexpanded, unvisited cells are untouched.
  EXPECT_EQ(PixelAt(image, 3 * 12, 2 * 12 + 11), kFreeColour);
  // The path: a 5-pixel-wide (scale 12: half width 2) line of 5.5 cells plus
  // 3 cells; the markers cover its ends.
  EXPECT_GT(CountPixels(image, kPathColour), 5 * 60);
}

TEST(RenderImageTest, AnyAnglePathIsAStraightLineBetweenVertices) {
  const Grid grid = *Grid::Create(10, 4);
  PlanOverlay overlay;
  overlay.path = {{0, 0}, {9, 3}};
  RenderOptions options;
  options.scale = 1;
  const Image image = *RenderImage(grid, overlay, options);
  // Bresenham from (0,0) to (9,3): one pixel per column.
  EXPECT_EQ(CountPixels(image, kPathColour), 10);
  for (int x = 0; x < 10; ++x) {
    int in_column = 0;
    for (int y = 0; y < 4; ++y)
      in_column += PixelAt(image, x, y) == kPathColour;
    EXPECT_EQ(in_column, 1) << "column " << x;
  }
  EXPECT_EQ(PixelAt(image, 9, 3), kPathColour);
}

TEST(RenderImageTest, MarkersStayVisibleAtOnePixelPerCell) {
  const Grid grid = *Grid::Create(40, 40);
  PlanOverlay overlay;
  overlay.start = Cell{20, 20};
  RenderOptions options;
  options.scale = 1;
  const Image image = *RenderImage(grid, overlay, options);
  EXPECT_GE(CountPixels(image, kStartColour), 25);
  EXPECT_EQ(PixelAt(image, 20, 20), kStartColour);
}

TEST(RenderImageTest, OverlayCellsOutsideTheGridAreSkipped) {
  const Grid grid = *Grid::Create(3, 3);
  PlanOverlay overlay;
  overlay.path = {{-1, 0}, {0, 0}, {1, 1}, {7, 7}};
  overlay.expanded = {{5, 5}, {-3, 0}};
  overlay.goal = Cell{3, 0};
  RenderOptions options;
  options.scale = 2;
  const absl::StatusOr<Image> image = RenderImage(grid, overlay, options);
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(CountPixels(*image, kGoalColour), 0);
  EXPECT_GT(CountPixels(*image, kPathColour), 0);  // the (0,0)-(1,1) segment
}

TEST(RenderImageTest, RejectsBadScalesAndHugePictures) {
  const Grid grid = *Grid::Create(10, 10);
  RenderOptions options;
  options.scale = kMaxScale + 1;
  EXPECT_EQ(RenderImage(grid, PlanOverlay{}, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  options.scale = -1;
  EXPECT_EQ(RenderImage(grid, PlanOverlay{}, options).status().code(),
            absl::StatusCode::kInvalidArgument);
  const Grid big = *Grid::Create(2048, 2048);
  options.scale = 3;  // 6144 x 6144 pixels
  const absl::Status status = RenderImage(big, PlanOverlay{}, options).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("use a smaller --scale"),
            absl::string_view::npos)
      << status;
  options.scale = 2;  // 4096 x 4096 = 2^24 pixels
  EXPECT_TRUE(RenderImage(big, PlanOverlay{}, options).ok());
}

TEST(RenderTextTest, GlyphsForCostsExpansionsPathAndMarkers) {
  const Grid grid = SampleGrid();
  PlanOverlay overlay;
  overlay.path = {{0, 3}, {3, 3}, {5, 1}};  // any-angle vertices
  overlay.start = Cell{0, 3};
  overlay.goal = Cell{5, 1};
  overlay.expanded = {{0, 0}, {1, 0}, {3, 3}};
  const absl::StatusOr<std::string> text =
      RenderText(grid, overlay, RenderOptions{});
  ASSERT_TRUE(text.ok()) << text.status();
  EXPECT_EQ(*text,
            "oo....\n"
            ".#?4#G\n"
            "....*.\n"
            "S***..\n");
  RenderOptions up;
  up.y_up = true;
  EXPECT_EQ(*RenderText(grid, overlay, up),
            "S***..\n"
            "....*.\n"
            ".#?4#G\n"
            "oo....\n");
}

TEST(RenderTextTest, RefusesLargeMapsSuggestingAPng) {
  const Grid grid = *Grid::Create(kMaxTextWidth + 1, 3);
  const absl::Status status =
      RenderText(grid, PlanOverlay{}, RenderOptions{}).status();
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(status.message().find("PNG"), absl::string_view::npos) << status;
  EXPECT_TRUE(RenderText(*Grid::Create(kMaxTextWidth, kMaxTextHeight),
                         PlanOverlay{}, RenderOptions{})
                  .ok());
  EXPECT_FALSE(RenderText(*Grid::Create(3, kMaxTextHeight + 1), PlanOverlay{},
                          RenderOptions{})
                   .ok());
}

TEST(PngTest, RenderedPictureReadsBackWithLibpng) {
  const Grid grid = SampleGrid();
  PlanOverlay overlay;
  overlay.path = {{0, 3}, {5, 3}};
  overlay.start = Cell{0, 3};
  RenderOptions options;
  options.scale = 5;
  const Image image = *RenderImage(grid, overlay, options);
  const std::string path =
      (std::filesystem::path(::testing::TempDir()) / "render_test.png")
          .string();
  ASSERT_TRUE(WritePngFile(image, path).ok());

  // libpng itself, not our decoder, reads the file back.
  png_image png;
  std::memset(&png, 0, sizeof(png));
  png.version = PNG_IMAGE_VERSION;
  ASSERT_TRUE(png_image_begin_read_from_file(&png, path.c_str()))
      << png.message;
  EXPECT_EQ(png.width, 30u);
  EXPECT_EQ(png.height, 20u);
  png.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> pixels(PNG_IMAGE_SIZE(png));
  ASSERT_TRUE(png_image_finish_read(&png, nullptr, pixels.data(), 0, nullptr))
      << png.message;
  EXPECT_EQ(pixels, image.pixels);

  const absl::StatusOr<Image> decoded =
      DecodePngRgba(*EncodePng(image), "memory", int64_t{1} << 20);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  ASSERT_EQ(decoded->channels, 4);
  for (int32_t y = 0; y < image.height; ++y) {
    for (int32_t x = 0; x < image.width; ++x) {
      ASSERT_EQ(PixelAt(*decoded, x, y), PixelAt(image, x, y)) << x << "," << y;
      ASSERT_EQ(
          decoded->pixels[(static_cast<size_t>(y) * image.width + x) * 4 + 3],
          255);
    }
  }
  std::filesystem::remove(path);
}

TEST(PngTest, DecodeErrorsNameTheSource) {
  const absl::Status bad = DecodePngRgba("not a png", "x.png", 100).status();
  EXPECT_EQ(bad.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(bad.message().find("x.png"), absl::string_view::npos) << bad;
  Image image;
  image.width = 20;
  image.height = 10;
  image.pixels.assign(20 * 10 * 3, 0);
  const absl::Status big =
      DecodePngRgba(*EncodePng(image), "big.png", 199).status();
  EXPECT_EQ(big.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(big.message().find("exceeds the limit of 199"),
            absl::string_view::npos)
      << big;
  EXPECT_TRUE(DecodePngRgba(*EncodePng(image), "ok.png", 200).ok());
  image.pixels.pop_back();
  EXPECT_EQ(EncodePng(image).status().code(),
            absl::StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace pathd::pathctl
