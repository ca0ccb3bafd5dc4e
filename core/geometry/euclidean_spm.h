// The Euclidean shortest path map of one goal (lecture notes "Shortest Path
// Map" and "Point Location Problem"; Mitchell, "Shortest paths among
// obstacles in the plane", 1996): every vertex of the tangent visibility
// graph labelled with its exact distance to the goal and the next vertex on
// its shortest path, and every free cell centre with its root, the first
// bend corner (or the goal itself) of its shortest path. A start is then
// answered by point location (one table read) and following the roots.
#ifndef PATHD_CORE_GEOMETRY_EUCLIDEAN_SPM_H_
#define PATHD_CORE_GEOMETRY_EUCLIDEAN_SPM_H_

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "absl/time/time.h"
#include "core/geometry/free_space.h"
#include "core/geometry/visibility_graph.h"
#include "core/map/grid.h"
#include "core/search/derived.h"

namespace pathd {

// Immutable once built; thread-safe (const).
class EuclideanSpm {
 public:
  static constexpr uint32_t kNoRoot = std::numeric_limits<uint32_t>::max();

  // Dijkstra from the goal over `graph` (taut continuations only) gives
  // each vertex its exact distance. Cell roots are then propagated in order
  // of distance, as a continuous Dijkstra would sweep the plane: a cell is
  // offered the roots of its eight neighbours, the next two roots after
  // them, the vertices at the corners around it (where a shadow region
  // starts) and, along each vertex's shadow edge, the vertex itself; it
  // keeps the best whose segment is clear and taut. That is right for
  // almost every cell but not provably for all (a region can be a sliver
  // between lattice points), so a last pass settles every cell exactly: a
  // root must be a seen vertex u (or the goal) minimising |c u| + dist(u),
  // and only vertices below the propagated value need their segment tested,
  // in increasing order until one is clear. O(cells x vertices) arithmetic
  // at worst, segment tests only for the few vertices that pass the bounds.
  // Precondition: `goal` is a free cell of graph->space().
  // Seconds to minutes on large maps (84 s on a 1024 x 1024 one), so every
  // phase polls `stop` every kPollEvery units of work (pops, vertices,
  // cells) and the build returns null, noting so in `stop`, when it fired.
  static std::shared_ptr<const EuclideanSpm> Build(
      std::shared_ptr<const VisibilityGraph> graph, Cell goal, DerivedStop& stop);
  // Never stops.
  static std::shared_ptr<const EuclideanSpm> Build(
      std::shared_ptr<const VisibilityGraph> graph, Cell goal);
  static constexpr int64_t kPollEvery = 64;

  Cell goal() const { return goal_; }
  const VisibilityGraph& graph() const { return *graph_; }
  // The root of cell `c`'s centre: a vertex id of graph(), root_count() -
  // 1 for the goal, kNoRoot when the goal cannot be reached (or c is
  // blocked). Precondition: c is on the grid.
  uint32_t RootOf(Cell c) const {
    return roots_[static_cast<size_t>(c.y) * graph_->space().width() + c.x];
  }
  // The goal's id among roots.
  uint32_t goal_root() const { return static_cast<uint32_t>(graph_->vertex_count()); }
  // The exact distance from root `r` to the goal.
  double RootDistance(uint32_t r) const { return distance_[r]; }
  // The next root after `r` towards the goal (kNoRoot after the goal).
  uint32_t NextRoot(uint32_t r) const { return next_[r]; }
  LatticePoint RootPoint(uint32_t r) const {
    return r == goal_root() ? CentreOf(goal_) : graph_->vertex(r);
  }
  // Shortest distance from cell c's centre to the goal's, +infinity when
  // unreachable.
  double DistanceFrom(Cell c) const;

  absl::Duration build_time() const { return build_time_; }
  // Bytes of the tables (the shared graph not included).
  size_t bytes() const;

 private:
  EuclideanSpm() = default;

  std::shared_ptr<const VisibilityGraph> graph_;
  Cell goal_;
  // Per vertex, then the goal: distance to the goal and next root.
  std::vector<double> distance_;
  std::vector<uint32_t> next_;
  // Per cell, row-major.
  std::vector<uint32_t> roots_;
  absl::Duration build_time_;
};

// The shortest path map of `goal` on `grid` under `unknown_is_free`, from
// `store` (key "euclidean_spm goal=X,Y unknown_is_free=N", over the shared
// visibility graph; rebuilt for every map version) or built now. Null when
// `stop` fired first, building it (or the visibility graph under it) or
// waiting for another query's build (stop.stopped_while() says which).
std::shared_ptr<const EuclideanSpm> GetEuclideanSpm(DerivedStore* store,
                                                    const Grid& grid, Cell goal,
                                                    bool unknown_is_free,
                                                    DerivedStop& stop);
// Never stops.
std::shared_ptr<const EuclideanSpm> GetEuclideanSpm(DerivedStore* store,
                                                    const Grid& grid, Cell goal,
                                                    bool unknown_is_free);

}  // namespace pathd

#endif  // PATHD_CORE_GEOMETRY_EUCLIDEAN_SPM_H_
