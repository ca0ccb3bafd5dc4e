#include "core/geometry/visibility_graph.h"

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/geometry/structure.h"

namespace pathd {
namespace {

std::string FlagKey(const char* kind, bool unknown_is_free) {
  return absl::StrCat(kind, " unknown_is_free=", unknown_is_free ? 1 : 0);
}

}  // namespace

CornerQuadrant QuadrantAt(const FreeSpace& space, LatticePoint p) {
  if (p.x2 % 2 != 0 || p.y2 % 2 != 0) return {};
  const int64_t x = p.x2 / 2;
  const int64_t y = p.y2 / 2;
  if (!space.IsBendCorner(x, y)) return {};
  // CornerMask bits: 0 (x-1, y-1), 1 (x, y-1), 2 (x-1, y), 3 (x, y).
  switch (space.CornerMask(x, y)) {
    case 1: return {-1, -1};
    case 2: return {1, -1};
    case 4: return {-1, 1};
    default: return {1, 1};
  }
}

bool SegmentMeetsBox(LatticePoint a, LatticePoint b, LatticePoint lo,
                     LatticePoint hi, bool open) {
  // t in [lo_n / lo_d, hi_n / hi_d] within [0, 1], denominators > 0.
  int64_t lo_n = 0, lo_d = 1, hi_n = 1, hi_d = 1;
  auto clip = [&](int64_t from, int64_t delta, int64_t low, int64_t high) {
    if (delta == 0) return open ? low < from && from < high : low <= from && from <= high;
    // from + t delta between low and high.
    int64_t n0 = low - from, n1 = high - from, d = delta;
    if (d < 0) {
      std::swap(n0, n1);
      n0 = -n0;
      n1 = -n1;
      d = -d;
    }
    if (n0 * lo_d > lo_n * d) {
      lo_n = n0;
      lo_d = d;
    }
    if (n1 * hi_d < hi_n * d) {
      hi_n = n1;
      hi_d = d;
    }
    return true;
  };
  if (!clip(a.x2, b.x2 - a.x2, lo.x2, hi.x2) || !clip(a.y2, b.y2 - a.y2, lo.y2, hi.y2)) {
    return false;
  }
  return open ? lo_n * hi_d < hi_n * lo_d : lo_n * hi_d <= hi_n * lo_d;
}

void VisibilityGraph::Compress(std::vector<std::vector<Edge>>& adjacency) {
  const auto n = static_cast<uint32_t>(adjacency.size());
  offsets_.assign(n + 1, 0);
  for (uint32_t v = 0; v < n; ++v) {
    offsets_[v + 1] = offsets_[v] + static_cast<uint32_t>(adjacency[v].size());
  }
  edges_.clear();
  edges_.reserve(offsets_[n]);
  for (std::vector<Edge>& edges : adjacency) {
    edges_.insert(edges_.end(), edges.begin(), edges.end());
    std::vector<Edge>().swap(edges);
  }
}

std::shared_ptr<const VisibilityGraph> VisibilityGraph::Advance(
    const VisibilityGraph& previous, std::shared_ptr<const FreeSpace> space,
    absl::Span<const Cell> changed) {
  DerivedStop never;
  return Advance(previous, std::move(space), changed, never);
}

std::shared_ptr<const VisibilityGraph> VisibilityGraph::Advance(
    const VisibilityGraph& previous, std::shared_ptr<const FreeSpace> space,
    absl::Span<const Cell> changed, DerivedStop& stop) {
  if (changed.size() > kMaxAdvanceCells) return nullptr;
  // Segments that miss every changed cell's closed square kept their state.
  LatticePoint lo{std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max()};
  LatticePoint hi{std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min()};
  for (const Cell& c : changed) {
    lo = {std::min<int64_t>(lo.x2, 2 * c.x), std::min<int64_t>(lo.y2, 2 * c.y)};
    hi = {std::max<int64_t>(hi.x2, 2 * c.x + 2), std::max<int64_t>(hi.y2, 2 * c.y + 2)};
  }
  // Every pair whose segment meets the box is tested again, so a box over a
  // large part of the map (scattered changes) costs more than a rebuild: on
  // Berlin scaled to 1024², 10 scattered cells took 1.6 s against a 1.5 s
  // rebuild, one cell 82 ms.
  const int64_t box_area = (hi.x2 - lo.x2) / 2 * ((hi.y2 - lo.y2) / 2);
  const int64_t map_area = static_cast<int64_t>(space->width()) * space->height();
  if (map_area >= kBoxRuleMinCells && box_area * kMaxAdvanceBoxShare > map_area) {
    return nullptr;
  }
  const absl::Time started = absl::Now();
  auto graph = std::shared_ptr<VisibilityGraph>(new VisibilityGraph());
  graph->space_ = std::move(space);
  const FreeSpace& fs = *graph->space_;
  graph->vertices_ = fs.BendCorners();
  const auto n = static_cast<uint32_t>(graph->vertices_.size());
  for (LatticePoint v : graph->vertices_) graph->quadrants_.push_back(QuadrantAt(fs, v));
  const std::vector<LatticePoint>& vs = graph->vertices_;
  const std::vector<CornerQuadrant>& qs = graph->quadrants_;

  // Old ids of the vertices that kept their corner and blocked cell (both
  // lists are in row order); kNew for the others.
  constexpr uint32_t kNew = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> old_id(n, kNew);
  std::vector<uint32_t> new_id(previous.vertex_count(), kNew);
  auto row_less = [](LatticePoint a, LatticePoint b) {
    return a.y2 != b.y2 ? a.y2 < b.y2 : a.x2 < b.x2;
  };
  for (uint32_t i = 0, j = 0; i < n && j < previous.vertex_count();) {
    const LatticePoint o = previous.vertex(j);
    if (row_less(vs[i], o)) {
      ++i;
    } else if (row_less(o, vs[i])) {
      ++j;
    } else {
      const CornerQuadrant q = previous.quadrant(j);
      if (q.qx == qs[i].qx && q.qy == qs[i].qy) {
        old_id[i] = j;
        new_id[j] = i;
      }
      ++i;
      ++j;
    }
  }
  std::vector<std::vector<Edge>> adjacency(n);
  // Per new id: 1 + the old vertex whose edges are marked (stamp).
  std::vector<uint32_t> was_edge(n, 0);
  for (uint32_t i = 0; i < n; ++i) {
    // Once per vertex: up to V pairs, with segment tests where the box or a
    // new vertex makes them.
    if (stop.Stopped()) {
      stop.Note(absl::StrFormat(
          "advancing the visibility graph to this map version (%d vertices, "
          "%d changed cells)",
          n, changed.size()));
      return nullptr;
    }
    if (old_id[i] != kNew) {
      for (const Edge& e : previous.EdgesOf(old_id[i])) {
        if (new_id[e.to] != kNew) was_edge[new_id[e.to]] = i + 1;
      }
    }
    for (uint32_t j = i + 1; j < n; ++j) {
      if (!Tangent(vs[i], qs[i], vs[j]) || !Tangent(vs[j], qs[j], vs[i])) continue;
      const bool kept = old_id[i] != kNew && old_id[j] != kNew &&
                        (changed.empty() || !SegmentMeetsBox(vs[i], vs[j], lo, hi, false));
      if (kept ? was_edge[j] != i + 1 : !fs.SegmentClear(vs[i], vs[j])) continue;
      const double length = Distance(vs[i], vs[j]);
      adjacency[i].push_back(Edge{j, length});
      adjacency[j].push_back(Edge{i, length});
    }
  }
  graph->Compress(adjacency);
  graph->build_time_ = absl::Now() - started;
  return graph;
}

std::shared_ptr<const VisibilityGraph> VisibilityGraph::Build(
    std::shared_ptr<const FreeSpace> space) {
  DerivedStop never;
  return Build(std::move(space), never);
}

std::shared_ptr<const VisibilityGraph> VisibilityGraph::Build(
    std::shared_ptr<const FreeSpace> space, DerivedStop& stop) {
  const absl::Time started = absl::Now();
  auto graph = std::shared_ptr<VisibilityGraph>(new VisibilityGraph());
  graph->space_ = std::move(space);
  const FreeSpace& fs = *graph->space_;
  graph->vertices_ = fs.BendCorners();
  const auto n = static_cast<uint32_t>(graph->vertices_.size());
  graph->quadrants_.reserve(n);
  for (LatticePoint v : graph->vertices_) {
    graph->quadrants_.push_back(QuadrantAt(fs, v));
  }
  std::vector<std::vector<Edge>> adjacency(n);
  const std::vector<LatticePoint>& vs = graph->vertices_;
  const std::vector<CornerQuadrant>& qs = graph->quadrants_;
  for (uint32_t i = 0; i < n; ++i) {
    // Once per vertex: V - i pairs, a few milliseconds on the random maps, so
    // a query stops within about that of its deadline or cancellation.
    if (stop.Stopped()) {
      stop.Note(absl::StrFormat(
          "building the visibility graph of this map version (%d vertices)", n));
      return nullptr;
    }
    for (uint32_t j = i + 1; j < n; ++j) {
      // Tangency at both ends rejects about three pairs in four for free.
      if (!Tangent(vs[i], qs[i], vs[j]) || !Tangent(vs[j], qs[j], vs[i])) continue;
      if (!fs.SegmentClear(vs[i], vs[j])) continue;
      const double length = Distance(vs[i], vs[j]);
      adjacency[i].push_back(Edge{j, length});
      adjacency[j].push_back(Edge{i, length});
    }
  }
  graph->Compress(adjacency);
  graph->build_time_ = absl::Now() - started;
  return graph;
}

size_t VisibilityGraph::bytes() const {
  return sizeof(*this) + space_->bytes() +
         vertices_.capacity() * sizeof(LatticePoint) +
         quadrants_.capacity() * sizeof(CornerQuadrant) +
         offsets_.capacity() * sizeof(uint32_t) + edges_.capacity() * sizeof(Edge);
}

std::shared_ptr<const VisibilityGraph> GetVisibilityGraph(DerivedStore* store,
                                                          const Grid& grid,
                                                          bool unknown_is_free,
                                                          DerivedStop& stop) {
  return GetDerived<VisibilityGraph>(
      store, grid, FlagKey("visibility_graph", unknown_is_free),
      "the visibility graph of this map version", stop,
      [store, unknown_is_free](const Grid& g, DerivedStop& s)
          -> std::shared_ptr<const VisibilityGraph> {
        std::shared_ptr<const FreeSpace> space =
            SharedFreeSpace(store, g, unknown_is_free, s);
        if (space == nullptr) return nullptr;
        return VisibilityGraph::Build(std::move(space), s);
      },
      [store, unknown_is_free](const VisibilityGraph& previous, const Grid& g,
                               absl::Span<const Cell> changed, DerivedStop& s)
          -> std::shared_ptr<const VisibilityGraph> {
        std::shared_ptr<const FreeSpace> space =
            SharedFreeSpace(store, g, unknown_is_free, s);
        if (space == nullptr) return nullptr;
        return VisibilityGraph::Advance(previous, std::move(space), changed, s);
      },
      [](const VisibilityGraph& graph) { return graph.bytes(); });
}

std::shared_ptr<const VisibilityGraph> GetVisibilityGraph(DerivedStore* store,
                                                          const Grid& grid,
                                                          bool unknown_is_free) {
  DerivedStop never;
  return GetVisibilityGraph(store, grid, unknown_is_free, never);
}

std::shared_ptr<const ObstacleCorners> ObstacleCorners::Build(
    std::shared_ptr<const FreeSpace> space) {
  auto result = std::shared_ptr<ObstacleCorners>(new ObstacleCorners());
  result->space_ = std::move(space);
  const FreeSpace& fs = *result->space_;
  const int64_t pw = static_cast<int64_t>(fs.width()) + 2;
  const int64_t ph = static_cast<int64_t>(fs.height()) + 2;
  std::vector<int32_t>& label = result->obstacle_;
  label.assign(static_cast<size_t>(pw * ph), -1);
  // Flood fill over the 8-neighbours of the map's cells (padded index of
  // cell (x, y) is (y + 1) * pw + x + 1); the padding stays -1.
  int32_t obstacles = 0;
  std::vector<int64_t> stack;
  for (int64_t start = 0; start < pw * ph; ++start) {
    const int64_t sx = start % pw - 1;
    const int64_t sy = start / pw - 1;
    if (sx < 0 || sy < 0 || sx >= fs.width() || sy >= fs.height() ||
        label[start] >= 0 || !fs.Blocked(sx, sy)) {
      continue;
    }
    label[start] = obstacles;
    stack.push_back(start);
    while (!stack.empty()) {
      const int64_t at = stack.back();
      stack.pop_back();
      const int64_t x = at % pw - 1;
      const int64_t y = at / pw - 1;
      for (int64_t ny = std::max<int64_t>(y - 1, 0);
           ny <= std::min<int64_t>(y + 1, fs.height() - 1); ++ny) {
        for (int64_t nx = std::max<int64_t>(x - 1, 0);
             nx <= std::min<int64_t>(x + 1, fs.width() - 1); ++nx) {
          const int64_t next = (ny + 1) * pw + nx + 1;
          if (label[next] >= 0 || !fs.Blocked(nx, ny)) continue;
          label[next] = obstacles;
          stack.push_back(next);
        }
      }
    }
    ++obstacles;
  }
  // Bend corners grouped by obstacle (counting sort keeps row order).
  const std::vector<LatticePoint> bends = fs.BendCorners();
  std::vector<int32_t> owner;
  owner.reserve(bends.size());
  result->corner_offsets_.assign(static_cast<size_t>(obstacles) + 1, 0);
  for (LatticePoint c : bends) {
    const CornerQuadrant q = QuadrantAt(fs, c);
    const int64_t cx = c.x2 / 2 + (q.qx < 0 ? -1 : 0);
    const int64_t cy = c.y2 / 2 + (q.qy < 0 ? -1 : 0);
    owner.push_back(result->ObstacleOf(cx, cy));
    ++result->corner_offsets_[owner.back() + 1];
  }
  std::partial_sum(result->corner_offsets_.begin(), result->corner_offsets_.end(),
                   result->corner_offsets_.begin());
  result->corners_.resize(bends.size());
  std::vector<uint32_t> fill(result->corner_offsets_.begin(),
                             result->corner_offsets_.end() - 1);
  for (size_t i = 0; i < bends.size(); ++i) {
    result->corners_[fill[owner[i]]++] = bends[i];
  }
  return result;
}

int32_t ObstacleCorners::ObstacleOf(int64_t x, int64_t y) const {
  const int64_t pw = static_cast<int64_t>(space_->width()) + 2;
  return obstacle_[static_cast<size_t>((y + 1) * pw + x + 1)];
}

std::optional<int32_t> ObstacleCorners::Blocker(LatticePoint a,
                                                LatticePoint b) const {
  const FreeSpace& fs = *space_;
  if (fs.SegmentClear(a, b)) return std::nullopt;
  // A blocked cell whose interior the segment crosses, or the second of two
  // blocked cells along a grid line (ForEachCellCrossed reports it then).
  // Along the bottom or right border the second is outside the map and the
  // first, the one inside, is the blocker.
  std::optional<int32_t> found;
  fs.ForEachCellCrossed(a, b, [&](Cell c) {
    const int32_t obstacle = ObstacleOf(std::min(c.x, fs.width() - 1),
                                        std::min(c.y, fs.height() - 1));
    if (!found.has_value() && fs.Blocked(c.x, c.y) && obstacle >= 0) found = obstacle;
  });
  if (found.has_value()) return found;
  // Otherwise a closed grid corner on the segment (a pinch): any blocked
  // cell of the map there. The segment's lattice points are a + k (d / gcd).
  const int64_t dx = b.x2 - a.x2;
  const int64_t dy = b.y2 - a.y2;
  const int64_t steps = std::gcd(std::abs(dx), std::abs(dy));
  for (int64_t k = 0; k <= steps; ++k) {
    const int64_t x2 = a.x2 + k * (dx / steps);
    const int64_t y2 = a.y2 + k * (dy / steps);
    if (x2 % 2 != 0 || y2 % 2 != 0 || fs.CornerFree(x2 / 2, y2 / 2)) continue;
    for (int64_t cy = y2 / 2 - 1; cy <= y2 / 2; ++cy) {
      for (int64_t cx = x2 / 2 - 1; cx <= x2 / 2; ++cx) {
        if (ObstacleOf(cx, cy) >= 0) return ObstacleOf(cx, cy);
      }
    }
  }
  // SegmentClear fails only for the causes above, and within the map each
  // involves a blocked cell of the map.
  std::abort();
}

size_t ObstacleCorners::bytes() const {
  return sizeof(*this) + space_->bytes() + obstacle_.capacity() * sizeof(int32_t) +
         corner_offsets_.capacity() * sizeof(uint32_t) +
         corners_.capacity() * sizeof(LatticePoint);
}

std::shared_ptr<const ObstacleCorners> GetObstacleCorners(DerivedStore* store,
                                                          const Grid& grid,
                                                          bool unknown_is_free,
                                                          DerivedStop& stop) {
  return GetDerived<ObstacleCorners>(
      store, grid, FlagKey("obstacle_corners", unknown_is_free),
      "the obstacles of this map version", stop,
      [store, unknown_is_free](const Grid& g, DerivedStop& s)
          -> std::shared_ptr<const ObstacleCorners> {
        std::shared_ptr<const FreeSpace> space =
            SharedFreeSpace(store, g, unknown_is_free, s);
        if (space == nullptr) return nullptr;
        return ObstacleCorners::Build(std::move(space));
      },
      // One changed cell can merge or split obstacles anywhere: rebuild.
      [](const ObstacleCorners&, const Grid&, absl::Span<const Cell>, DerivedStop&) {
        return std::shared_ptr<const ObstacleCorners>();
      },
      [](const ObstacleCorners& corners) { return corners.bytes(); });
}

std::shared_ptr<const ObstacleCorners> GetObstacleCorners(DerivedStore* store,
                                                          const Grid& grid,
                                                          bool unknown_is_free) {
  DerivedStop never;
  return GetObstacleCorners(store, grid, unknown_is_free, never);
}

GeometricStructure DescribeVisibilityGraph(const Grid& grid, bool unknown_is_free) {
  // Drawing more segments than this helps nobody and costs megabytes.
  constexpr int64_t kMaxSegments = 200000;
  const std::shared_ptr<const VisibilityGraph> graph =
      GetVisibilityGraph(nullptr, grid, unknown_is_free);
  GeometricStructure s;
  s.kind = "visibility";
  s.counts = {{"vertices", static_cast<int64_t>(graph->vertex_count())},
              {"edges", graph->edge_count()}};
  s.bytes = graph->bytes();
  s.build_time = graph->build_time();
  for (uint32_t v = 0; v < graph->vertex_count(); ++v) {
    s.points.push_back(ToCellPoint(graph->vertex(v)));
    for (const VisibilityGraph::Edge& e : graph->EdgesOf(v)) {
      if (e.to < v) continue;
      if (static_cast<int64_t>(s.segments.size()) == kMaxSegments) break;
      s.segments.push_back({ToCellPoint(graph->vertex(v)), ToCellPoint(graph->vertex(e.to))});
    }
  }
  if (graph->edge_count() > kMaxSegments) {
    s.counts.push_back({"edges drawn", kMaxSegments});
  }
  return s;
}

}  // namespace pathd
