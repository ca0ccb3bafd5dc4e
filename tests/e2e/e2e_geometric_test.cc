// The geometric planners through the real daemon and pathctl, as a new user
// tries them: a navmesh plan is an exact polyline shorter than A*'s grid
// path, render --overlay draws the mesh under it, maps stats lists the
// structures, and a map update changes the answer (the server advances its
// cached structures to the new version). A structure too slow for the
// query's deadline ends the query, not the daemon.
#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
#include "tests/e2e/e2e_fixture.h"

namespace pathd::e2e_test {
namespace {

// The polyline's length, from its vertices.
double PolylineLength(const v1::PlanResponse& plan) {
  double length = 0.0;
  for (int i = 1; i < plan.polyline_size(); ++i) {
    length += std::hypot(plan.polyline(i).x() - plan.polyline(i - 1).x(),
                         plan.polyline(i).y() - plan.polyline(i - 1).y());
  }
  return length;
}

TEST_F(E2eTest, GeometricPlansAreExactPolylinesShorterThanGridPaths) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const v1::PlanResponse astar =
      PlanJson({"walled", "2", "2", "17", "3", "--planner", "astar"});
  for (const char* planner : {"navmesh", "visibility_graph", "minimal_construct"}) {
    SCOPED_TRACE(planner);
    const v1::PlanResponse plan =
        PlanJson({"walled", "2", "2", "17", "3", "--planner", planner});
    ASSERT_TRUE(plan.found());
    ASSERT_GE(plan.polyline_size(), 3) << "the wall's gap bends the path";
    EXPECT_EQ(plan.world_polyline_size(), plan.polyline_size());
    EXPECT_DOUBLE_EQ(plan.polyline(0).x(), 2.5);
    EXPECT_DOUBLE_EQ(plan.polyline(0).y(), 2.5);
    EXPECT_DOUBLE_EQ(plan.polyline(plan.polyline_size() - 1).x(), 17.5);
    EXPECT_NEAR(plan.length(), PolylineLength(plan), 1e-9);
    EXPECT_LT(plan.length(), astar.length());
    // Bends sit on grid corners: the gap's top corners at x = 10 and 11.
    for (int i = 1; i + 1 < plan.polyline_size(); ++i) {
      EXPECT_EQ(plan.polyline(i).x(), std::floor(plan.polyline(i).x()));
      EXPECT_EQ(plan.polyline(i).y(), 8.0);
    }
  }
  const ProcessResult text =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--planner", "navmesh", "--world"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "polyline (4 vertices, cell coordinates): (2.5,2.5) (10,8) (11,8) (17.5,3.5)"))
      << text;
  EXPECT_TRUE(absl::StrContains(text.out, "world polyline (m): ")) << text;
}

TEST_F(E2eTest, RenderOverlayDrawsTheStructureUnderThePlan) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const std::string png = (temp_dir_ / "mesh.png").string();
  const ProcessResult r = Ctl({"render", "walled", "--plan", "2", "2", "17", "3",
                               "--planner", "navmesh", "--overlay", "mesh", "-o", png});
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(fs::exists(png));
  EXPECT_TRUE(absl::StrContains(r.out, "polyline vertices")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "mesh: ")) << r;
  const ProcessResult unknown =
      Ctl({"render", "walled", "--overlay", "meshes", "-o", png});
  EXPECT_EQ(unknown.exit_code, 2) << unknown;
  EXPECT_TRUE(absl::StrContains(unknown.err, "unknown structure 'meshes'")) << unknown;
  EXPECT_TRUE(absl::StrContains(unknown.err, "mesh")) << unknown;
}

TEST_F(E2eTest, MapsStatsListsEveryStructure) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const ProcessResult r = Ctl({"maps", "stats", "walled"});
  ASSERT_EQ(r.exit_code, 0) << r;
  for (const char* kind : {"polygons: ", "visibility: ", "mesh: ", "decomposition: ",
                           "voronoi: "}) {
    EXPECT_TRUE(absl::StrContains(r.out, kind)) << kind << "\n" << r;
  }
  EXPECT_TRUE(absl::StrContains(r.out, "polygons: 1 regions, 0 holes, 12 vertices"))
      << r;
  const ProcessResult csv = Ctl({"maps", "stats", "walled", "--overlay", "polygons",
                                 "--output", "csv"});
  ASSERT_EQ(csv.exit_code, 0) << csv;
  EXPECT_TRUE(absl::StartsWith(csv.out, "structure,count,name,bytes,build_ms\n")) << csv;
}

TEST_F(E2eTest, AMapUpdateChangesTheGeometricAnswer) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  for (const char* planner : {"navmesh", "visibility_graph", "minimal_construct",
                              "trapezoidal"}) {
    SCOPED_TRACE(planner);
    // Warm the server's structures on version 1, then narrow the gap.
    const v1::PlanResponse before =
        PlanJson({"walled", "2", "2", "17", "3", "--planner", planner});
    ASSERT_TRUE(before.found());
  }
  ASSERT_EQ(Ctl({"maps", "set", "walled", "10", "8", "lethal"}).exit_code, 0);
  for (const char* planner : {"navmesh", "visibility_graph", "minimal_construct",
                              "trapezoidal"}) {
    SCOPED_TRACE(planner);
    const v1::PlanResponse after =
        PlanJson({"walled", "2", "2", "17", "3", "--planner", planner});
    ASSERT_TRUE(after.found());
    EXPECT_EQ(after.map_version(), 2u);
    // No vertex inside the new lethal cell; the exact planners now bend at
    // the narrowed gap's corners (10, 9) and (11, 9).
    const bool exact = std::string(planner) != "trapezoidal";
    for (const v1::CellPoint& p : after.polyline()) {
      EXPECT_FALSE(p.x() > 10 && p.x() < 11 && p.y() > 8 && p.y() < 9);
      if (exact && p.x() >= 10 && p.x() <= 11) EXPECT_EQ(p.y(), 9.0);
    }
  }
}

// width x height Moving AI text with a quarter of the cells blocked at
// random (fixed seed), row 0 and the last column open so a path joins their
// ends. At 512 x 512 it is like random512-25: about 49,000 obstacle corners,
// a visibility graph of minutes.
std::string QuarterBlockedMap(int width, int height) {
  std::mt19937 rng(25);
  std::string text = absl::StrCat("type octile\nheight ", height, "\nwidth ", width,
                                  "\nmap\n");
  for (int y = 0; y < height; ++y) {
    std::string row(width, '.');
    for (int x = 0; y > 0 && x + 1 < width; ++x) {
      if (rng() % 4 == 0) row[x] = '@';
    }
    text += row + "\n";
  }
  return text;
}

TEST_F(E2eTest, AStructureSlowerThanTheDeadlineEndsTheQueryNotTheWorker) {
  // One worker: the A* plan below runs only once the build let it go.
  const std::unique_ptr<e2e::PathdProcess> pathd =
      StartOwnPathd({"--threads=1", "--log_level=debug"});
  ASSERT_TRUE(pathd->listening());
  const std::string server = "--server=" + pathd->address();
  const ProcessResult created =
      RunPathctl({server, "maps", "create", "random", "--from",
                  MapFile("random.map", QuarterBlockedMap(512, 512))});
  ASSERT_EQ(created.exit_code, 0) << created;

  const ProcessResult slow =
      RunPathctl({server, "--timeout=300ms", "plan", "random", "0", "0", "511", "511",
                  "--planner", "visibility_graph"});
  EXPECT_EQ(slow.exit_code,
            pathctl::ExitCodeForStatus(absl::StatusCode::kDeadlineExceeded))
      << slow;
  EXPECT_TRUE(absl::StartsWith(slow.err, "error: DEADLINE_EXCEEDED: ")) << slow;

  // pathctl's default timeout is far below the graph's minutes.
  const ProcessResult astar = RunPathctl(
      {server, "plan", "random", "0", "0", "511", "511", "--planner", "astar"});
  EXPECT_EQ(astar.exit_code, 0) << astar;

  // The client's own timer ends its call at the deadline, so the server's
  // answer, sent a poll later, reaches only the request log.
  const ProcessResult log = StopOwnPathd(*pathd);
  EXPECT_EQ(log.exit_code, 0) << log;
  EXPECT_TRUE(absl::StrContains(
      log.err, "planner=visibility_graph outcome=TIMEOUT"))
      << log.err;
  EXPECT_TRUE(absl::StrContains(
      log.err, "error=\"building the visibility graph of this map version ("))
      << log.err;
  EXPECT_TRUE(absl::StrContains(log.err, " vertices) did not finish before the deadline\""))
      << log.err;
}

}  // namespace
}  // namespace pathd::e2e_test
