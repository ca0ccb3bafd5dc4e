#include "core/kinematics/obstacle_heuristic.h"

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "absl/strings/str_format.h"
#include "core/kinematics/footprint.h"
#include "core/map/cost_model.h"

namespace pathd {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// Settled cells between two polls of the stop condition (about a
// millisecond of work).
constexpr int64_t kPollCells = 1 << 16;

}  // namespace

std::shared_ptr<const std::vector<float>> GetObstacleDistance(DerivedStore* store,
                                                              const Grid& grid,
                                                              bool unknown_is_free) {
  return GetDerived<std::vector<float>>(
      store, grid,
      std::string("obstacle_distance unknown_is_free=") + (unknown_is_free ? "1" : "0"),
      [unknown_is_free](const Grid& g) {
        return std::make_shared<const std::vector<float>>(
            ObstacleDistanceField(g, unknown_is_free));
      },
      // The transform is as fast as a scan of the changes would be: rebuild.
      [](const std::vector<float>&, const Grid&, absl::Span<const Cell>) {
        return std::shared_ptr<const std::vector<float>>();
      },
      [](const std::vector<float>& field) {
        return sizeof(field) + field.capacity() * sizeof(float);
      });
}

std::shared_ptr<const ObstacleHeuristic> BuildObstacleHeuristic(
    const Grid& grid, const ObstacleHeuristicParams& params, const float* distance,
    DerivedStop& stop) {
  const int32_t w = grid.width();
  const int32_t h = grid.height();
  // Open cells: traversable and not within blocked_within of an obstacle.
  std::vector<uint8_t> open(grid.size());
  std::vector<float> factor(grid.size());
  for (size_t i = 0; i < grid.size(); ++i) {
    const uint8_t c = grid.cells()[i];
    open[i] = Traversable(c, params.unknown_is_free) &&
              (params.blocked_within <= 0.0 || distance == nullptr ||
               distance[i] >= params.blocked_within);
    factor[i] = static_cast<float>(CellFactor(c, params.cost_penalty));
  }
  auto field = std::make_shared<ObstacleHeuristic>();
  field->goal = params.goal;
  field->width = w;
  field->cost.assign(grid.size(), kInfinity);
  if (!grid.InBounds(params.goal)) return field;
  // Dial's buckets of width 1: every move costs at least 1 (a length of 1
  // or sqrt(2) times a factor >= 1), so a cell taken from bucket k (costs
  // in [k, k + 1)) only ever lowers cells into later buckets, and every
  // cell is final when its bucket comes up: exact, like Dijkstra, without
  // the heap (several times faster on a 1000 x 1000 map). A ring of
  // buckets one longer than the dearest move is enough.
  constexpr float kDiagonal = static_cast<float>(kSqrt2);
  const size_t ring =
      static_cast<size_t>(std::ceil(kSqrt2 * CellFactor(kMaxTraversableCost, params.cost_penalty))) +
      2;
  std::vector<std::vector<uint32_t>> buckets(ring);
  std::vector<uint8_t> settled(grid.size(), 0);
  const uint32_t goal = static_cast<uint32_t>(grid.Index(params.goal));
  field->cost[goal] = 0.0f;
  buckets[0].push_back(goal);
  size_t pending = 1;
  int64_t done = 0;
  const auto is_open = [&](int32_t cx, int32_t cy) {
    return cx >= 0 && cy >= 0 && cx < w && cy < h && open[grid.Index(cx, cy)];
  };
  for (size_t k = 0; pending > 0; ++k) {
    std::vector<uint32_t>& bucket = buckets[k % ring];
    // Cells pushed here while it is read are in later buckets: the ring is
    // longer than any move, so none lands in this slot.
    for (size_t i = 0; i < bucket.size(); ++i) {
      const uint32_t cell = bucket[i];
      --pending;
      if (settled[cell]) continue;
      settled[cell] = 1;
      if (++done % kPollCells == 0 && stop.Stopped()) return nullptr;
      const float here = field->cost[cell];
      const int32_t x = static_cast<int32_t>(cell % static_cast<uint32_t>(w));
      const int32_t y = static_cast<int32_t>(cell / static_cast<uint32_t>(w));
      // A robot moving from the neighbour into this cell pays this cell's
      // factor.
      const float f = factor[cell];
      for (const Move& m : kMoves) {
        const int32_t nx = x + m.dx;
        const int32_t ny = y + m.dy;
        if (!is_open(nx, ny)) continue;
        const bool diagonal = m.dx != 0 && m.dy != 0;
        if (diagonal && !is_open(x + m.dx, y) && !is_open(x, y + m.dy)) continue;
        const uint32_t next = static_cast<uint32_t>(grid.Index(nx, ny));
        const float cost = here + (diagonal ? kDiagonal : 1.0f) * f;
        if (cost < field->cost[next]) {
          field->cost[next] = cost;
          buckets[static_cast<size_t>(cost) % ring].push_back(next);
          ++pending;
        }
      }
    }
    bucket.clear();
  }
  return field;
}

std::shared_ptr<const ObstacleHeuristic> GetObstacleHeuristic(
    DerivedStore* store, const Grid& grid, const ObstacleHeuristicParams& params,
    DerivedStop& stop) {
  const std::string key = absl::StrFormat(
      "obstacle_heuristic goal=%d,%d unknown_is_free=%d cost_penalty=%.17g "
      "blocked_within=%.17g",
      params.goal.x, params.goal.y, params.unknown_is_free ? 1 : 0, params.cost_penalty,
      params.blocked_within);
  return GetDerived<ObstacleHeuristic>(
      store, grid, key,
      absl::StrFormat("the obstacle heuristic of goal (%d, %d) on this map version",
                      params.goal.x, params.goal.y),
      stop,
      [store, params](const Grid& g, DerivedStop& s) {
        std::shared_ptr<const std::vector<float>> distance;
        if (params.blocked_within > 0.0) {
          distance = GetObstacleDistance(store, g, params.unknown_is_free);
        }
        return BuildObstacleHeuristic(g, params, distance ? distance->data() : nullptr, s);
      },
      // A changed cell can change the cost-to-go of any cell: rebuild.
      [](const ObstacleHeuristic&, const Grid&, absl::Span<const Cell>, DerivedStop&) {
        return std::shared_ptr<const ObstacleHeuristic>();
      },
      [](const ObstacleHeuristic& field) { return field.bytes(); });
}

}  // namespace pathd
