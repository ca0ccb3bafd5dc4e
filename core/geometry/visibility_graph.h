// The reduced ("tangent") visibility graph of a grid's free space, the
// obstacles of that free space numbered for Minimal Construct, and the
// result a geometric planner builds from an exact polyline. Shared by the
// visibility_graph, minimal_construct and euclidean_spm planners.
//
// Vertices are the bend corners of core/geometry/free_space.h (grid corners
// with exactly one blocked cell: the convex obstacle corners, the only points
// where a Euclidean shortest path bends). An edge joins two vertices whose
// segment is clear and tangent to the obstacle at both ends: a taut path
// wraps each corner it bends at with the obstacle inside the bend, so a
// segment whose line cuts into the blocked cell at an end is never part of a
// shortest path (Lozano-Pérez & Wesley 1979; LaValle, "Planning Algorithms",
// 6.2.4, the shortest-path roadmap). Keeping only those edges is exact for
// shortest paths and drops most pairs before their segment test.
#ifndef PATHD_CORE_GEOMETRY_VISIBILITY_GRAPH_H_
#define PATHD_CORE_GEOMETRY_VISIBILITY_GRAPH_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "absl/time/time.h"
#include "absl/types/span.h"
#include "core/geometry/free_space.h"
#include "core/map/grid.h"
#include "core/search/derived.h"
#include "core/search/plan_types.h"

namespace pathd {

// The blocked cell of a bend corner as a direction from the corner: qx, qy
// in {-1, +1}. Zero for points that are not bend corners (cell centres),
// which constrain no segment.
struct CornerQuadrant {
  int8_t qx = 0;
  int8_t qy = 0;
};

// The quadrant of the one blocked cell at `p`, or {0, 0} when `p` is not a
// bend corner of `space`.
CornerQuadrant QuadrantAt(const FreeSpace& space, LatticePoint p);

// The segment from `p` (with blocked quadrant `q`) towards `other` is tangent
// to the obstacle at `p`: its line does not enter the blocked cell on either
// side of `p`. Always true for q = {0, 0}.
inline bool Tangent(LatticePoint p, CornerQuadrant q, LatticePoint other) {
  const int64_t dx = other.x2 - p.x2;
  const int64_t dy = other.y2 - p.y2;
  const int sx = (dx > 0) - (dx < 0);
  const int sy = (dy > 0) - (dy < 0);
  return sx * q.qx * sy * q.qy <= 0;
}

// A shortest path may run prev -> p -> next, bending at `p` (blocked
// quadrant `q`): both segments are tangent at p and the turn wraps the
// blocked cell (it lies on the inner side of the turn), or the path runs
// straight on. Otherwise the corner could be cut, so no shortest path does
// this; searches use it to skip successors of a node given its parent.
// Always true for q = {0, 0}.
inline bool TautAt(LatticePoint prev, LatticePoint p, CornerQuadrant q,
                   LatticePoint next) {
  if (q.qx == 0) return true;
  if (!Tangent(p, q, prev) || !Tangent(p, q, next)) return false;
  const int64_t ax = p.x2 - prev.x2;
  const int64_t ay = p.y2 - prev.y2;
  const int64_t turn = ax * (next.y2 - p.y2) - ay * (next.x2 - p.x2);
  const int64_t side = ax * q.qy - ay * q.qx;
  return turn == 0 || (turn > 0) == (side > 0);
}

// The segment a-b meets the box [lo, hi] (lattice coordinates): its closed
// box when `open` is false, its open interior when true. Exact (Liang-Barsky
// with the parameter ranges compared as fractions).
bool SegmentMeetsBox(LatticePoint a, LatticePoint b, LatticePoint lo,
                     LatticePoint hi, bool open);

// The tangent visibility graph of one FreeSpace. Immutable once built, so one
// value is shared by every query on its map version. Thread-safe (const).
class VisibilityGraph {
 public:
  struct Edge {
    uint32_t to;
    double length;
  };

  // Tests every pair of bend corners: the two O(1) tangent tests first, the
  // exact segment test (O(cells crossed)) only for pairs that pass both.
  // O(V^2) pairs for V bend corners: minutes on a 512 x 512 map with 25%
  // random obstacles, so it polls `stop` once per vertex (every V pairs) and
  // returns null, noting so in `stop`, when it fired.
  static std::shared_ptr<const VisibilityGraph> Build(
      std::shared_ptr<const FreeSpace> space, DerivedStop& stop);
  // Never stops.
  static std::shared_ptr<const VisibilityGraph> Build(
      std::shared_ptr<const FreeSpace> space);
  // The graph of `space`, whose cells differ from previous.space()'s exactly
  // in `changed`: vertices whose corner kept its blocked cell keep their
  // edges, except pairs whose segment meets the bounding box of the changed
  // cells, which are tested again; new or changed vertices are tested
  // against all. Null (rebuild) past kMaxAdvanceCells changed cells. Equal to
  // Build(space). Polls `stop` as Build does: null when it fired too (and
  // `stop` notes it), so a caller that rebuilds after a null checks `stop`.
  static std::shared_ptr<const VisibilityGraph> Advance(
      const VisibilityGraph& previous, std::shared_ptr<const FreeSpace> space,
      absl::Span<const Cell> changed, DerivedStop& stop);
  // Never stops.
  static std::shared_ptr<const VisibilityGraph> Advance(
      const VisibilityGraph& previous, std::shared_ptr<const FreeSpace> space,
      absl::Span<const Cell> changed);
  static constexpr size_t kMaxAdvanceCells = 256;
  // Null (rebuild) too when the changed cells' bounding box covers more than
  // 1/kMaxAdvanceBoxShare of a map of at least kBoxRuleMinCells cells (on
  // smaller maps either is cheap, and the tests' random maps keep the
  // advance exercised).
  static constexpr int64_t kMaxAdvanceBoxShare = 64;
  static constexpr int64_t kBoxRuleMinCells = 256 * 256;

  const FreeSpace& space() const { return *space_; }
  size_t vertex_count() const { return vertices_.size(); }
  LatticePoint vertex(uint32_t v) const { return vertices_[v]; }
  CornerQuadrant quadrant(uint32_t v) const { return quadrants_[v]; }
  absl::Span<const Edge> EdgesOf(uint32_t v) const {
    return absl::MakeConstSpan(edges_.data() + offsets_[v],
                               offsets_[v + 1] - offsets_[v]);
  }
  // Undirected edges (each stored once per end).
  int64_t edge_count() const { return static_cast<int64_t>(edges_.size()) / 2; }
  absl::Duration build_time() const { return build_time_; }
  // Bytes of the graph, FreeSpace included.
  size_t bytes() const;

  // Calls visit(v, length) for every vertex v whose segment to the free
  // point `p` is clear and tangent at v: the vertices a shortest path from
  // or to `p` may use first. O(V) tangent tests plus the segment tests.
  template <typename Visit>
  void ForEachTangentVisible(LatticePoint p, Visit&& visit) const {
    const CornerQuadrant qp = QuadrantAt(*space_, p);
    for (uint32_t v = 0; v < vertices_.size(); ++v) {
      const LatticePoint w = vertices_[v];
      if (w == p || !Tangent(w, quadrants_[v], p) || !Tangent(p, qp, w)) continue;
      if (space_->SegmentClear(p, w)) visit(v, Distance(p, w));
    }
  }

 private:
  VisibilityGraph() = default;
  // Fills offsets_ and edges_ from per-vertex lists.
  void Compress(std::vector<std::vector<Edge>>& adjacency);

  std::shared_ptr<const FreeSpace> space_;
  std::vector<LatticePoint> vertices_;
  std::vector<CornerQuadrant> quadrants_;
  // Compressed adjacency: the edges of v are edges_[offsets_[v], offsets_[v+1]).
  std::vector<uint32_t> offsets_;
  std::vector<Edge> edges_;
  absl::Duration build_time_;
};

// The visibility graph of `grid` under `unknown_is_free`, from `store` (key
// "visibility_graph unknown_is_free=N"; advanced from the previous version's
// graph, VisibilityGraph::Advance) or built now when `store` is null. Null
// when `stop` fired first, building it or waiting for another query's build
// (stop.stopped_while() says which).
std::shared_ptr<const VisibilityGraph> GetVisibilityGraph(DerivedStore* store,
                                                          const Grid& grid,
                                                          bool unknown_is_free,
                                                          DerivedStop& stop);
// Never stops.
std::shared_ptr<const VisibilityGraph> GetVisibilityGraph(DerivedStore* store,
                                                          const Grid& grid,
                                                          bool unknown_is_free);

// The obstacles of a FreeSpace as Minimal Construct sees them: the connected
// groups of the map's blocked cells (cells sharing an edge or a corner) with
// the bend corners of each. Two blocked cells that close a segment together
// (along the edge between them, or through a pinch) always belong to one
// obstacle, so a blocked segment is blocked by one obstacle alone. The
// outside of the map belongs to none: a segment between points of the map
// never crosses it, and where it closes a segment along the border (or at a
// pinch there) together with a cell of the map, that cell's obstacle is the
// blocker; it has no bend corners either (every corner on the border has two
// outside cells). So walls that merely touch the border stay separate
// obstacles. Immutable; thread-safe.
class ObstacleCorners {
 public:
  static std::shared_ptr<const ObstacleCorners> Build(
      std::shared_ptr<const FreeSpace> space);

  const FreeSpace& space() const { return *space_; }
  int32_t obstacle_count() const {
    return static_cast<int32_t>(corner_offsets_.size()) - 1;
  }
  // The bend corners whose blocked cell belongs to `obstacle`.
  absl::Span<const LatticePoint> CornersOf(int32_t obstacle) const {
    return absl::MakeConstSpan(corners_.data() + corner_offsets_[obstacle],
                               corner_offsets_[obstacle + 1] -
                                   corner_offsets_[obstacle]);
  }
  // The obstacle that blocks segment a-b, nullopt when it is clear.
  // Precondition: a and b are free points of the map (within 0..width x
  // 0..height).
  std::optional<int32_t> Blocker(LatticePoint a, LatticePoint b) const;
  size_t bytes() const;

 private:
  ObstacleCorners() = default;
  int32_t ObstacleOf(int64_t x, int64_t y) const;

  std::shared_ptr<const FreeSpace> space_;
  // Per cell of the grid padded by one on every side: the obstacle it
  // belongs to, -1 when free or outside the map.
  std::vector<int32_t> obstacle_;
  std::vector<uint32_t> corner_offsets_;
  std::vector<LatticePoint> corners_;
};

// The obstacles of `grid` under `unknown_is_free`, from `store` (key
// "obstacle_corners unknown_is_free=N") or built now. The build is one flood
// fill, O(cells), and does not poll `stop`; null when `stop` fired before
// the value was there (the query would not start the build, or stopped
// waiting for another query's).
std::shared_ptr<const ObstacleCorners> GetObstacleCorners(DerivedStore* store,
                                                          const Grid& grid,
                                                          bool unknown_is_free,
                                                          DerivedStop& stop);
// Never stops.
std::shared_ptr<const ObstacleCorners> GetObstacleCorners(DerivedStore* store,
                                                          const Grid& grid,
                                                          bool unknown_is_free);

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_VISIBILITY_GRAPH_H_
