// A robot's shape and the collision test of an oriented robot against a grid:
// the footprint (a circle or a simple polygon in the body frame, cells) and
// FootprintChecker, which precomputes for a fixed number of headings the
// cells the footprint may cover and answers "does the robot at this pose
// touch anything it may not?" by reading those cells, after two shortcuts on
// the obstacle distance: farther than the circumscribed radius from every
// obstacle is free, nearer than the inscribed radius is a collision.
//
// Configuration space with rotation, as the lecture "Planning in C-space"
// presents it ("Example of C_obs for a Robot with Rotation"): the obstacle
// region of a rotating robot is a stack of slices, one per heading; the masks
// are those slices, made conservative so a pose the checker calls free is
// free for the exact footprint at any heading of its bin and any position in
// its sub-cell. Nav2's footprint collision checker and Smac planners'
// precomputed rotated footprints are what users compare with.
#ifndef PATHD_CORE_KINEMATICS_FOOTPRINT_H_
#define PATHD_CORE_KINEMATICS_FOOTPRINT_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/kinematics/pose.h"
#include "core/map/grid.h"

namespace pathd {

// A robot's outline in its body frame (x forward, y left), in cells: a circle
// about the origin, or a simple polygon (not self-intersecting, non-zero area;
// kept counter-clockwise; it need not be convex nor contain the origin). A
// value type.
class Footprint {
 public:
  // A circle of radius > 0. INVALID_ARGUMENT naming the footprint radius when
  // it is not finite or not positive.
  static absl::StatusOr<Footprint> Circle(double radius_cells);
  // A polygon of 3 to kMaxVertices finite vertices, in order around the
  // outline (either direction). INVALID_ARGUMENT naming the problem (too few
  // or too many vertices, a vertex that is not finite, repeated vertices,
  // crossing edges, zero area).
  static absl::StatusOr<Footprint> Polygon(std::vector<CellPoint> vertices);

  static constexpr size_t kMaxVertices = 64;

  bool is_circle() const { return vertices_.empty(); }
  // The circle's radius; 0 for a polygon.
  double circle_radius() const { return circle_radius_; }
  // The polygon's vertices, counter-clockwise; empty for a circle.
  const std::vector<CellPoint>& vertices() const { return vertices_; }
  // The largest radius of a disc about the origin inside the footprint (0
  // when the origin is outside or on the outline).
  double inscribed_radius() const { return inscribed_radius_; }
  // The smallest radius of a disc about the origin that contains it.
  double circumscribed_radius() const { return circumscribed_radius_; }

  // The same shape with every length multiplied by `factor` > 0 (metres to
  // cells: 1 / resolution).
  Footprint Scaled(double factor) const;
  // The polygon at `pose` in cell coordinates (rotated by pose.yaw, then
  // moved to the position); empty for a circle.
  std::vector<CellPoint> At(const Pose& pose) const;
  // "circle r=0.3" or "polygon [[0.3,0.2],...]", for messages.
  std::string DebugString() const;

 private:
  double circle_radius_ = 0.0;
  std::vector<CellPoint> vertices_;
  double inscribed_radius_ = 0.0;
  double circumscribed_radius_ = 0.0;
};

// Whether a cell may be under the robot's footprint: the cost rule of
// Traversable (core/map/cost_model.h). Lethal, inscribed and (unless
// unknown_is_free) unknown cells are obstacles; the map's outside is one too.
//
// Per-grid distance to the nearest obstacle, for the checker's shortcuts:
// the Euclidean distance, cells, from each cell's centre to the nearest
// obstacle cell's centre or the ring just outside the map; row-major. O(cells)
// (core/map/euclidean_distance.h).
std::vector<float> ObstacleDistanceField(const Grid& grid, bool unknown_is_free);

struct FootprintCheckerOptions {
  // Heading bins over the full turn; a pose uses the bin nearest its yaw.
  int32_t headings = 72;
  // Each cell is divided into subcells x subcells positions; a pose uses the
  // mask of its position's subcell. More subcells make the masks tighter
  // (the over-approximation is about 1/subcells of a cell on each side).
  int32_t subcells = 2;
  // Extra clearance every mask keeps around the footprint, cells: what a
  // caller that checks poses a distance apart along a motion needs so the
  // motion between them is covered too.
  double margin_cells = 0.0;
};

// Precomputed masks of one footprint. Immutable once created; thread-safe.
//
// Guarantee: when Collides() is false, the exact footprint placed at any
// position within the pose's subcell, rotated to any heading within the
// pose's heading bin, and grown by margin_cells, overlaps no obstacle cell
// (touching a cell's boundary counts as overlapping) and stays on the map.
class FootprintChecker {
 public:
  // INVALID_ARGUMENT naming the option when headings is not in 1..3600,
  // subcells not in 1..8, or the margin negative or not finite.
  static absl::StatusOr<FootprintChecker> Create(const Footprint& footprint,
                                                 const FootprintCheckerOptions& options = {});

  const Footprint& footprint() const { return footprint_; }
  const FootprintCheckerOptions& options() const { return options_; }
  int32_t headings() const { return options_.headings; }
  // The bin nearest `yaw`, in 0..headings-1 (bin i is centred on i * 2pi /
  // headings).
  int32_t HeadingIndex(double yaw) const;
  double HeadingAngle(int32_t index) const;

  // True when the robot at `pose` may touch an obstacle of `grid` (see the
  // class comment). `distance`, when not null, is ObstacleDistanceField of
  // the same grid and rule and enables the shortcuts.
  bool Collides(const Grid& grid, const Pose& pose, bool unknown_is_free,
                const float* distance = nullptr) const;
  // The exact test, without masks: true when the footprint at exactly
  // `pose`, grown by margin_cells, overlaps or touches an obstacle cell or
  // leaves the map. O(cells under the footprint x vertices); for validating
  // given poses (IsPathValid), where the masks' conservative bins and
  // subcells would call a path that passes 2 cm from a wall invalid.
  bool CollidesExactly(const Grid& grid, const Pose& pose, bool unknown_is_free) const;
  // The highest cost of the cells the pose's mask covers, 255 when it
  // leaves the map (for planners that weigh cost under the whole robot).
  uint8_t MaxCost(const Grid& grid, const Pose& pose) const;

  // The cells of the mask of `pose` on the grid (may be off the grid), for
  // renders and tests.
  std::vector<Cell> CoveredCells(const Pose& pose) const;
  // Cells in the largest mask.
  size_t max_mask_cells() const { return max_mask_cells_; }
  size_t bytes() const;

 private:
  // One row of a mask: cells (dx_begin .. dx_end - 1, dy) relative to the
  // pose's cell.
  struct Run {
    int32_t dy;
    int32_t dx_begin;
    int32_t dx_end;
  };
  struct Mask {
    std::vector<Run> runs;
    // Bounding box of the mask, relative offsets (for the off-map test).
    int32_t min_dx = 0, max_dx = 0, min_dy = 0, max_dy = 0;
  };

  FootprintChecker(Footprint footprint, FootprintCheckerOptions options)
      : footprint_(std::move(footprint)), options_(options) {}
  void BuildMasks();
  const Mask& MaskOf(const Pose& pose) const;

  Footprint footprint_;
  FootprintCheckerOptions options_;
  // masks_[(heading * subcells + sy) * subcells + sx]
  std::vector<Mask> masks_;
  size_t max_mask_cells_ = 0;
  // Shortcut bounds on the obstacle distance of the pose's cell.
  double free_beyond_ = 0.0;
  double hit_within_ = 0.0;
};

}  // namespace pathd

#endif  // PATHD_CORE_KINEMATICS_FOOTPRINT_H_
