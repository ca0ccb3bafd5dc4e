// Pictures of maps and plans for `pathctl render`: a cost grid with an
// optional path, start, goal and expanded cells drawn as an RGB image (for
// PNG) or as text (for a terminal). Pure functions of their inputs, so tests
// check pixels and characters without a server.
#ifndef PATHD_CLIENT_PATHCTL_RENDER_H_
#define PATHD_CLIENT_PATHCTL_RENDER_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "client/pathctl/png_io.h"
#include "core/map/grid.h"

namespace pathd::pathctl {

struct Rgb {
  uint8_t r = 0;
  uint8_t g = 0;
  uint8_t b = 0;
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

// Colours of the picture; docs/pathctl.md ("Pictures of plans") describes them.
inline constexpr Rgb kFreeColour = {255, 255, 255};
inline constexpr Rgb kLethalColour = {0, 0, 0};
inline constexpr Rgb kInscribedColour = {48, 48, 48};
inline constexpr Rgb kUnknownColour = {150, 162, 190};  // blue-grey
inline constexpr Rgb kPathColour = {230, 25, 25};       // red
inline constexpr Rgb kStartColour = {0, 170, 60};       // green
inline constexpr Rgb kGoalColour = {30, 90, 255};       // blue
inline constexpr Rgb kMarkerOutlineColour = {0, 0, 0};
// Expanded cells are their cost's colour blended half-way towards this.
inline constexpr Rgb kExpandedTint = {255, 170, 0};  // amber
// Planner structures (mesh, visibility graph, Voronoi, decomposition).
inline constexpr Rgb kStructureColour = {150, 60, 200};  // purple
// The robot's footprint along a path.
inline constexpr Rgb kFootprintColour = {0, 150, 170};  // teal

// Text glyphs drawn over pathctl's cell glyphs (CellGlyph).
inline constexpr char kPathGlyph = '*';
inline constexpr char kStartGlyph = 'S';
inline constexpr char kGoalGlyph = 'G';
inline constexpr char kExpandedGlyph = 'o';

// Largest map RenderText draws; beyond it a terminal wraps the lines.
inline constexpr int32_t kMaxTextWidth = 200;
inline constexpr int32_t kMaxTextHeight = 200;
// Largest picture RenderImage draws (width * height pixels, 96 MiB of RGB).
inline constexpr int64_t kMaxImagePixels = int64_t{1} << 25;
// Pixels per cell RenderImage accepts, and the longest side DefaultScale aims
// for.
inline constexpr int kMaxScale = 64;
inline constexpr int32_t kTargetImageSide = 1024;
// Longest side of a picture of a map drawn at the default scale: a larger
// map (a 16384² one) is drawn at one pixel per block of k x k cells, the
// smallest k that fits (DownsampleGrid).
inline constexpr int32_t kMaxImageSide = 4096;

// A simulated robot's run (pathctl simulate): where it drove, in cell
// coordinates, its disc's radius in cells and its goal.
struct SimTrail {
  std::vector<CellPoint> points;
  double radius = 0.0;
  CellPoint goal;
};

// What to draw over the map; every part is optional.
struct PlanOverlay {
  // Path vertices; consecutive ones are joined by straight lines, so grid
  // paths (neighbouring cells) and any-angle paths (turning points) both work.
  std::vector<Cell> path;
  // A geometric plan's exact polyline (cell coordinates), drawn instead of
  // `path` when not empty.
  std::vector<CellPoint> polyline;
  std::vector<Cell> expanded;
  // What a planner built from the map (core/geometry/structure.h), drawn in
  // thin lines and dots under the path.
  std::vector<std::array<CellPoint, 2>> structure_segments;
  std::vector<CellPoint> structure_points;
  // Closed outlines in cell coordinates (the robot's footprint at poses
  // along the path), drawn in one-pixel lines over the structure and under
  // the path.
  std::vector<std::vector<CellPoint>> outlines;
  std::optional<Cell> start;
  std::optional<Cell> goal;
  // A fleet plan's timed paths (PlanFleet), one colour per robot
  // (FleetColour): each path, its start as a disc and its goal as a ring.
  std::vector<std::vector<Cell>> fleet_paths;
  // Simulated robots, one colour each (FleetColour): the trail as a thin
  // line, the start as a disc, the robot's outline where it ended, and the
  // goal as a ring.
  std::vector<SimTrail> trails;
};

// Robot i's colour in a fleet picture: twelve well-separated hues, then
// they repeat.
Rgb FleetColour(size_t robot);

struct RenderOptions {
  // Pixels per cell, 1..kMaxScale; 0: DefaultScale.
  int scale = 0;
  // Draw row 0 at the bottom (world y up), as ROS map images show their map;
  // by default row 0 is the top row, as in a Moving AI file and in
  // `maps get --cells`.
  bool y_up = false;
};

// The colour of a cost byte: free white, weighted 1..252 from light grey
// (230) to dark grey (80), inscribed dark grey, lethal black, unknown
// blue-grey.
Rgb CostColour(uint8_t cost);

// The pixels per cell that make the longer side about kTargetImageSide
// pixels: 16 for tiny maps, 1 for maps of 1024 cells or more.
int DefaultScale(int32_t width, int32_t height);

// One cell per block of k x k cells of `grid` (the last blocks of a row or
// column may be partial), with the block's most blocking cost: lethal, then
// inscribed, then unknown, then the highest weighted cost, then free. So a
// one-cell wall never disappears from a downsampled picture. Resolution
// times k, same origin. Precondition: k >= 1.
Grid DownsampleGrid(const Grid& grid, int k);
// The same for an overlay: cells and points divided by k.
PlanOverlay DownsampleOverlay(const PlanOverlay& overlay, int k);

// Draws the grid, the expanded cells (tinted), the structure (one-pixel
// lines and dots), the path (lines through cell
// centres, about a third of a cell wide and at least 3 pixels from 3 pixels
// per cell on) and the start and goal (discs with a black outline, about a
// cell across and never less than 9 pixels). Overlay cells
// outside the grid are skipped. INVALID_ARGUMENT for a scale outside
// 0..kMaxScale or a picture above kMaxImagePixels (the message suggests a
// smaller --scale). With scale 0, a map longer than kMaxImageSide on a side
// is drawn downsampled (DownsampleGrid). Returns an RGB Image.
absl::StatusOr<Image> RenderImage(const Grid& grid, const PlanOverlay& overlay,
                                  const RenderOptions& options);

// The same as text: one line per row, CellGlyph per cell, overdrawn by
// kExpandedGlyph, then kPathGlyph along the path's lines, then kStartGlyph and
// kGoalGlyph; a fleet's robot i draws its path with the letter 'a' + i % 26
// and its start and goal with the capital. INVALID_ARGUMENT above kMaxTextWidth x kMaxTextHeight, saying
// to write a PNG instead.
absl::StatusOr<std::string> RenderText(const Grid& grid,
                                       const PlanOverlay& overlay,
                                       const RenderOptions& options);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_RENDER_H_
