#include "core/geometry/euclidean_spm.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <queue>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"

namespace pathd {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct Entry {
  double d;
  uint32_t id;
  bool operator>(const Entry& o) const { return d > o.d; }
};
using MinQueue = std::priority_queue<Entry, std::vector<Entry>, std::greater<>>;

// A build's stop, read every EuclideanSpm::kPollEvery units of work (the
// first included); once it fired it stays fired.
class Poller {
 public:
  explicit Poller(DerivedStop& stop) : stop_(stop) {}
  bool Stopped() {
    if (!stopped_ && calls_++ % EuclideanSpm::kPollEvery == 0) {
      stopped_ = stop_.Stopped();
    }
    return stopped_;
  }

 private:
  DerivedStop& stop_;
  int64_t calls_ = 0;
  bool stopped_ = false;
};

// Exact distances to the goal (`goal_point`, id vertex_count()) and the next
// root towards it, for every vertex: Dijkstra from the goal over the graph.
// False when `poll` stopped it.
bool DistancesFromGoal(const VisibilityGraph& vg, LatticePoint goal_point,
                       std::vector<double>& dist, std::vector<uint32_t>& next,
                       Poller& poll) {
  const auto goal_id = static_cast<uint32_t>(vg.vertex_count());
  dist.assign(goal_id + 1, kInfinity);
  next.assign(goal_id + 1, EuclideanSpm::kNoRoot);
  dist[goal_id] = 0.0;
  MinQueue queue;
  vg.ForEachTangentVisible(goal_point, [&](uint32_t v, double d) {
    dist[v] = d;
    next[v] = goal_id;
    queue.push({d, v});
  });
  while (!queue.empty()) {
    if (poll.Stopped()) return false;
    const Entry top = queue.top();
    queue.pop();
    if (top.d != dist[top.id]) continue;
    const LatticePoint at = vg.vertex(top.id);
    const LatticePoint after = next[top.id] == goal_id ? goal_point : vg.vertex(next[top.id]);
    for (const VisibilityGraph::Edge& e : vg.EdgesOf(top.id)) {
      // Paths from the vertex's neighbours to the goal through it are
      // shortest only if taut there.
      if (!TautAt(vg.vertex(e.to), at, vg.quadrant(top.id), after)) continue;
      const double d = top.d + e.length;
      if (d < dist[e.to]) {
        dist[e.to] = d;
        next[e.to] = top.id;
        queue.push({d, e.to});
      }
    }
  }
  return true;
}

// The segment a-b crosses the open interior of cell `c`: then it is not
// clear.
bool CrossesInterior(LatticePoint a, LatticePoint b, Cell c) {
  return SegmentMeetsBox(a, b, CornerAt(c.x, c.y), CornerAt(c.x + 1, c.y + 1), true);
}

// The cells of the goal's free region: free cells joined by shared edges
// (two free cells touching only at a corner are joined through a side cell,
// or not at all: a pinch).
std::vector<uint8_t> GoalRegion(const FreeSpace& space, Cell goal) {
  const int32_t w = space.width();
  const int32_t h = space.height();
  std::vector<uint8_t> in(static_cast<size_t>(w) * h, 0);
  std::vector<Cell> stack = {goal};
  in[static_cast<size_t>(goal.y) * w + goal.x] = 1;
  while (!stack.empty()) {
    const Cell c = stack.back();
    stack.pop_back();
    const Cell around[] = {{c.x + 1, c.y}, {c.x - 1, c.y}, {c.x, c.y + 1}, {c.x, c.y - 1}};
    for (const Cell& n : around) {
      if (space.Blocked(n.x, n.y)) continue;  // the outside reads as blocked
      uint8_t& seen = in[static_cast<size_t>(n.y) * w + n.x];
      if (seen) continue;
      seen = 1;
      stack.push_back(n);
    }
  }
  return in;
}

// The vertices with a finite distance, bucketed by square tiles of the map
// with each tile's smallest distance, so that a cell can skip every tile
// whose vertices cannot beat a bound.
class RootTiles {
 public:
  struct Root {
    LatticePoint p;
    CornerQuadrant q;
    LatticePoint next;
    double dist;
    uint32_t id;
  };

  RootTiles(const VisibilityGraph& vg, const std::vector<double>& dist,
            const std::vector<uint32_t>& next_root, LatticePoint goal_point)
      : across_((vg.space().width() + kTile) / kTile),
        down_((vg.space().height() + kTile) / kTile),
        tiles_(static_cast<size_t>(across_) * down_) {
    const auto n = static_cast<uint32_t>(vg.vertex_count());
    for (uint32_t v = 0; v < n; ++v) {
      if (dist[v] == kInfinity) continue;
      const LatticePoint p = vg.vertex(v);
      const LatticePoint next = next_root[v] == n ? goal_point : vg.vertex(next_root[v]);
      Tile& tile = tiles_[static_cast<size_t>(p.y2 / (2 * kTile)) * across_ +
                          p.x2 / (2 * kTile)];
      tile.roots.push_back({p, vg.quadrant(v), next, dist[v], v});
      tile.min_dist = std::min(tile.min_dist, dist[v]);
    }
  }

  // Calls visit(root, d) for each root r whose path from `c` through it,
  // d = |c r| + dist(r), is below `bound` and taut at r.
  template <typename Visit>
  void ForEachBelow(LatticePoint c, double bound, Visit&& visit) const {
    const double cx = static_cast<double>(c.x2) / 2.0;
    const double cy = static_cast<double>(c.y2) / 2.0;
    for (int32_t ty = 0; ty < down_; ++ty) {
      // Distance from c to the tile's rectangle, split by axis.
      const double y0 = static_cast<double>(ty) * kTile;
      const double gap_y = std::max({y0 - cy, cy - (y0 + kTile), 0.0});
      for (int32_t tx = 0; tx < across_; ++tx) {
        const Tile& tile = tiles_[static_cast<size_t>(ty) * across_ + tx];
        if (tile.roots.empty()) continue;
        const double x0 = static_cast<double>(tx) * kTile;
        const double gap_x = std::max({x0 - cx, cx - (x0 + kTile), 0.0});
        const double slack = bound - tile.min_dist;
        if (slack <= 0.0 || gap_x * gap_x + gap_y * gap_y >= slack * slack) continue;
        for (const Root& r : tile.roots) {
          const double dx = static_cast<double>(r.p.x2 - c.x2) / 2.0;
          const double dy = static_cast<double>(r.p.y2 - c.y2) / 2.0;
          const double left = bound - r.dist;
          if (left <= 0.0 || dx * dx + dy * dy >= left * left) continue;
          if (!TautAt(c, r.p, r.q, r.next)) continue;
          visit(r, r.dist + std::sqrt(dx * dx + dy * dy));
        }
      }
    }
  }

 private:
  static constexpr int32_t kTile = 16;
  struct Tile {
    std::vector<Root> roots;
    double min_dist = kInfinity;
  };
  int32_t across_;
  int32_t down_;
  std::vector<Tile> tiles_;
};

// Makes every root of the goal's region exact. The first bend of a
// shortest path from point c is a vertex u seen from c (or the goal), so the
// distance is min over those of |c u| + dist(u). The propagated root's value
// `best` is the length of a clear path, so only vertices with dist(u) +
// |c u| below it can do better: those are tested in order of that sum, and
// the first whose segment is clear (and taut) is the root. Tiles whose
// vertices are all too far for the bound are skipped whole, and a blocked
// cell that hid a vertex from a cell usually hides it from the next.
// False when `poll` stopped it.
bool SettleRoots(const VisibilityGraph& vg, Cell goal, const std::vector<double>& dist,
                 const std::vector<uint32_t>& next_root,
                 const std::vector<double>& best, std::vector<uint32_t>& roots,
                 Poller& poll) {
  const FreeSpace& space = vg.space();
  const int32_t w = space.width();
  const auto n = static_cast<uint32_t>(vg.vertex_count());
  const LatticePoint goal_point = CentreOf(goal);
  const RootTiles tiles(vg, dist, next_root, goal_point);
  const std::vector<uint8_t> region = GoalRegion(space, goal);
  std::vector<Entry> candidates;
  // Per root: a blocked cell that hid it from an earlier cell. Neighbouring
  // cells tend to be hidden by the same one, and testing that costs O(1).
  std::vector<Cell> hidden_by(n + 1, Cell{-1, -1});
  for (size_t i = 0; i < roots.size(); ++i) {
    if (!region[i]) continue;
    if (poll.Stopped()) return false;
    const LatticePoint c = CentreOf(Cell{static_cast<int32_t>(i % w),
                                         static_cast<int32_t>(i / w)});
    // Strictly below the propagated value (a tie keeps its root).
    const double bound = best[i] - 1e-9 * (1.0 + best[i]);
    candidates.clear();
    const double to_goal = Distance(c, goal_point);
    if (to_goal < bound) candidates.push_back({to_goal, n});
    tiles.ForEachBelow(c, bound, [&](const RootTiles::Root& r, double d) {
      candidates.push_back({d, r.id});
    });
    std::sort(candidates.begin(), candidates.end(),
              [](const Entry& a, const Entry& b) { return a.d < b.d; });
    for (const Entry& e : candidates) {
      const LatticePoint u = e.id == n ? goal_point : vg.vertex(e.id);
      Cell& block = hidden_by[e.id];
      if (block.x >= 0 && CrossesInterior(c, u, block)) continue;
      if (space.SegmentClear(c, u)) {
        roots[i] = e.id;
        break;
      }
      space.ForEachCellCrossed(c, u, [&](Cell crossed) {
        if (space.Blocked(crossed.x, crossed.y)) block = crossed;
      });
    }
  }
  return true;
}

}  // namespace

std::shared_ptr<const EuclideanSpm> EuclideanSpm::Build(
    std::shared_ptr<const VisibilityGraph> graph, Cell goal) {
  DerivedStop never;
  return Build(std::move(graph), goal, never);
}

std::shared_ptr<const EuclideanSpm> EuclideanSpm::Build(
    std::shared_ptr<const VisibilityGraph> graph, Cell goal, DerivedStop& stop) {
  const absl::Time started = absl::Now();
  auto spm = std::shared_ptr<EuclideanSpm>(new EuclideanSpm());
  spm->graph_ = std::move(graph);
  spm->goal_ = goal;
  const VisibilityGraph& vg = *spm->graph_;
  const FreeSpace& space = vg.space();
  const auto n = static_cast<uint32_t>(vg.vertex_count());
  const uint32_t goal_id = n;
  const LatticePoint goal_point = CentreOf(goal);

  std::vector<double>& dist = spm->distance_;
  std::vector<uint32_t>& next = spm->next_;
  Poller poll(stop);
  auto stopped = [&] {
    stop.Note(absl::StrFormat(
        "building the Euclidean shortest path map of goal (%d, %d) on this map "
        "version (%d vertices, %d x %d cells)",
        goal.x, goal.y, n, space.width(), space.height()));
    return nullptr;
  };
  if (!DistancesFromGoal(vg, goal_point, dist, next, poll)) return stopped();
  MinQueue queue;

  // Cells: roots propagated in order of distance.
  const int32_t w = space.width();
  const int32_t h = space.height();
  std::vector<uint32_t>& roots = spm->roots_;
  roots.assign(static_cast<size_t>(w) * h, kNoRoot);
  std::vector<double> best(roots.size(), kInfinity);
  std::vector<uint8_t> done(roots.size(), 0);
  auto point_of = [&](uint32_t r) {
    return r == goal_id ? goal_point : vg.vertex(r);
  };
  auto offer = [&](int32_t x, int32_t y, uint32_t r) {
    if (r == kNoRoot || dist[r] == kInfinity) return;
    const size_t i = static_cast<size_t>(y) * w + x;
    if (done[i]) return;
    const LatticePoint c = CentreOf(Cell{x, y});
    const LatticePoint p = point_of(r);
    const double d = Distance(c, p) + dist[r];
    // Near-ties (a cell centre on the line through a root and its next
    // root) go to the deeper root, the one nearer the cell: the cells along
    // a shadow's edge then carry the shadow's root to the cells inside it.
    const double tolerance = 1e-9 * (1.0 + d);
    if (d > best[i] + tolerance) return;
    if (d >= best[i] - tolerance &&
        (roots[i] == r || dist[r] <= dist[roots[i]])) {
      return;
    }
    if (r != goal_id && !TautAt(c, p, vg.quadrant(r), point_of(next[r]))) return;
    if (!space.SegmentClear(c, p)) return;
    best[i] = d;
    roots[i] = r;
    queue.push({d, static_cast<uint32_t>(i)});
  };
  // The vertex ids at grid corners, for the corner candidates.
  std::vector<uint32_t> corner_vertex(static_cast<size_t>(w + 1) * (h + 1), kNoRoot);
  for (uint32_t v = 0; v < n; ++v) {
    const LatticePoint p = vg.vertex(v);
    corner_vertex[static_cast<size_t>(p.y2 / 2) * (w + 1) + p.x2 / 2] = v;
  }
  // A vertex's region begins as a thin wedge between the extension of the
  // segment from its next root and the obstacle edge at the corner. Cell
  // centres there may have no neighbour in the wedge, so the vertex is
  // offered to the cells along that extension until the wedge is two cells
  // wide, from where on neighbours carry it.
  auto SeedShadow = [&](uint32_t v) {
    if (dist[v] == kInfinity) return;
    const LatticePoint u = vg.vertex(v);
    const LatticePoint from = point_of(next[v]);
    const double dx = static_cast<double>(u.x2 - from.x2);
    const double dy = static_cast<double>(u.y2 - from.y2);
    const double norm = std::hypot(dx, dy);
    const CornerQuadrant q = vg.quadrant(v);
    // The edge of the blocked cell that points forward along the extension.
    const double ex = dx * q.qx >= 0 ? q.qx : 0.0;
    const double ey = ex == 0.0 ? q.qy : 0.0;
    if (dx * ex + dy * ey < 0) return;
    const double sine = std::abs(dx * ey - dy * ex) / norm;
    if (sine == 0.0) return;
    const double reach = std::min(2.0 / sine + 2.0, static_cast<double>(w + h));
    const double ux = static_cast<double>(u.x2) / 2.0;
    const double uy = static_cast<double>(u.y2) / 2.0;
    for (double t = 0.25; t <= reach; t += 0.5) {
      const auto px = static_cast<int32_t>(std::floor(ux + t * dx / norm));
      const auto py = static_cast<int32_t>(std::floor(uy + t * dy / norm));
      if (px < 0 || py < 0 || px >= w || py >= h || space.Blocked(px, py)) return;
      for (int32_t y = std::max(py - 1, 0); y <= std::min(py + 1, h - 1); ++y) {
        for (int32_t x = std::max(px - 1, 0); x <= std::min(px + 1, w - 1); ++x) {
          if (!space.Blocked(x, y)) offer(x, y, v);
        }
      }
    }
  };
  offer(goal.x, goal.y, goal_id);
  for (uint32_t v = 0; v < n; ++v) {
    if (poll.Stopped()) return stopped();
    SeedShadow(v);
  }
  while (!queue.empty()) {
    if (poll.Stopped()) return stopped();
    const Entry top = queue.top();
    queue.pop();
    if (done[top.id] || top.d != best[top.id]) continue;
    done[top.id] = 1;
    const auto cx = static_cast<int32_t>(top.id % w);
    const auto cy = static_cast<int32_t>(top.id / w);
    const uint32_t root = roots[top.id];
    const uint32_t after = next[root];
    for (int32_t y = std::max(cy - 1, 0); y <= std::min(cy + 1, h - 1); ++y) {
      for (int32_t x = std::max(cx - 1, 0); x <= std::min(cx + 1, w - 1); ++x) {
        if (done[static_cast<size_t>(y) * w + x] || space.Blocked(x, y)) continue;
        offer(x, y, root);
        offer(x, y, after);
        if (after != kNoRoot) offer(x, y, next[after]);
        // The corners around the cell: a shadow starts at one of them.
        for (int32_t j = std::max(y - 1, 0); j <= std::min(y + 2, h); ++j) {
          for (int32_t i = std::max(x - 1, 0); i <= std::min(x + 2, w); ++i) {
            offer(x, y, corner_vertex[static_cast<size_t>(j) * (w + 1) + i]);
          }
        }
      }
    }
  }
  if (!SettleRoots(vg, goal, dist, next, best, roots, poll)) return stopped();
  spm->build_time_ = absl::Now() - started;
  return spm;
}

double EuclideanSpm::DistanceFrom(Cell c) const {
  const uint32_t r = RootOf(c);
  if (r == kNoRoot) return kInfinity;
  return Distance(CentreOf(c), RootPoint(r)) + distance_[r];
}

size_t EuclideanSpm::bytes() const {
  return sizeof(*this) + distance_.capacity() * sizeof(double) +
         next_.capacity() * sizeof(uint32_t) + roots_.capacity() * sizeof(uint32_t);
}

std::shared_ptr<const EuclideanSpm> GetEuclideanSpm(DerivedStore* store,
                                                    const Grid& grid, Cell goal,
                                                    bool unknown_is_free,
                                                    DerivedStop& stop) {
  const std::string key = absl::StrCat("euclidean_spm goal=", goal.x, ",", goal.y,
                                       " unknown_is_free=", unknown_is_free ? 1 : 0);
  return GetDerived<EuclideanSpm>(
      store, grid, key,
      absl::StrFormat("the Euclidean shortest path map of goal (%d, %d) on this "
                      "map version",
                      goal.x, goal.y),
      stop,
      [store, goal, unknown_is_free](const Grid& g, DerivedStop& s)
          -> std::shared_ptr<const EuclideanSpm> {
        std::shared_ptr<const VisibilityGraph> graph =
            GetVisibilityGraph(store, g, unknown_is_free, s);
        if (graph == nullptr) return nullptr;
        return EuclideanSpm::Build(std::move(graph), goal, s);
      },
      // Any changed cell can move roots anywhere: rebuild.
      [](const EuclideanSpm&, const Grid&, absl::Span<const Cell>, DerivedStop&) {
        return std::shared_ptr<const EuclideanSpm>();
      },
      [](const EuclideanSpm& spm) { return spm.bytes(); });
}

std::shared_ptr<const EuclideanSpm> GetEuclideanSpm(DerivedStore* store,
                                                    const Grid& grid, Cell goal,
                                                    bool unknown_is_free) {
  DerivedStop never;
  return GetEuclideanSpm(store, grid, goal, unknown_is_free, never);
}

}  // namespace pathd
