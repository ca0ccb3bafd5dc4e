// A dynamic brushfire distance map and the generalized Voronoi diagram (GVD)
// on it, for the `voronoi` planner: Lau, Sprunk & Burgard, "Efficient
// grid-based spatial representations for robot navigation in dynamic
// environments", RAS 61(10), 2013. Each cell keeps its nearest obstacle
// cell; when cells change, a raise wave clears the cells whose nearest
// obstacle vanished and a lower wave spreads the obstacles that remain or
// appeared, so an update costs O(cells whose nearest obstacle changes), not
// O(map).
//
// The metric differs from the paper on purpose. The paper measures the
// Euclidean distance to the obstacle a cell inherits from a neighbour; that
// is not always the nearest obstacle (inherited sites are a known source of
// small errors), and then the state an update leaves depends on the history
// of updates. Here the distance is the octile distance (straight steps 1,
// diagonal steps sqrt(2)) between cell centres: a path metric of the
// 8-connected grid, so the nearest obstacle of a cell is always the nearest
// obstacle of a neighbour one step closer to it and inheriting is exact.
// Ties go to the obstacle with the smaller index, which inherits just as
// exactly. The field is therefore a function of the obstacle set alone: an
// update yields exactly what a fresh build would. Octile distance is at most
// 8.3% above the Euclidean one (1 <= octile / Euclidean <= 1.0824).
//
// The GVD cells: a free cell c lies on the diagram when a 4-neighbour n
// (free) has a nearest obstacle that is a different obstacle (the two are not
// 8-adjacent cells, the paper's test) and c is at least as close to the
// bisector of the two: d(c, site(n)) - d(c) <= d(n, site(c)) - d(n).
#ifndef PATHD_CORE_GEOMETRY_VORONOI_H_
#define PATHD_CORE_GEOMETRY_VORONOI_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "absl/types/span.h"
#include "core/map/grid.h"
#include "core/search/derived.h"

namespace pathd {

// Octile distance between cells as straight + diagonal * sqrt(2), compared
// exactly with integers.
struct OctileLength {
  int64_t straight = 0;
  int64_t diagonal = 0;

  static OctileLength Between(int64_t dx, int64_t dy);
  double value() const;
  // -1, 0, 1 as a is shorter than, equal to, longer than b.
  friend int Compare(const OctileLength& a, const OctileLength& b);
  friend OctileLength operator+(const OctileLength& a, const OctileLength& b) {
    return {a.straight + b.straight, a.diagonal + b.diagonal};
  }
};

// The distance map and GVD of one map version under one traversability rule.
// Blocked cells and the ring of cells around the map are obstacles. A value
// type, 5 bytes per cell; Update() mutates it, so a shared value is copied
// first (see VoronoiPlanner's advance).
class VoronoiField {
 public:
  // Cells are indexed with int32 over the grid and its border ring.
  static bool Fits(const Grid& grid) {
    return (static_cast<int64_t>(grid.width()) + 2) * (grid.height() + 2) <=
           int64_t{1} << 31;
  }

  // Precondition: Fits(grid).
  VoronoiField(const Grid& grid, bool unknown_is_free);
  // The same, or null when `stop` fired first: the brushfire is O(cells) but
  // takes seconds on the largest maps (about 2 s at 4096 x 4096), so it
  // polls `stop` every kPollCells cells and notes in it that it gave up.
  static std::shared_ptr<const VoronoiField> Build(const Grid& grid,
                                                   bool unknown_is_free,
                                                   DerivedStop& stop);
  static constexpr int32_t kPollCells = 1 << 16;

  // Re-reads `changed` cells from `grid` (the same size as the one built
  // from) and repairs distances and the diagram with the raise and lower
  // waves. Cells listed that did not change cost nothing beyond the read.
  void Update(const Grid& grid, absl::Span<const Cell> changed);

  int32_t width() const { return width_; }
  int32_t height() const { return height_; }
  bool unknown_is_free() const { return unknown_is_free_; }

  // Precondition for the accessors: c on the grid.
  bool Blocked(Cell c) const { return (flags_[Index(c)] & kBlockedBit) != 0; }
  // The nearest obstacle cell (ties: the first in row-major order over the
  // padded map); outside the grid for the border ring. c itself if blocked.
  Cell NearestObstacle(Cell c) const { return CellOf(site_[Index(c)]); }
  // Octile distance, cells, from c's centre to its nearest obstacle's.
  OctileLength Distance(Cell c) const;
  double Clearance(Cell c) const { return Distance(c).value(); }
  // c is a GVD cell.
  bool OnDiagram(Cell c) const { return (flags_[Index(c)] & kDiagramBit) != 0; }

  // Cells on the diagram.
  int64_t DiagramCells() const;
  size_t bytes() const {
    return site_.capacity() * sizeof(int32_t) + flags_.capacity();
  }

 private:
  static constexpr uint8_t kBlockedBit = 1;
  static constexpr uint8_t kDiagramBit = 2;
  static constexpr int32_t kCleared = -1;

  struct Entry {
    int32_t site;
    int32_t cell;
  };

  // Padded index (one ring of border cells around the grid).
  int32_t Index(Cell c) const { return (c.y + 1) * stride_ + c.x + 1; }
  Cell CellOf(int32_t index) const {
    return Cell{index % stride_ - 1, index / stride_ - 1};
  }
  bool BlockedAt(int32_t index) const {
    return (flags_[index] & kBlockedBit) != 0;
  }
  bool InPadded(int32_t x, int32_t y) const {
    return x >= -1 && y >= -1 && x <= width_ && y <= height_;
  }
  OctileLength Between(int32_t a, int32_t b) const;
  // Queues `cell` to spread its site, in the bucket of its distance.
  void Push(int32_t cell);
  // The sizes of `grid`, nothing filled in.
  VoronoiField(int32_t width, int32_t height, bool unknown_is_free);
  // Fills in the field of `grid`; false when `stop` (may be null) fired
  // first.
  bool Fill(const Grid& grid, DerivedStop* stop);
  // Spreads every queued site until nothing improves; appends each cell it
  // changes to `touched` when not null. False when `stop` (may be null)
  // fired first.
  bool Lower(std::vector<int32_t>* touched, DerivedStop* stop = nullptr);
  // The diagram bit of padded cell `index` from its and its 4-neighbours'
  // sites.
  void SetDiagramBit(int32_t index);

  int32_t width_ = 0;
  int32_t height_ = 0;
  int32_t stride_ = 0;
  bool unknown_is_free_ = false;
  std::vector<int32_t> site_;
  std::vector<uint8_t> flags_;
  // The waves' queue: buckets of distance [k, k + 1), so nearer cells go
  // first without a heap's log factor (the order within a bucket does not
  // matter for the result, see Lower()).
  std::vector<std::vector<Entry>> buckets_;
  size_t first_bucket_ = 0;
};

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_VORONOI_H_
