// The wave-front planner against the worked example of the lecture "Path
// Planning in Discrete Sampled Space" ("Wave-Front Planner"; the 16 x 16 map
// bundled as maps/wavefront16.map) and against a reference breadth-first
// search on random grids, 4- and 8-connected.
#include "core/search/registry.h"
#include "core/search/path_measure.h"
#include "core/planners/wavefront.h"

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"

namespace pathd {
namespace {

constexpr int kSide = 16;
constexpr Cell kExampleStart{0, 15};  // "*" / "start", bottom left
constexpr Cell kExampleGoal{15, 0};   // labelled 2, top right
constexpr int kNotPrinted = -1;

// The final label table of the lecture (the slide after "to generate a path
// starting from the start point", repeated under "Goal Potential"),
// transcribed by hand. It is not parsed from the lecture's text at run time:
// the extracted text puts the "goal"/"start" caption into the last row and prints
// 15 values for its 16 cells, so a parser would need special cases for
// exactly this table. The last row's values fit columns 0..13 and 15 (the
// final 37 sits under 36); column 14's label is missing.
constexpr int kPrinted[kSide][kSide] = {
    {17, 16, 15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3, 2},
    {18, 17, 16, 15, 14, 13, 12, 11, 10, 9, 8, 7, 6, 5, 4, 3},
    {19, 18, 1, 1, 15, 14, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1},
    {20, 19, 1, 1, 16, 15, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1},
    {21, 20, 1, 1, 17, 16, 17, 18, 19, 20, 21, 22, 1, 1, 37, 38},
    {1, 1, 1, 1, 18, 17, 18, 19, 20, 21, 22, 23, 1, 1, 36, 37},
    {1, 1, 1, 1, 19, 18, 19, 20, 21, 22, 23, 24, 1, 1, 35, 36},
    {0, 0, 1, 1, 20, 19, 20, 21, 22, 23, 24, 25, 1, 1, 34, 35},
    {0, 0, 1, 1, 1, 1, 1, 1, 23, 24, 1, 1, 1, 1, 33, 34},
    {0, 0, 1, 1, 1, 1, 1, 1, 24, 25, 1, 1, 1, 1, 32, 33},
    {0, 0, 1, 1, 29, 28, 27, 26, 25, 26, 27, 28, 29, 30, 31, 32},
    {0, 0, 1, 1, 30, 29, 28, 27, 26, 27, 28, 29, 30, 31, 32, 33},
    {0, 51, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 33, 34},
    {51, 50, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 1, 34, 35},
    {50, 49, 48, 46, 45, 44, 43, 42, 41, 40, 39, 38, 37, 36, 35, 36},
    {51, 50, 49, 47, 46, 45, 44, 43, 42, 41, 40, 39, 38, 37, kNotPrinted, 37},
};

// Where the hand-made table departs from its own algorithm. At (2, 14) it
// jumps from the 46 beside it to 48 (the flood gives every free neighbour of
// a 46 the label 47), and every label reached through that cell is one too
// high as a result, the start's included (51 instead of 50). With the start
// at 50 the flood stops after the layer labelled 50, so (0, 12), printed 0,
// stays 0 in both. PrintedTableBreaksItsRuleOnlyWhereTheErrataStart checks
// this reading against the table itself.
struct Erratum {
  Cell cell;
  int printed;
  int label;
};
constexpr Erratum kErrata[] = {
    {{2, 14}, 48, 47},  // the jump: its neighbour (3, 14) is 46
    {{1, 14}, 49, 48},
    {{0, 14}, 50, 49},
    {{1, 13}, 50, 49},
    {{0, 13}, 51, 50},
    {{1, 12}, 51, 50},
    {{2, 15}, 49, 48},  // beside (3, 15) = 47
    {{1, 15}, 50, 49},
    {{0, 15}, 51, 50},  // the start
    {{14, 15}, kNotPrinted, 36},
};

const Erratum* FindErratum(Cell c) {
  for (const Erratum& e : kErrata) {
    if (e.cell == c) return &e;
  }
  return nullptr;
}

Grid ExampleMap() {
  absl::StatusOr<Grid> grid = ReadMovingAiMapFile("maps/wavefront16.map");
  EXPECT_TRUE(grid.ok()) << grid.status();
  return grid.ok() ? *std::move(grid) : Grid();
}

CostParams FourConnected() {
  CostParams cost;
  cost.connectivity = Connectivity::kFour;
  return cost;
}

TEST(WavefrontLectureExample, BundledMapHasTheNotesObstacles) {
  const Grid grid = ExampleMap();
  ASSERT_EQ(grid.width(), kSide);
  ASSERT_EQ(grid.height(), kSide);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      EXPECT_EQ(grid.cost(x, y) == kLethalCost, kPrinted[y][x] == 1)
          << "cell (" << x << ", " << y << ")";
    }
  }
}

TEST(WavefrontLectureExample, LabelsMatchTheNotesFinalTable) {
  const Grid grid = ExampleMap();
  ASSERT_EQ(grid.size(), static_cast<size_t>(kSide * kSide));
  const WavefrontLabelling w =
      WavefrontLabels(grid, kExampleGoal, FourConnected(), kExampleStart);
  EXPECT_EQ(w.outcome, PlanOutcome::kFound);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const int label = w.labels[grid.Index(x, y)];
      if (const Erratum* e = FindErratum(Cell{x, y}); e != nullptr) {
        EXPECT_EQ(kPrinted[y][x], e->printed)
            << "transcription at (" << x << ", " << y << ")";
        EXPECT_EQ(label, e->label) << "cell (" << x << ", " << y << ")";
      } else {
        EXPECT_EQ(label, kPrinted[y][x]) << "cell (" << x << ", " << y << ")";
      }
    }
  }
}

// The notes' rule: a free cell labelled L > 2 has a 4-neighbour labelled
// L - 1 and none lower. The printed table keeps it everywhere except at the
// two cells where the error enters: (2, 14), and (2, 15) below it, whose
// printed 49 sits beside a 47. Every other erratum is consistent with its
// (wrong) neighbours.
TEST(WavefrontLectureExample, PrintedTableBreaksItsRuleOnlyWhereTheErrataStart) {
  std::vector<std::pair<int, int>> broken;
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const int label = kPrinted[y][x];
      if (label <= 2) continue;
      int lowest = 1000;
      for (int m = 0; m < 4; ++m) {
        const int nx = x + kMoves[m].dx, ny = y + kMoves[m].dy;
        if (nx < 0 || ny < 0 || nx >= kSide || ny >= kSide) continue;
        if (kPrinted[ny][nx] >= 2) lowest = std::min(lowest, kPrinted[ny][nx]);
      }
      if (lowest != label - 1) broken.emplace_back(x, y);
    }
  }
  EXPECT_EQ(broken, (std::vector<std::pair<int, int>>{{2, 14}, {2, 15}}));
}

TEST(WavefrontLectureExample, PathDescendsTheLabelsFromStartToGoal) {
  const Grid grid = ExampleMap();
  const Planner* planner = PlannerRegistry::Default().Get("wavefront");
  ASSERT_NE(planner, nullptr);
  SearchScratch scratch;
  const CostParams cost = FourConnected();
  auto r = planner->Plan(grid, PlanRequest::Between(kExampleStart, kExampleGoal, cost),
                         StopCondition::None(), scratch);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->found());
  const WavefrontLabelling w = WavefrontLabels(grid, kExampleGoal, cost, kExampleStart);
  ASSERT_EQ(r->path.size(), 49u);  // start label 50, goal 2
  EXPECT_EQ(r->path.front(), kExampleStart);
  EXPECT_EQ(r->path.back(), kExampleGoal);
  for (size_t i = 0; i < r->path.size(); ++i) {
    EXPECT_EQ(w.labels[grid.Index(r->path[i])], 50 - static_cast<int>(i)) << "step " << i;
  }
  // Tie-break: from the start both (1, 15) and (0, 14) are labelled 49; the
  // move order tries +x first.
  EXPECT_EQ(r->path[1], (Cell{1, 15}));
  const PathMeasure m = MeasurePath(grid, r->path, cost);
  ASSERT_TRUE(m.valid);
  EXPECT_DOUBLE_EQ(r->cost, m.cost);
  EXPECT_DOUBLE_EQ(r->length, 48.0);
}

TEST(WavefrontLectureExample, EightConnectedFloodCountsDiagonalMoves) {
  const Grid grid = ExampleMap();
  const CostParams eight;
  const WavefrontLabelling w = WavefrontLabels(grid, kExampleGoal, eight, kExampleStart);
  ASSERT_EQ(w.outcome, PlanOutcome::kFound);
  EXPECT_EQ(w.labels[grid.Index(14, 1)], 3);  // one diagonal move from the goal
  const int start_moves = MoveCounts(grid, kExampleGoal, eight)[grid.Index(kExampleStart)];
  EXPECT_EQ(w.labels[grid.Index(kExampleStart)], kWavefrontGoal + start_moves);
  EXPECT_LT(start_moves, 48);  // the 4-connected count
}

TEST(Wavefront, RandomGridsMatchAReferenceBreadthFirstSearch) {
  std::mt19937 rng(4004);
  const Planner* planner = PlannerRegistry::Default().Get("wavefront");
  ASSERT_NE(planner, nullptr);
  SearchScratch scratch;
  int found = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 16);
    const int h = 1 + static_cast<int>(rng() % 16);
    Grid grid = Grid::Create(w, h).value();
    const int blocked_pct = static_cast<int>(rng() % 45);
    for (uint8_t& v : grid.mutable_cells()) {
      const int roll = static_cast<int>(rng() % 100);
      if (roll < blocked_pct) {
        v = rng() % 4 == 0 ? kUnknownCost : kLethalCost;
      } else if (rng() % 3 == 0) {
        v = static_cast<uint8_t>(rng() % 253);
      }
    }
    CostParams cost;
    cost.connectivity = trial % 2 == 0 ? Connectivity::kFour : Connectivity::kEight;
    cost.unknown_is_free = trial % 3 == 0;
    const Cell goal{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    const Cell start{static_cast<int32_t>(rng() % w), static_cast<int32_t>(rng() % h)};
    grid.set_cost(goal, kFreeCost);
    grid.set_cost(start, kFreeCost);
    const std::vector<int> reference = MoveCounts(grid, goal, cost);

    // Without a start the flood labels everything reachable.
    const WavefrontLabelling all = WavefrontLabels(grid, goal, cost, std::nullopt);
    ASSERT_EQ(all.outcome, PlanOutcome::kFound);
    for (size_t i = 0; i < grid.size(); ++i) {
      const bool blocked = !Traversable(grid.cells()[i], cost.unknown_is_free);
      const int expected = blocked            ? kWavefrontObstacle
                           : reference[i] < 0 ? kWavefrontUnlabelled
                                              : kWavefrontGoal + reference[i];
      ASSERT_EQ(all.labels[i], expected) << "trial " << trial << " cell " << i;
    }

    // With a start it stops after the start's layer.
    const WavefrontLabelling until = WavefrontLabels(grid, goal, cost, start);
    const int start_moves = reference[grid.Index(start)];
    ASSERT_EQ(until.outcome,
              start_moves < 0 ? PlanOutcome::kNoPath : PlanOutcome::kFound);
    if (start_moves >= 0) {
      for (size_t i = 0; i < grid.size(); ++i) {
        if (reference[i] >= 0) {
          ASSERT_EQ(until.labels[i],
                    reference[i] <= start_moves ? all.labels[i] : kWavefrontUnlabelled)
              << "trial " << trial << " cell " << i;
        }
      }
    }

    auto r = planner->Plan(grid, PlanRequest::Between(start, goal, cost),
                           StopCondition::None(), scratch);
    ASSERT_TRUE(r.ok()) << r.status();
    if (start_moves < 0) {
      EXPECT_EQ(r->outcome, PlanOutcome::kNoPath);
      continue;
    }
    ++found;
    ASSERT_TRUE(r->found());
    ASSERT_EQ(r->path.size(), static_cast<size_t>(start_moves) + 1) << "trial " << trial;
    for (size_t i = 0; i < r->path.size(); ++i) {
      ASSERT_EQ(all.labels[grid.Index(r->path[i])],
                kWavefrontGoal + start_moves - static_cast<int>(i));
    }
    const PathMeasure m = MeasurePath(grid, r->path, cost);
    ASSERT_TRUE(m.valid) << "trial " << trial;
    EXPECT_DOUBLE_EQ(r->cost, m.cost);
    EXPECT_DOUBLE_EQ(r->length, m.length);
  }
  EXPECT_GT(found, 200);
}

TEST(Wavefront, ExpansionBudgetStopsTheFlood) {
  const Grid grid = ExampleMap();
  const WavefrontLabelling w =
      WavefrontLabels(grid, kExampleGoal, FourConnected(), kExampleStart,
                      StopCondition(absl::InfiniteFuture(), nullptr, 20));
  EXPECT_EQ(w.outcome, PlanOutcome::kExpansionLimit);
  EXPECT_EQ(w.expansions, 20);
}

}  // namespace
}  // namespace pathd
