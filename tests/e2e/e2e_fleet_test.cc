// e2e_test: the fleet map queries through the real pathd and pathctl:
// table (entries against one plan per pair, a second table from the cache,
// an unreachable pair), nearest (against a scan of the map), trip (the
// order against every permutation of the table's costs, the legs as one
// path), isochrone (cell count against the octile distance, GeoJSON),
// plan --snap_start, and fleet plan (every solver's plan through the
// independent conflict checker, render --robots, no plan).
#include <algorithm>
#include <array>
#include <numeric>

#include "core/map_io/map_io.h"
#include "tests/e2e/e2e_fixture.h"
#include "tests/testing/fleet_checker.h"

namespace pathd::e2e_test {
namespace {

// 12 x 10: a wall at x = 5 for y = 2..7, and cell (11, 9) sealed off by
// (10, 9), (10, 8) and (11, 8) (no corner cutting).
std::string FleetMap() {
  std::vector<std::string> rows(10, std::string(12, '.'));
  for (int y = 2; y <= 7; ++y) rows[y][5] = '@';
  rows[9][10] = '@';
  rows[8][10] = '@';
  rows[8][11] = '@';
  std::string text = "type octile\nheight 10\nwidth 12\nmap\n";
  for (const std::string& row : rows) text += row + "\n";
  return text;
}

bool Blocked(int x, int y) {
  return (x == 5 && y >= 2 && y <= 7) || (x == 10 && y == 9) || (x == 10 && y == 8) ||
         (x == 11 && y == 8);
}

}  // namespace

TEST_F(E2eTest, TableEntriesEqualOnePlanPerPairAndRepeatFromTheCache) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("fleet", FleetMap()));
  const std::vector<std::pair<int, int>> sources = {{0, 0}, {2, 5}, {11, 0}};
  const std::vector<std::pair<int, int>> dests = {{8, 5}, {11, 9}};
  const std::vector<std::string> args = {"table", "fleet", "--sources", "0,0;2,5;11,0",
                                         "--destinations", "8,5;11,9", "--json"};
  const ProcessResult r = Ctl(args);
  ASSERT_EQ(r.exit_code, 0) << r;
  const auto table = ParseJson<v1::TableResponse>(r.out);
  ASSERT_EQ(table.entries_size(), 6);
  EXPECT_EQ(table.method(), v1::TABLE_METHOD_BACKWARD);  // 2 destinations <= 3 sources
  EXPECT_EQ(table.fields_cached(), 0);
  for (size_t i = 0; i < sources.size(); ++i) {
    for (size_t j = 0; j < dests.size(); ++j) {
      const v1::TableEntry& e = table.entries(static_cast<int>(i * dests.size() + j));
      if (j == 1) {
        EXPECT_FALSE(e.reachable()) << "the sealed cell";
        continue;
      }
      const v1::PlanResponse plan =
          PlanJson({"fleet", absl::StrCat(sources[i].first), absl::StrCat(sources[i].second),
                    absl::StrCat(dests[j].first), absl::StrCat(dests[j].second)});
      ASSERT_TRUE(e.reachable());
      EXPECT_NEAR(e.cost(), plan.cost(), 1e-9);
      EXPECT_NEAR(e.cost_m(), plan.cost_m(), 1e-9);
    }
  }
  // The fields are cached now; forward gives the same costs.
  const auto again = ParseJson<v1::TableResponse>(Ctl(args).out);
  EXPECT_EQ(again.fields_cached(), 2);
  std::vector<std::string> forward = args;
  forward.insert(forward.end(), {"--method", "forward"});
  const auto fwd = ParseJson<v1::TableResponse>(Ctl(forward).out);
  EXPECT_EQ(fwd.method(), v1::TABLE_METHOD_FORWARD);
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(fwd.entries(k).reachable(), table.entries(k).reachable());
    EXPECT_NEAR(fwd.entries(k).cost(), table.entries(k).cost(), 1e-9);
  }
  // CSV: a header and one row per pair; the table form marks '-'.
  const ProcessResult csv = Ctl({"table", "fleet", "--sources", "0,0;2,5;11,0",
                                 "--destinations", "8,5;11,9", "--output", "csv"});
  ASSERT_EQ(csv.exit_code, 0) << csv;
  EXPECT_EQ(std::count(csv.out.begin(), csv.out.end(), '\n'), 7) << csv;
  const ProcessResult text = Ctl({"table", "fleet", "--sources", "0,0", "--destinations",
                                  "11,9"});
  EXPECT_TRUE(absl::StrContains(text.out, "-")) << text;
}

TEST_F(E2eTest, NearestEqualsAScanOfTheMap) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("fleet", FleetMap()));
  for (const auto& [px, py] : std::vector<std::pair<int, int>>{{5, 4}, {10, 9}, {3, 3}}) {
    const ProcessResult r = Ctl({"nearest", "fleet", absl::StrCat(px), absl::StrCat(py),
                                 "--robot_radius_cells", "1", "--json"});
    ASSERT_EQ(r.exit_code, 0) << r;
    const auto got = ParseJson<v1::NearestResponse>(r.out);
    // The scan: free, and no blocked cell (nor the map's edge... only
    // lethal cells inflate) within 1 cell of the centre.
    int best_d2 = 1 << 30;
    std::pair<int, int> best;
    for (int y = 0; y < 10; ++y) {
      for (int x = 0; x < 12; ++x) {
        bool ok = !Blocked(x, y);
        for (int dy = -1; dy <= 1 && ok; ++dy) {
          for (int dx = -1; dx <= 1 && ok; ++dx) {
            if (dx * dx + dy * dy <= 1 && Blocked(x + dx, y + dy)) ok = false;
          }
        }
        const int d2 = (x - px) * (x - px) + (y - py) * (y - py);
        if (ok && d2 < best_d2) {
          best_d2 = d2;
          best = {x, y};
        }
      }
    }
    ASSERT_TRUE(got.found()) << r;
    EXPECT_EQ(got.cell().x(), best.first) << r;
    EXPECT_EQ(got.cell().y(), best.second) << r;
    EXPECT_NEAR(got.distance_cells(), std::sqrt(best_d2), 1e-9);
  }
}

TEST_F(E2eTest, TripIsTheBestPermutationAndItsLegsAreOnePath) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("fleet", FleetMap()));
  const std::string stops = "0,0;9,1;8,7;1,8;3,4";
  const ProcessResult r = Ctl({"trip", "fleet", "--waypoints", stops, "--json"});
  ASSERT_EQ(r.exit_code, 0) << r;
  const auto trip = ParseJson<v1::TripResponse>(r.out);
  ASSERT_TRUE(trip.found());
  EXPECT_TRUE(trip.exact());
  EXPECT_EQ(trip.method(), "held_karp");
  const auto table = ParseJson<v1::TableResponse>(
      Ctl({"table", "fleet", "--sources", stops, "--destinations", stops, "--json"}).out);
  const auto cost = [&](int i, int j) { return table.entries(i * 5 + j).cost(); };
  std::vector<int> middle = {1, 2, 3, 4};
  double best = 1e18;
  do {
    double sum = cost(0, middle[0]) + cost(middle[3], 0);
    for (int k = 0; k + 1 < 4; ++k) sum += cost(middle[k], middle[k + 1]);
    best = std::min(best, sum);
  } while (std::next_permutation(middle.begin(), middle.end()));
  EXPECT_NEAR(trip.cost(), best, 1e-6);
  EXPECT_NEAR(trip.lower_bound(), trip.cost(), 1e-9);
  ASSERT_EQ(trip.order_size(), 5);
  EXPECT_EQ(trip.order(0), 0);
  // The legs: one path from the first stop back to it through the others.
  const v1::PlanResponse& plan = trip.plan();
  ASSERT_TRUE(plan.found());
  EXPECT_EQ(plan.path(0).x(), 0);
  EXPECT_EQ(plan.path(plan.path_size() - 1).x(), 0);
  EXPECT_EQ(plan.leg_end_indices_size(), 5);
  EXPECT_NEAR(plan.cost(), trip.cost(), 1e-6);
  // fixed_last keeps the last stop last; the text form names the method.
  const auto fixed = ParseJson<v1::TripResponse>(
      Ctl({"trip", "fleet", "--waypoints", stops, "--end", "fixed_last", "--json"}).out);
  EXPECT_EQ(fixed.order(4), 4);
  const ProcessResult text = Ctl({"trip", "fleet", "--waypoints", stops});
  EXPECT_TRUE(absl::StrContains(text.out, "held_karp (optimal)")) << text;
  // A stop nobody can reach: no trip, exit code 3, the reason.
  const ProcessResult none = Ctl({"trip", "fleet", "--waypoints", "0,0;11,9"});
  EXPECT_EQ(none.exit_code, 3) << none;  // kExitNoPath
  EXPECT_TRUE(absl::StrContains(none.out, "cannot reach")) << none;
}

TEST_F(E2eTest, IsochroneCountsTheCellsWithinTheBudgetAndPrintsGeoJson) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("open", OpenRoomMap(15, 15)));
  const ProcessResult r =
      Ctl({"isochrone", "open", "7", "7", "--budget_cells", "3", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r;
  const auto iso = ParseJson<v1::IsochroneResponse>(r.out);
  int within = 0;
  for (int y = 0; y < 15; ++y) {
    for (int x = 0; x < 15; ++x) {
      const double dx = std::abs(x - 7), dy = std::abs(y - 7);
      within += std::max(dx, dy) + (kSqrt2 - 1) * std::min(dx, dy) <= 3 + 1e-9 ? 1 : 0;
    }
  }
  EXPECT_EQ(iso.reachable_cells(), within);
  ASSERT_EQ(iso.polygons_size(), 1);
  EXPECT_EQ(iso.polygons(0).holes_size(), 0);
  const ProcessResult geo =
      Ctl({"isochrone", "open", "7", "7", "--budget", "3", "--output", "geojson"});
  ASSERT_EQ(geo.exit_code, 0) << geo;
  EXPECT_TRUE(absl::StartsWith(geo.out, "{\"type\": \"FeatureCollection\"")) << geo;
  EXPECT_TRUE(absl::StrContains(geo.out, "\"MultiPolygon\"")) << geo;
  // plan prints GeoJSON too (a LineString in world metres); table does not.
  const ProcessResult line = Ctl({"plan", "open", "0", "0", "2", "1", "--output", "geojson"});
  ASSERT_EQ(line.exit_code, 0) << line;
  EXPECT_TRUE(absl::StrContains(line.out, "\"LineString\", \"coordinates\": [[0.5")) << line;
  EXPECT_EQ(Ctl({"table", "open", "--sources", "0,0", "--destinations", "1,1", "--output",
                 "geojson"})
                .exit_code,
            2);
}

TEST_F(E2eTest, PlanSnapStartMovesABlockedStartToTheNearestFreeCell) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("fleet", FleetMap()));
  // (5, 4) is in the wall; without snapping it is an error.
  const ProcessResult refused = Ctl({"plan", "fleet", "5", "4", "9", "4"});
  EXPECT_NE(refused.exit_code, 0) << refused;
  const v1::PlanResponse plan = PlanJson({"fleet", "5", "4", "9", "4", "--snap_start"});
  EXPECT_TRUE(plan.start_snapped());
  EXPECT_EQ(plan.requested_start().x(), 5);
  // (4, 4) and (6, 4) are both 1 away: ties go to the smaller row, then
  // the smaller column.
  EXPECT_EQ(plan.start().x(), 4);
  EXPECT_EQ(plan.path(0).x(), plan.start().x());
  EXPECT_NEAR(plan.snap_distance_cells(), 1.0, 1e-9);
}

TEST_F(E2eTest, FleetPlanEverySolverPassesTheConflictCheckerAndRenders) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("fleet", FleetMap()));
  const absl::StatusOr<Grid> grid = ParseMovingAiMap(FleetMap(), "fleet");
  ASSERT_TRUE(grid.ok()) << grid.status();
  // Six robots trading sides of the wall in crossing pairs (twelve distinct
  // cells, so each capital letter shows twice in the picture).
  const std::vector<std::array<int, 4>> robots = {
      {0, 0, 11, 7}, {11, 6, 0, 1}, {0, 9, 11, 0}, {11, 1, 0, 8}, {2, 4, 8, 4}, {8, 5, 2, 5}};
  std::string file = "# SX SY GX GY\n";
  std::vector<testing::FleetCheckRobot> check;
  for (const auto& r : robots) {
    absl::StrAppend(&file, r[0], " ", r[1], " ", r[2], " ", r[3], "\n");
    check.push_back({Cell{r[0], r[1]}, Cell{r[2], r[3]}, &*grid});
  }
  const std::string path = MapFile("robots.txt", file);
  for (const std::string solver : {"lacam", "pibt", "prioritized", "cbs"}) {
    SCOPED_TRACE(solver);
    const ProcessResult r =
        Ctl({"fleet", "plan", "fleet", "--robots", path, "--solver", solver, "--json"});
    ASSERT_EQ(r.exit_code, 0) << r;
    const auto plan = ParseJson<v1::PlanFleetResponse>(r.out);
    ASSERT_TRUE(plan.found()) << plan.reason();
    std::vector<std::vector<Cell>> paths;
    for (const v1::FleetPath& p : plan.paths()) {
      std::vector<Cell>& cells = paths.emplace_back();
      for (const v1::Cell& c : p.cells()) cells.push_back(Cell{c.x(), c.y()});
      ASSERT_EQ(p.world_size(), p.cells_size());
    }
    const testing::FleetCheckResult checked = testing::CheckFleetPlan(
        check, /*eight_connected=*/true, /*unknown_is_free=*/false, paths);
    ASSERT_TRUE(checked.ok) << checked.error;
    EXPECT_EQ(plan.sum_of_costs(), checked.sum_of_costs);
    EXPECT_EQ(plan.makespan(), checked.makespan);
    EXPECT_LE(plan.lower_bound(), plan.sum_of_costs());
    for (int i = 0; i < plan.paths_size(); ++i) {
      EXPECT_EQ(plan.paths(i).cost(), checked.costs[i]) << "robot " << i;
    }
    if (solver == "cbs") {
      EXPECT_TRUE(plan.optimal());
    }
  }
  // The table form, and the picture: one letter per robot, its capital at
  // the start and the goal.
  const ProcessResult text = Ctl({"fleet", "plan", "fleet", "--robots", path});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "robots:       6")) << text;
  const ProcessResult drawn = Ctl({"render", "fleet", "--robots", path, "--ascii"});
  ASSERT_EQ(drawn.exit_code, 0) << drawn;
  for (const char c : std::string("ABCDEF")) {
    EXPECT_EQ(std::count(drawn.out.begin(), drawn.out.end(), c), 2) << c << "\n" << drawn.out;
  }
  EXPECT_TRUE(absl::StrContains(drawn.out, "fleet plan (lacam): 6 robots")) << drawn;

  // A goal in the sealed cell: no plan, exit 3 and the reason.
  const std::string sealed = MapFile("sealed.txt", "0 0 11 9\n3 0 4 0\n");
  const ProcessResult none = Ctl({"fleet", "plan", "fleet", "--robots", sealed});
  EXPECT_EQ(none.exit_code, 3) << none;
  EXPECT_TRUE(absl::StrContains(none.out, "no plan: no conflict-free plan exists")) << none;
  // A bad line is a usage error naming the file and the line.
  const std::string bad = MapFile("bad.txt", "0 0 11 7\n1 2 3\n");
  const ProcessResult usage = Ctl({"fleet", "plan", "fleet", "--robots", bad});
  EXPECT_EQ(usage.exit_code, 2) << usage;
  EXPECT_TRUE(absl::StrContains(usage.err, "bad.txt:2: expected 'SX SY GX GY [RADIUS_M]'"))
      << usage;
}

}  // namespace pathd::e2e_test
