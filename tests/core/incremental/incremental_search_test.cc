// LPA*, D* Lite and the shortest path map (core/incremental/incremental_search.h):
// the lecture's D* Lite example value for value, and long random sequences of
// map changes and robot moves checked after every step against an independent
// Dijkstra. The edge cases are in incremental_cases_test.cc.
#include "core/search/path_measure.h"
#include "core/incremental/incremental_search.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <queue>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/time/clock.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/incremental/engine.h"
#include "core/map_io/map_io.h"
#include "core/search/planner.h"
#include "gtest/gtest.h"
#include "tests/testing/test_grids.h"
#include "tests/core/incremental/incremental_test_util.h"

namespace pathd {
namespace {

using internal::IncrementalAccess;
using internal::MoveRules;
using namespace testing_incremental;  // NOLINT: test helpers


// ---------------------------------------------------------------------------
// The "D* Lite – Example" of Faigl's lecture "Path Planning" (B4M36UIR,
// Lecture 03):
// a 5 x 4 grid labelled "row,col" with row 0 at the bottom, goal 0,0, start
// 2,4, obstacles 1,1, 1,2 and 0,2; 8-connected, straight moves cost 1 and
// diagonal ones 1.4, moves only to and from obstacles are infinite (slide 6
// gives 2,1 rhs 2.4 through the corner of obstacle 1,1), h = 0. The robot
// follows the g gradient from 2,4 to 2,3; while it moves on towards 2,2 that
// cell turns out to be an obstacle (slide 25) and D* Lite replans.
//
// The notes print full tables only up to slide 10; the tables below are the
// states the slides narrate, and every value the text states is one of them:
// first search (slides 12-22), the start 2,4 settles at g = rhs = 5.4 after
// 1,3 and 3,3 at 4.8 push 0,3 and 0,4 on the open list; replan: 3,3 stays
// consistent at 4.8 through 3,2 (slide 27), 2,3 ends at 5.2 = 3.8 + 1.4
// through 3,2 (slides 28, 37), 2,4 becomes inconsistent, 1,4 keeps rhs 5.8
// then rises, 0,3 and 0,4 end consistent at infinity (slide 35), and 1,3
// ends inconsistent (slide 38).
//
// Rows top (row 3) to bottom (row 0), columns 0..4, each "g/rhs" ("#" is an
// obstacle: g = rhs = infinity).
const std::vector<std::string> kAfterFirstSearch = {
    "3/3     3.4/3.4  3.8/3.8  4.8/4.8  inf/5.8",
    "2/2     2.4/2.4  3.4/3.4  4.4/4.4  5.4/5.4",
    "1/1     #        #        4.8/4.8  inf/5.8",
    "0/0     1/1      #        inf/5.8  inf/6.2",
};
const std::vector<std::string> kAfterReplan = {
    "3/3     3.4/3.4  3.8/3.8  4.8/4.8  inf/5.8",
    "2/2     2.4/2.4  #        5.2/5.2  5.4/6.2",
    "1/1     #        #        inf/6.2  inf/6.4",
    "0/0     1/1      #        inf/inf  inf/inf",
};

// Notes' "row,col" to our cell: column is x, row is y.
Cell NotesCell(int row, int col) { return Cell{col, row}; }

double ParseValue(const std::string& s) { return s == "inf" ? kInf : std::stod(s); }

void ExpectTable(const DStarLite& dstar, const std::vector<std::string>& table,
                 const std::string& when) {
  for (int r = 0; r < 4; ++r) {
    const int row = 3 - r;
    const std::vector<std::string> entries =
        absl::StrSplit(table[r], ' ', absl::SkipWhitespace());
    ASSERT_EQ(entries.size(), 5u);
    for (int col = 0; col < 5; ++col) {
      double g = kInf, rhs = kInf;
      if (entries[col] != "#") {
        const std::vector<std::string> parts = absl::StrSplit(entries[col], '/');
        g = ParseValue(parts[0]);
        rhs = ParseValue(parts[1]);
      }
      const Cell c = NotesCell(row, col);
      const std::string where = absl::StrFormat("%s: cell %d,%d", when, row, col);
      EXPECT_TRUE(Near(dstar.g(c), g, 1e-12)) << where << " g " << dstar.g(c);
      EXPECT_TRUE(Near(dstar.rhs(c), rhs, 1e-12)) << where << " rhs " << dstar.rhs(c);
    }
  }
}

// The notes' robot step: to the neighbour minimising c + g under the notes'
// move rules (diagonals 1.4, corners may be cut).
Cell NotesStep(const DStarLite& dstar, Cell from) {
  Cell best = from;
  double best_sum = kInf;
  for (const Move& m : kMoves) {
    const Cell n{from.x + m.dx, from.y + m.dy};
    if (!dstar.grid().InBounds(n) || dstar.grid().cost(n) != kFreeCost) continue;
    const double sum = (m.dx != 0 && m.dy != 0 ? 1.4 : 1.0) + dstar.g(n);
    if (sum < best_sum) {
      best_sum = sum;
      best = n;
    }
  }
  return best;
}

TEST(DStarLiteNotesExample, GAndRhsMatchTheNotesAfterSearchAndReplan) {
  Grid grid = Grid::Create(5, 4).value();
  for (const Cell c : {NotesCell(1, 1), NotesCell(1, 2), NotesCell(0, 2)}) {
    grid.set_cost(c, kLethalCost);
  }
  const MoveRules notes_rules{.diagonal_length = 1.4, .corner_cutting = true,
                              .heuristic = false};
  auto dstar = IncrementalAccess::CreateDStarLite(Share(grid), NotesCell(0, 0),
                                                  CostParams{}, notes_rules);
  ASSERT_TRUE(dstar.ok()) << dstar.status();
  DStarLite& d = **dstar;
  // Initialisation (slide 1): rhs(goal) = 0, everything else infinite.
  EXPECT_EQ(d.rhs(NotesCell(0, 0)), 0.0);
  EXPECT_EQ(d.g(NotesCell(0, 0)), kInf);
  EXPECT_EQ(d.rhs(NotesCell(2, 4)), kInf);

  ASSERT_TRUE(d.SetStart(NotesCell(2, 4)).ok());
  ASSERT_EQ(IncrementalAccess::ComputeShortestPath(d, StopCondition::None()),
            PlanOutcome::kFound);
  ExpectTable(d, kAfterFirstSearch, "after the first search");

  // Slides 23-25: the robot follows the gradient to 2,3 and would go on to
  // 2,2, which it then sees blocked.
  const Cell robot = NotesStep(d, NotesCell(2, 4));
  EXPECT_EQ(robot, NotesCell(2, 3));
  EXPECT_EQ(NotesStep(d, robot), NotesCell(2, 2));
  ASSERT_TRUE(d.SetStart(robot).ok());
  EXPECT_EQ(d.km(), 0.0);  // h = 0
  grid.set_cost(NotesCell(2, 2), kLethalCost);
  const std::vector<Cell> changed{NotesCell(2, 2)};
  ASSERT_TRUE(d.UpdateMap(Share(grid), changed).ok());
  // Slides 26-29: the update alone makes 2,2, 2,3 and 1,3 inconsistent.
  EXPECT_EQ(d.rhs(NotesCell(2, 2)), kInf);
  EXPECT_NEAR(d.rhs(NotesCell(2, 3)), 5.2, 1e-12);
  EXPECT_NEAR(d.g(NotesCell(2, 3)), 4.4, 1e-12);
  EXPECT_NEAR(d.rhs(NotesCell(1, 3)), 5.4, 1e-12);
  EXPECT_NEAR(d.rhs(NotesCell(3, 3)), 4.8, 1e-12);
  EXPECT_NEAR(d.g(NotesCell(3, 3)), 4.8, 1e-12);

  ASSERT_EQ(IncrementalAccess::ComputeShortestPath(d, StopCondition::None()),
            PlanOutcome::kFound);
  ExpectTable(d, kAfterReplan, "after the replan");
  // Slide 39: the new path leaves 2,3 diagonally for 3,2.
  EXPECT_EQ(NotesStep(d, robot), NotesCell(3, 2));
}

// The same map under DESIGN.md's rules (sqrt(2) diagonals, no corner cutting,
// octile heuristic) through the public API: the replanned path goes around.
TEST(DStarLiteNotesExample, PublicApiReplansAroundTheNewObstacle) {
  Grid grid = MakeGrid({"..#..", ".##..", ".....", "....."});
  auto shared = Share(grid);
  auto dstar = DStarLite::Create(shared, {0, 0}, CostParams{});
  ASSERT_TRUE(dstar.ok());
  ASSERT_TRUE((*dstar)->SetStart({4, 2}).ok());
  auto first = (*dstar)->Plan(StopCondition::None());
  ASSERT_TRUE(first.ok() && first->found());
  const std::vector<double> ref = ReferenceCostToGo(grid, {0, 0}, {});
  EXPECT_NEAR(first->cost, ref[grid.Index(4, 2)], 1e-9);
  ASSERT_TRUE((*dstar)->SetStart({3, 2}).ok());
  grid.set_cost(2, 2, kLethalCost);
  const std::vector<Cell> changed{{2, 2}};
  ASSERT_TRUE((*dstar)->UpdateMap(Share(grid), changed).ok());
  auto second = (*dstar)->Plan(StopCondition::None());
  ASSERT_TRUE(second.ok() && second->found()) << second.status();
  EXPECT_NEAR(second->cost, ReferenceCostToGo(grid, {0, 0}, {})[grid.Index(3, 2)], 1e-9);
  for (const Cell c : second->path) EXPECT_NE(c, (Cell{2, 2}));
  EXPECT_EQ((*dstar)->last_stats().changed_cells, 1);
  EXPECT_GT((*dstar)->last_stats().expansions, 0);
}

// ---------------------------------------------------------------------------
// Random sequences.


// After every step of thousands of random sequences (map changes: single
// cells and clusters that block, free or re-weight; robot moves along the path
// or jumps), D* Lite, LPA* (fixed start) and the shortest path map agree with
// a fresh Dijkstra: same cost (double searches to 1e-9, the float field's
// descent to 1e-5 relative), found exactly when reachable, legal paths that
// cost what they claim, the whole field within float rounding of the
// reference, and the repaired field equal bit for bit to one built from
// scratch on the same map.
TEST(IncrementalEquivalence, RandomChangesAndMovesMatchDijkstra) {
  std::mt19937 rng(5150);
  constexpr int kSequences = 4000;
  constexpr int kSteps = 24;
  int64_t checks = 0, found = 0, repaired = 0, rebuilt = 0;
  for (int seq = 0; seq < kSequences; ++seq) {
    const int w = 4 + static_cast<int>(rng() % 29);
    const int h = 4 + static_cast<int>(rng() % 29);
    const bool weighted = seq % 3 != 0;
    World world{Grid::Create(w, h).value(), CostParams{}};
    for (uint8_t& v : world.grid.mutable_cells()) v = RandomCellValue(rng, weighted);
    world.cost.connectivity = seq % 2 ? Connectivity::kFour : Connectivity::kEight;
    world.cost.cost_weight = seq % 5 == 0 ? 0.0 : static_cast<double>(rng() % 400) / 100.0;
    world.cost.unknown_is_free = seq % 7 == 0;
    const Cell goal = RandomCell(rng, world.grid);
    Cell robot = RandomCell(rng, world.grid);
    world.grid.set_cost(goal, kFreeCost);
    world.grid.set_cost(robot, kFreeCost);
    const Cell lpa_start = robot;
    auto grid = Share(world.grid);

    auto dstar = DStarLite::Create(grid, goal, world.cost);
    auto lpa = LpaStar::Create(grid, lpa_start, goal, world.cost);
    auto spm = ShortestPathMap::Build(grid, goal, world.cost, StopCondition::None());
    ASSERT_TRUE(dstar.ok() && lpa.ok() && spm.ok()) << "sequence " << seq;
    ASSERT_TRUE((*dstar)->SetStart(robot).ok());
    std::vector<Cell> last_path;

    for (int step = 0; step < kSteps; ++step) {
      const std::string where = absl::StrFormat("sequence %d step %d", seq, step);
      if (step > 0) {
        const int action = static_cast<int>(rng() % 10);
        if (action < 6) {
          // A map change: one cell, a small cluster or a few scattered cells;
          // the ends are spared most of the time.
          Grid next = *grid;
          std::vector<Cell> changed;
          const int kind = static_cast<int>(rng() % 3);
          const Cell at = RandomCell(rng, next);
          const uint8_t value = RandomCellValue(rng, weighted);
          const int count = kind == 0 ? 1 : 2 + static_cast<int>(rng() % 7);
          for (int k = 0; k < count; ++k) {
            Cell c = at;
            if (kind == 1) {
              c = Cell{at.x + static_cast<int32_t>(rng() % 3) - 1,
                       at.y + static_cast<int32_t>(rng() % 3) - 1};
            } else if (kind == 2) {
              c = RandomCell(rng, next);
            }
            if (!next.InBounds(c)) continue;
            if ((c == goal || c == robot || c == lpa_start) && rng() % 8 != 0) continue;
            const uint8_t v = kind == 2 ? RandomCellValue(rng, weighted) : value;
            next.set_cost(c, v);
            changed.push_back(c);  // cells may repeat, unchanged ones too
          }
          grid = Share(std::move(next));
          ASSERT_TRUE((*dstar)->UpdateMap(grid, changed).ok()) << where;
          ASSERT_TRUE((*lpa)->UpdateMap(grid, changed).ok()) << where;
          ASSERT_TRUE((*spm)->UpdateMap(grid, changed).ok()) << where;
          ((*spm)->last_stats().rebuilt ? rebuilt : repaired) += 1;
        } else if (action < 9 && last_path.size() > 1) {
          // Along the current path.
          robot = last_path[1 + rng() % std::min<size_t>(last_path.size() - 1, 4)];
          ASSERT_TRUE((*dstar)->SetStart(robot).ok());
        } else {
          robot = RandomCell(rng, *grid);
          ASSERT_TRUE((*dstar)->SetStart(robot).ok());
        }
      }

      const std::vector<double> ref = ReferenceCostToGo(*grid, goal, world.cost);
      const bool robot_free = Traversable(grid->cost(robot), world.cost.unknown_is_free);

      // D* Lite, sometimes stopped by a small budget first and then resumed.
      if (rng() % 5 == 0) {
        auto partial = (*dstar)->Plan(
            StopCondition(absl::InfiniteFuture(), nullptr, 1 + rng() % 16));
        if (!robot_free) {
          ASSERT_EQ(partial.status().code(), absl::StatusCode::kInvalidArgument) << where;
        } else {
          ASSERT_TRUE(partial.ok()) << where << ": " << partial.status();
        }
      }
      auto d = (*dstar)->Plan(StopCondition::None());
      last_path.clear();
      if (!robot_free) {
        ASSERT_EQ(d.status().code(), absl::StatusCode::kInvalidArgument) << where;
      } else {
        ASSERT_TRUE(d.ok()) << where << ": " << d.status();
        const double optimum = ref[grid->Index(robot)];
        ASSERT_EQ(d->found(), std::isfinite(optimum)) << where;
        if (d->found()) {
          ++found;
          const PathMeasure m = MeasurePath(*grid, d->path, world.cost);
          ASSERT_TRUE(m.valid) << where;
          ASSERT_EQ(d->path.front(), robot);
          ASSERT_EQ(d->path.back(), goal);
          ASSERT_TRUE(Near(d->cost, m.cost, 1e-12)) << where;
          ASSERT_TRUE(Near(d->cost, optimum, 1e-9)) << where << ": " << d->cost
                                                    << " vs " << optimum;
          last_path = d->path;
        } else {
          ASSERT_EQ(d->outcome, PlanOutcome::kNoPath) << where;
        }
      }

      // LPA* from its fixed start.
      auto l = (*lpa)->Plan(StopCondition::None());
      ASSERT_TRUE(l.ok()) << where << ": " << l.status();
      const bool lpa_start_free =
          Traversable(grid->cost(lpa_start), world.cost.unknown_is_free);
      const double lpa_optimum = lpa_start_free ? ref[grid->Index(lpa_start)] : kInf;
      ASSERT_EQ(l->found(), std::isfinite(lpa_optimum)) << where;
      if (l->found()) {
        const PathMeasure m = MeasurePath(*grid, l->path, world.cost);
        ASSERT_TRUE(m.valid) << where;
        ASSERT_EQ(l->path.front(), lpa_start);
        ASSERT_EQ(l->path.back(), goal);
        ASSERT_TRUE(Near(l->cost, lpa_optimum, 1e-9)) << where;
      }

      // The shortest path map: every cell, and a descent from the robot.
      const absl::Span<const float> field = (*spm)->field();
      for (size_t i = 0; i < grid->size(); ++i) {
        if (grid->CellAt(i) == goal) {
          // Blocked or not, the goal is the root of the field.
          ASSERT_EQ(field[i], 0.0f) << where;
          continue;
        }
        if (!Traversable(grid->cost(grid->CellAt(i)), world.cost.unknown_is_free)) {
          ASSERT_TRUE(std::isinf(field[i])) << where << " cell " << i;
          continue;
        }
        ASSERT_TRUE(Near(field[i], ref[i], 1e-5))
            << where << " cell " << CellToString(grid->CellAt(i)) << ": " << field[i]
            << " vs " << ref[i];
      }
      if (Traversable(grid->cost(goal), world.cost.unknown_is_free)) {
        auto fresh =
            ShortestPathMap::Build(grid, goal, world.cost, StopCondition::None());
        ASSERT_TRUE(fresh.ok()) << where << ": " << fresh.status();
        ASSERT_TRUE(std::equal(field.begin(), field.end(), (*fresh)->field().begin()))
            << where << ": the repaired field differs from a rebuilt one";
      }
      auto s = (*spm)->PathFrom(robot);
      if (!robot_free) {
        ASSERT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument) << where;
      } else {
        ASSERT_TRUE(s.ok()) << where << ": " << s.status();
        const double optimum = ref[grid->Index(robot)];
        ASSERT_EQ(s->found(), std::isfinite(optimum)) << where;
        if (s->found()) {
          const PathMeasure m = MeasurePath(*grid, s->path, world.cost);
          ASSERT_TRUE(m.valid) << where;
          ASSERT_EQ(s->path.back(), goal);
          ASSERT_TRUE(Near(s->cost, m.cost, 1e-12)) << where;
          // The float field's descent is optimal up to its rounding.
          ASSERT_TRUE(Near(s->cost, optimum, 1e-5)) << where;
        }
      }
      ++checks;
    }
  }
  // The sequences exercise what they are meant to.
  EXPECT_GT(found, checks / 3);
  EXPECT_GT(repaired, 1000);
  EXPECT_GT(rebuilt, 100);
}

// A field built on the radix heap (ComputeFromReset) is the binary heap's
// (Compute) bit for bit with the same expansions, and a build stopped half
// way and finished by Compute is too.
TEST(ShortestPathMapBuild, RadixHeapBuildEqualsTheGeneralLoop) {
  using FieldSearch = internal::IncrementalSearch<internal::FieldConfig>;
  std::mt19937 rng(90210);
  for (int trial = 0; trial < 300; ++trial) {
    const int w = 1 + static_cast<int>(rng() % 60);
    const int h = 1 + static_cast<int>(rng() % 60);
    Grid grid = Grid::Create(w, h).value();
    for (uint8_t& v : grid.mutable_cells()) v = RandomCellValue(rng, trial % 3 != 0);
    CostParams cost;
    cost.connectivity = trial % 2 ? Connectivity::kFour : Connectivity::kEight;
    cost.cost_weight = trial % 5 == 0 ? 0.0 : static_cast<double>(rng() % 1000) / 10.0;
    cost.unknown_is_free = trial % 7 == 0;
    const Cell goal = RandomCell(rng, grid);
    grid.set_cost(goal, kFreeCost);
    const auto shared = Share(grid);
    FieldSearch general(shared, cost, internal::MoveRules(), goal);
    FieldSearch radix(shared, cost, internal::MoveRules(), goal);
    FieldSearch resumed(shared, cost, internal::MoveRules(), goal);
    general.Reset();
    radix.Reset();
    resumed.Reset();
    const auto g = general.Compute(StopCondition::None());
    const auto r = radix.ComputeFromReset(StopCondition::None());
    const int64_t half = std::max<int64_t>(1, g.expansions / 2);
    const auto first = resumed.ComputeFromReset(StopCondition(absl::InfiniteFuture(), nullptr, half));
    const auto rest = resumed.Compute(StopCondition::None());
    ASSERT_EQ(g.outcome, PlanOutcome::kFound);
    ASSERT_EQ(r.outcome, PlanOutcome::kFound);
    EXPECT_EQ(r.expansions, g.expansions) << "trial " << trial;
    ASSERT_EQ(rest.outcome, PlanOutcome::kFound);
    if (g.expansions > half) {
      EXPECT_EQ(first.outcome, PlanOutcome::kExpansionLimit) << "trial " << trial;
    }
    for (size_t i = 0; i < grid.size(); ++i) {
      const auto c = static_cast<uint32_t>(i);
      ASSERT_EQ(std::bit_cast<uint32_t>(radix.g(c)), std::bit_cast<uint32_t>(general.g(c)))
          << "trial " << trial << " cell " << i;
      ASSERT_EQ(std::bit_cast<uint32_t>(resumed.g(c)), std::bit_cast<uint32_t>(general.g(c)))
          << "trial " << trial << " cell " << i << " (stopped, then Compute)";
    }
  }
}

// The float field's descent is optimal to 1e-9 (what the Moving AI conformance
// demands of optimal planners) from every cell of the shared Moving AI maps, a
// few goals each: its rounding never flips a choice between two routes there.
TEST(ShortestPathMapOnMovingAi, DescentFromEveryCellIsOptimal) {
  const std::filesystem::path root = "../shared/benchmarks/movingai";
  std::vector<std::filesystem::path> maps;
  std::error_code ec;
  for (const auto& e : std::filesystem::recursive_directory_iterator(root, ec)) {
    if (e.path().extension() == ".map") maps.push_back(e.path());
  }
  if (maps.empty()) GTEST_SKIP() << "no Moving AI maps under " << root;
  std::sort(maps.begin(), maps.end());
  std::mt19937 rng(99);
  int64_t cells_checked = 0, worse = 0;
  double worst = 0.0;
  for (const auto& path : maps) {
    auto grid = ReadMovingAiMapFile(path.string());
    ASSERT_TRUE(grid.ok()) << grid.status();
    auto shared = Share(*std::move(grid));
    for (int k = 0; k < 2; ++k) {
      Cell goal;
      do {
        goal = RandomCell(rng, *shared);
      } while (!Traversable(shared->cost(goal), false));
      auto spm = ShortestPathMap::Build(shared, goal, {}, StopCondition::None());
      ASSERT_TRUE(spm.ok());
      auto costs = IncrementalAccess::PathCosts(**spm);
      ASSERT_TRUE(costs.ok()) << costs.status();
      const std::vector<double> ref = ReferenceCostToGo(*shared, goal, {});
      for (size_t i = 0; i < ref.size(); ++i) {
        if (std::isinf(ref[i])) continue;
        ++cells_checked;
        const double rel = ((*costs)[i] - ref[i]) / (1.0 + ref[i]);
        worst = std::max(worst, rel);
        if (rel > 1e-9) ++worse;
      }
    }
  }
  std::printf("%lld cells, %lld suboptimal, worst relative excess %g\n",
              static_cast<long long>(cells_checked), static_cast<long long>(worse), worst);
  EXPECT_EQ(worse, 0);
}

}  // namespace
}  // namespace pathd
