// The radix heap against std::priority_queue on random monotone sequences
// (equal keys, 0, huge and tiny keys, pushes and pops interleaved, the rare
// key below the last pop), and MonotoneOpenList against the binary-heap
// OpenList and a textbook Dijkstra: the same settle order, bit-identical
// cost-to-go fields and Dijkstra costs. PATHD_RADIX_CASES=N caps the
// randomised counts.
#include "core/search/radix_heap.h"

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <limits>
#include <queue>
#include <random>
#include <utility>
#include <vector>

#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/planners/cost_to_go.h"
#include "core/search/best_first.h"
#include "core/search/open_list.h"
#include "core/search/path_measure.h"
#include "core/search/search_scratch.h"
#include "gtest/gtest.h"

namespace pathd::internal {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

int Cases(int fallback) {
  const char* env = std::getenv("PATHD_RADIX_CASES");
  const int scale = env != nullptr ? std::atoi(env) : 0;
  return scale > 0 ? std::min(fallback, scale) : fallback;
}

using Ref = std::priority_queue<std::pair<uint64_t, uint32_t>,
                                std::vector<std::pair<uint64_t, uint32_t>>,
                                std::greater<>>;

// A key at or above `last`: equal, a little above, a power of two above, or
// anywhere up to the largest key.
uint64_t NextKey(std::mt19937_64& rng, uint64_t last) {
  const uint64_t room = std::numeric_limits<uint64_t>::max() - last;
  switch (rng() % 6) {
    case 0:
      return last;
    case 1:
      return last + std::min<uint64_t>(room, rng() % 4);
    case 2:
      return last + std::min<uint64_t>(room, rng() % 1000);
    case 3:
      return last + std::min<uint64_t>(room, uint64_t{1} << (rng() % 64));
    case 4:
      return room == 0 ? last : last + rng() % room;
    default:
      return std::numeric_limits<uint64_t>::max() - rng() % 3 > last
                 ? std::numeric_limits<uint64_t>::max() - rng() % 3
                 : last;
  }
}

// Pops keys in the reference's order; every pushed (key, value) comes out
// once. `below` is the chance in 1000 of a push under the last pop.
void RunSequence(std::mt19937_64& rng, int ops, int below) {
  RadixHeap<uint32_t> heap;
  Ref ref;
  std::vector<std::pair<uint64_t, uint32_t>> pushed, popped;
  uint64_t last = 0;
  uint32_t next_value = 0;
  auto pop = [&] {
    ASSERT_EQ(heap.Top().key, ref.top().first);
    const auto e = heap.Pop();
    ASSERT_EQ(e.key, ref.top().first);
    ref.pop();
    popped.emplace_back(e.key, e.value);
    last = e.key;
  };
  for (int i = 0; i < ops; ++i) {
    if (!ref.empty() && rng() % 3 == 0) {
      pop();
    } else {
      uint64_t key = NextKey(rng, last);
      if (last > 0 && static_cast<int>(rng() % 1000) < below)
        key = rng() % last;
      heap.Push(key, next_value);
      ref.emplace(key, next_value);
      pushed.emplace_back(key, next_value++);
    }
    ASSERT_EQ(heap.size(), ref.size());
  }
  while (!ref.empty()) pop();
  EXPECT_TRUE(heap.empty());
  std::sort(pushed.begin(), pushed.end());
  std::sort(popped.begin(), popped.end());
  EXPECT_EQ(pushed, popped);
}

TEST(RadixHeap, MatchesPriorityQueueOnMonotoneSequences) {
  std::mt19937_64 rng(7);
  for (int round = 0; round < Cases(300); ++round) {
    RunSequence(rng, 1 + static_cast<int>(rng() % 2000), 0);
    if (testing::Test::HasFatalFailure()) return;
  }
}

TEST(RadixHeap, KeysBelowTheLastPopStillComeOutInOrder) {
  std::mt19937_64 rng(11);
  for (int round = 0; round < Cases(100); ++round) {
    RunSequence(rng, 1 + static_cast<int>(rng() % 1000), 20);
    if (testing::Test::HasFatalFailure()) return;
  }
}

TEST(RadixHeap, ClearForgetsEverything) {
  RadixHeap<uint32_t> heap;
  heap.Push(100, 1);
  heap.Push(5, 2);
  EXPECT_EQ(heap.Pop().key, 5u);
  heap.Clear();
  EXPECT_TRUE(heap.empty());
  heap.Push(3, 3);  // below the old last pop: Clear reset it
  heap.Push(0, 4);
  EXPECT_EQ(heap.Pop().key, 0u);
  EXPECT_EQ(heap.Pop().key, 3u);
  EXPECT_TRUE(heap.empty());
}

// OpenList's order: truncated key first, then the larger g.
bool OpenListBefore(double a, double b) {
  return OpenList::Key(a) < OpenList::Key(b) ||
         (OpenList::Key(a) == OpenList::Key(b) && a > b);
}

TEST(MonotoneOpenList, KeyOrdersLikeTheBinaryHeap) {
  std::vector<double> g = {0.0,
                           std::numeric_limits<double>::denorm_min(),
                           std::numeric_limits<double>::min(),
                           1e-300,
                           1.0,
                           std::nextafter(1.0, 2.0),
                           1.0 + 0x1p-40,
                           1.0 + 0x1p-31,
                           1.0 + 0x1p-33,
                           kSqrt2,
                           1.0 + kSqrt2,
                           kSqrt2 + 1.0,
                           1e12,
                           std::nextafter(1e12, 0.0),
                           1e300,
                           std::numeric_limits<double>::max()};
  std::mt19937_64 rng(3);
  for (int i = 0; i < 2000; ++i) {
    const double base =
        std::ldexp(1.0 + static_cast<double>(rng() % 1000) / 1000.0,
                   static_cast<int>(rng() % 80) - 20);
    g.push_back(base);
    g.push_back(
        std::bit_cast<double>(std::bit_cast<uint64_t>(base) + rng() % 4096));
  }
  for (double a : g) {
    EXPECT_EQ(MonotoneOpenList::GOf(MonotoneOpenList::KeyOf(a)), a);
    for (double b : g) {
      ASSERT_EQ(MonotoneOpenList::KeyOf(a) < MonotoneOpenList::KeyOf(b),
                OpenListBefore(a, b))
          << a << " vs " << b;
    }
  }
}

Grid RandomGrid(std::mt19937& rng) {
  const int w = 1 + static_cast<int>(rng() % 40);
  const int h = 1 + static_cast<int>(rng() % 40);
  Grid grid = Grid::Create(w, h).value();
  const int blocked_pct = static_cast<int>(rng() % 35);
  const bool costs = rng() % 2 == 0;
  for (uint8_t& v : grid.mutable_cells()) {
    if (static_cast<int>(rng() % 100) < blocked_pct) {
      v = kLethalCost;
    } else if (costs) {
      v = static_cast<uint8_t>(rng() % 253);
    }
  }
  return grid;
}

// Dijkstra from `goal` over reversed moves as a textbook writes it
// (std::priority_queue, lazy deletion), with its own move rule: a move
// u -> v costs its length times v's factor; diagonals need both side cells.
std::vector<double> TextbookField(const Grid& grid, Cell goal,
                                  const CostParams& cost) {
  const int w = grid.width(), h = grid.height();
  auto open = [&](int x, int y) {
    return x >= 0 && y >= 0 && x < w && y < h &&
           Traversable(grid.cost(x, y), cost.unknown_is_free);
  };
  std::vector<double> dist(grid.size(), kInf);
  std::priority_queue<std::pair<double, int>,
                      std::vector<std::pair<double, int>>, std::greater<>>
      queue;
  dist[goal.y * w + goal.x] = 0.0;
  queue.emplace(0.0, goal.y * w + goal.x);
  while (!queue.empty()) {
    const auto [d, v] = queue.top();
    queue.pop();
    if (d > dist[v]) continue;
    const int x = v % w, y = v / w;
    const double factor = CellFactor(grid.cost(x, y), cost.cost_weight);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !open(x + dx, y + dy)) continue;
        const bool diagonal = dx != 0 && dy != 0;
        if (diagonal && (cost.connectivity == Connectivity::kFour ||
                         !open(x + dx, y) || !open(x, y + dy))) {
          continue;
        }
        const int u = (y + dy) * w + x + dx;
        const double du = d + (diagonal ? kSqrt2 : 1.0) * factor;
        if (du < dist[u]) {
          dist[u] = du;
          queue.emplace(du, u);
        }
      }
    }
  }
  return dist;
}

// The fields and the settle order of the radix heap equal the binary heap's
// bit for bit (the order up to cells of equal g, compared by their g), and
// the fields equal a textbook Dijkstra's. A cost weight of 1e9 takes g past
// 2^32, where a move may no longer clear a key bucket of the truncated order
// (the radix heap's side list).
TEST(MonotoneOpenList, SettlesLikeTheBinaryHeap) {
  std::mt19937 rng(19);
  SearchScratch old_scratch, new_scratch;
  for (int round = 0; round < Cases(300); ++round) {
    const Grid grid = RandomGrid(rng);
    CostParams cost;
    cost.connectivity =
        rng() % 4 == 0 ? Connectivity::kFour : Connectivity::kEight;
    const double weights[] = {0.0, 1.0, 3.7, 1e9};
    cost.cost_weight = weights[rng() % 4];
    const Cell goal{static_cast<int32_t>(rng() % grid.width()),
                    static_cast<int32_t>(rng() % grid.height())};
    if (!Traversable(grid.cost(goal.x, goal.y), false)) continue;
    ExpansionRecorder old_order(grid.size()), new_order(grid.size());
    const CostToGoField old_field = DijkstraCostToGoOn<OpenList>(
        grid, goal, cost, StopCondition::None(), old_scratch, &old_order);
    const CostToGoField new_field = DijkstraCostToGoOn<MonotoneOpenList>(
        grid, goal, cost, StopCondition::None(), new_scratch, &new_order);
    ASSERT_EQ(new_field.outcome, PlanOutcome::kFound);
    ASSERT_EQ(new_field.expansions, old_field.expansions);
    ASSERT_EQ(new_order.cells().size(), old_order.cells().size());
    for (size_t i = 0; i < grid.size(); ++i) {
      ASSERT_EQ(std::bit_cast<uint64_t>(new_field.values[i]),
                std::bit_cast<uint64_t>(old_field.values[i]))
          << "round " << round << " cell " << i;
    }
    // Past 2^32 a move can stay inside a key bucket, so the keys are no
    // longer monotone and cells of exactly equal g, which either heap pops
    // in its own order, change what is found next: only the fields agree.
    for (size_t i = 0; cost.cost_weight < 1e9 && i < new_order.cells().size();
         ++i) {
      const Cell a = old_order.cells()[i], b = new_order.cells()[i];
      ASSERT_EQ(old_field.values[grid.Index(a.x, a.y)],
                new_field.values[grid.Index(b.x, b.y)])
          << "round " << round << " pop " << i;
    }
    const std::vector<double> textbook = TextbookField(grid, goal, cost);
    for (size_t i = 0; i < grid.size(); ++i) {
      ASSERT_EQ(std::bit_cast<uint64_t>(new_field.values[i]),
                std::bit_cast<uint64_t>(textbook[i]))
          << "round " << round << " cell " << i << ": " << new_field.values[i]
          << " vs " << textbook[i];
    }
  }
}

// Forward Dijkstra through the one loop: the same cost bit for bit with
// either open list, and the path found costs that when measured. (The
// expansion counts may differ by cells of exactly the goal's g, which the
// two heaps pop in different orders.)
TEST(MonotoneOpenList, DijkstraCostsMatchTheBinaryHeap) {
  std::mt19937 rng(23);
  SearchScratch old_scratch, new_scratch;
  for (int round = 0; round < Cases(300); ++round) {
    const Grid grid = RandomGrid(rng);
    CostParams cost;
    cost.cost_weight = rng() % 2 == 0 ? 1.0 : 1e9;
    const Cell start{static_cast<int32_t>(rng() % grid.width()),
                     static_cast<int32_t>(rng() % grid.height())};
    const Cell goal{static_cast<int32_t>(rng() % grid.width()),
                    static_cast<int32_t>(rng() % grid.height())};
    if (!Traversable(grid.cost(start.x, start.y), false) ||
        !Traversable(grid.cost(goal.x, goal.y), false)) {
      continue;
    }
    const PlanRequest request = PlanRequest::Between(start, goal, cost);
    const AStarPriority<ZeroHeuristic> dijkstra{};
    const PlanResult old_result = GridBestFirstSearch<OpenList>(
        grid, request, StopCondition::None(), old_scratch, dijkstra);
    const PlanResult new_result = GridBestFirstSearch<MonotoneOpenList>(
        grid, request, StopCondition::None(), new_scratch, dijkstra);
    ASSERT_EQ(new_result.outcome, old_result.outcome) << "round " << round;
    EXPECT_EQ(std::bit_cast<uint64_t>(new_result.cost),
              std::bit_cast<uint64_t>(old_result.cost))
        << "round " << round;
    if (new_result.found()) {
      ASSERT_FALSE(new_result.path.empty());
      EXPECT_EQ(new_result.path.front(), start);
      EXPECT_EQ(new_result.path.back(), goal);
      const PathMeasure measure = MeasurePath(grid, new_result.path, cost);
      EXPECT_TRUE(measure.valid) << "round " << round;
      EXPECT_EQ(measure.cost, new_result.cost) << "round " << round;
    }
  }
}

}  // namespace
}  // namespace pathd::internal
