// e2e_test: navigate sessions and pushes (grid and kinematic robots), maps
// watch, cost-to-go, the cache statistics, D* Lite reuse, the arena2 scenarios
// and SIGTERM.
#include <chrono>

#include "grpcpp/create_channel.h"
#include "grpcpp/security/credentials.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "tests/e2e/e2e_fixture.h"
#include "tests/testing/kinematic_checker.h"
#include "tests/testing/test_grids.h"

namespace pathd::e2e_test {

// Path lines of `pathctl navigate` output ("  path (N cells): (x,y) ..."),
// without the prefix.
std::vector<std::string> NavigatePaths(const std::string& out) {
  std::vector<std::string> paths;
  for (absl::string_view line : absl::StrSplit(out, '\n')) {
    if (!absl::ConsumePrefix(&line, "  path (")) continue;
    const size_t colon = line.find("): ");
    if (colon != absl::string_view::npos) {
      paths.emplace_back(line.substr(colon + 3));
    }
  }
  return paths;
}

// The seed's D* Lite example, shipped as maps/dstar_example.map and
// examples/navigate/dstar_example.nav: the robot steps from (4,2) to (3,2),
// an obstacle appears at (2,2), the robot drives the repaired path.
TEST_F(E2eTest, NavigateReplaysTheDstarLiteDemo) {
  const std::string source_dir = PATHD_SOURCE_DIR;
  ASSERT_EQ(Ctl({"maps", "create", "dstar_example", "--from",
                 source_dir + "/maps/dstar_example.map"})
                .exit_code,
            0);
  const ProcessResult r =
      Ctl({"navigate", "dstar_example", "4", "2", "0", "0", "--script",
           source_dir + "/examples/navigate/dstar_example.nav"});
  ASSERT_EQ(r.exit_code, 0) << r;
  const std::vector<std::string> paths = NavigatePaths(r.out);
  // OPENED, MOVED, OBSERVED, then one answer per step.
  ASSERT_GE(paths.size(), 4u) << r;
  EXPECT_EQ(paths[0], "(4,2) (3,2) (2,2) (1,2) (0,2) (0,1) (0,0)") << r;
  EXPECT_EQ(paths[1], "(3,2) (2,2) (1,2) (0,2) (0,1) (0,0)") << r;
  // The only optimal detour: no corner cutting past (2,2) or (1,1).
  EXPECT_EQ(paths[2], "(3,2) (3,3) (2,3) (1,3) (0,2) (0,1) (0,0)") << r;
  for (size_t i = 2; i < paths.size(); ++i) {
    EXPECT_FALSE(absl::StrContains(paths[i], "(2,2)")) << paths[i];
  }
  EXPECT_TRUE(absl::StrContains(r.out, "[OPENED] seq 1")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "found, cost 6.000000, 7 cells")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "found, cost 6.414214, 7 cells")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "at the goal (0,0)")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "closed: ")) << r;
  // The demo's observation is private: the shared map is untouched.
  const ProcessResult get = Ctl({"maps", "get", "dstar_example"});
  EXPECT_TRUE(absl::StrContains(get.out, "version:     1")) << get;

  // Without a script: the first path, then a clean close.
  const ProcessResult open =
      Ctl({"navigate", "dstar_example", "4", "2", "0", "0"});
  ASSERT_EQ(open.exit_code, 0) << open;
  EXPECT_EQ(NavigatePaths(open.out),
            std::vector<std::string>{"(4,2) (3,2) (2,2) (1,2) (0,2) (0,1) (0,0)"})
      << open;
}

// The issue's headline: a robot driven by pathctl navigate sees its path
// change when another client blocks a cell on it, without asking.
TEST_F(E2eTest, NavigateSessionReceivesAPushWhenAnotherClientBlocksItsPath) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const std::string script = MapFile("push.nav", "expect-push 30000\n");
  std::unique_ptr<PathctlProcess> robot =
      StartCtl({"navigate", "room", "0", "0", "9", "9", "--script", script});
  ASSERT_TRUE(robot->WaitForLine(" cells): ")) << robot->Finish();
  const std::vector<std::string> first = NavigatePaths(robot->out());
  ASSERT_EQ(first.size(), 1u) << robot->out();
  // The open room's only shortest path is the diagonal; block its middle.
  ASSERT_TRUE(absl::StrContains(first[0], "(4,4)")) << first[0];
  const ProcessResult set = Ctl({"maps", "set", "room", "4", "4", "lethal"});
  ASSERT_EQ(set.exit_code, 0) << set;

  const ProcessResult r = robot->Finish();
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "[MAP_CHANGED, unasked] seq 0")) << r;
  const std::vector<std::string> paths = NavigatePaths(r.out);
  ASSERT_EQ(paths.size(), 2u) << r;
  EXPECT_FALSE(absl::StrContains(paths[1], "(4,4)")) << paths[1];
  EXPECT_TRUE(absl::StartsWith(paths[1], "(0,0) ")) << paths[1];
  EXPECT_TRUE(absl::EndsWith(paths[1], " (9,9)")) << paths[1];
}

TEST_F(E2eTest, MapsWatchSeesAnotherClientsUpdateAndTheDelete) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  std::unique_ptr<PathctlProcess> watch = StartCtl({"maps", "watch", "room"});
  std::unique_ptr<PathctlProcess> json =
      StartCtl({"maps", "watch", "room", "--json", "--count", "2"});
  // Without --from_version the whole map comes first, which also shows the
  // stream is open before the update is made.
  ASSERT_TRUE(watch->WaitForLine("version 1 resync: whole map 10x10")) << watch->Finish();
  ASSERT_TRUE(json->WaitForLine("MAP_EVENT_KIND_RESYNC")) << json->Finish();
  const ProcessResult rect = Ctl({"maps", "rect", "room", "2", "3", "4", "5", "lethal"});
  ASSERT_EQ(rect.exit_code, 0) << rect;

  const ProcessResult json_result = json->Finish();
  ASSERT_EQ(json_result.exit_code, 0) << json_result;
  const std::vector<std::string> lines =
      absl::StrSplit(json_result.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 2u) << json_result;
  const auto updated = ParseJson<v1::MapEvent>(lines[1]);
  EXPECT_EQ(updated.kind(), v1::MAP_EVENT_KIND_UPDATED);
  EXPECT_EQ(updated.version(), 2u);
  ASSERT_EQ(updated.changes_size(), 1);
  EXPECT_EQ(updated.changes(0).rect().x_min(), 2);
  EXPECT_EQ(updated.changes(0).rect().y_max(), 5);
  EXPECT_EQ(updated.changes(0).costs(), std::string(9, '\xfe'));

  const ProcessResult deleted = Ctl({"maps", "delete", "room"});
  ASSERT_EQ(deleted.exit_code, 0) << deleted;
  const ProcessResult r = watch->Finish();
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_EQ(r.out,
            "version 1 resync: whole map 10x10\n"
            "version 2 updated: 9 cells in 1 rect: (2,3)-(4,5)\n"
            "version 2 deleted\n");
}

TEST_F(E2eTest, NavigateScriptErrorsAndFailedExpectations) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  // A bad line is reported with its place before anything is sent.
  const std::string bad = MapFile("bad.nav", "move 1 1\njump 2 2\n");
  const ProcessResult r =
      Ctl({"navigate", "room", "0", "0", "9", "9", "--script", bad});
  EXPECT_EQ(r.exit_code, 2) << r;
  EXPECT_EQ(r.err, absl::StrCat("error: ", bad,
                                ":2: unknown command 'jump'; expected move, pose, "
                                "follow, block, free, cost, rect, private, "
                                "wait or expect-push\n"));
  EXPECT_EQ(r.out, "") << r;
  // Nobody else updates the map, so no push comes.
  const std::string lonely = MapFile("lonely.nav", "move 1 1\nexpect-push 50\n");
  ExpectRpcError({"navigate", "room", "0", "0", "9", "9", "--script", lonely},
                 "DEADLINE_EXCEEDED", {"lonely.nav:2: expect-push"});
  // A move off the map ends the session with the server's reason.
  const std::string off = MapFile("off.nav", "move 40 1\n");
  ExpectRpcError({"navigate", "room", "0", "0", "9", "9", "--script", off},
                 "INVALID_ARGUMENT");
  ExpectRpcError({"navigate", "nosuch", "0", "0", "9", "9"}, "NOT_FOUND",
                 {"nosuch"});
}

TEST_F(E2eTest, CostToGoPrintsAWindowOrWritesItsCsv) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  // Columns 9..11 of rows 0..1 straddle the wall at x = 10.
  const ProcessResult table =
      Ctl({"cost-to-go", "walled", "17", "3", "--window", "9,0,3,2"});
  ASSERT_EQ(table.exit_code, 0) << table;
  EXPECT_TRUE(absl::StrContains(table.out, "goal:        (17,3)")) << table;
  EXPECT_TRUE(absl::StrContains(table.out, "window:      x 9..11, y 0..1 (3x2 cells)"))
      << table;
  EXPECT_TRUE(absl::StrContains(table.out, "reachable:   4 of 6 cells")) << table;
  EXPECT_TRUE(absl::StrContains(table.out, "  y\\x       9      10      11\n"))
      << table;
  EXPECT_TRUE(absl::StrContains(table.out, "     inf ")) << table;

  const std::string csv = (temp_dir_ / "window.csv").string();
  const ProcessResult written = Ctl({"cost-to-go", "walled", "17", "3", "--window",
                                     "15,2,4,3", "--cost_to_go_file", csv});
  ASSERT_EQ(written.exit_code, 0) << written;
  EXPECT_TRUE(absl::StrContains(written.out, "12 cells written to")) << written;
  std::ifstream in(csv);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    rows.push_back(absl::StrSplit(line, ','));
  }
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& row : rows) ASSERT_EQ(row.size(), 4u);
  EXPECT_EQ(rows[1][2], "0.000000");  // the goal (17,3)
  EXPECT_EQ(rows[0][1], "1.414214");  // (16,2), one diagonal away
  EXPECT_EQ(rows[1][3], "1.000000");  // (18,3)

  // The whole field agrees with A* from a far start.
  const std::string whole = (temp_dir_ / "whole.csv").string();
  ASSERT_EQ(Ctl({"cost-to-go", "walled", "17", "3", "--cost_to_go_file", whole})
                .exit_code,
            0);
  std::ifstream whole_in(whole);
  std::vector<std::vector<std::string>> field;
  for (std::string line; std::getline(whole_in, line);) {
    field.push_back(absl::StrSplit(line, ','));
  }
  ASSERT_EQ(field.size(), 12u);
  double start_cost = 0;
  ASSERT_TRUE(absl::SimpleAtod(field[2][2], &start_cost));
  const v1::PlanResponse astar = PlanJson({"walled", "2", "2", "17", "3"});
  EXPECT_NEAR(start_cost, astar.cost(), 1e-4);  // the field holds floats

  ExpectRpcError({"cost-to-go", "walled", "17", "3", "--window", "18,0,5,5"},
                 "INVALID_ARGUMENT", {"window"});
  ExpectRpcError({"cost-to-go", "walled", "10", "0"}, "INVALID_ARGUMENT",
                 {"goal"});
}

TEST_F(E2eTest, CacheStatsCountSpmHits) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse first =
      PlanJson({"room", "0", "0", "9", "9", "--planner=spm"});
  EXPECT_FALSE(first.cache_hit());
  // Another start, the same goal and cost options: the cached field answers.
  const v1::PlanResponse second =
      PlanJson({"room", "0", "5", "9", "9", "--planner=spm"});
  EXPECT_TRUE(second.cache_hit());
  EXPECT_NEAR(second.cost(), 5 + 4 * kSqrt2, 1e-9);

  const ProcessResult stats = Ctl({"cache-stats", "--json"});
  ASSERT_EQ(stats.exit_code, 0) << stats;
  const auto response = ParseJson<v1::GetCacheStatsResponse>(stats.out);
  const v1::CacheStats* spm = nullptr;
  for (const v1::CacheStats& c : response.caches()) {
    if (c.name() == "spm") spm = &c;
  }
  ASSERT_NE(spm, nullptr) << stats;
  EXPECT_GE(spm->hits(), 1) << stats;
  EXPECT_GE(spm->misses(), 1) << stats;
  EXPECT_GE(spm->entries(), 1) << stats;
  EXPECT_GT(spm->bytes(), 0) << stats;

  const ProcessResult text = Ctl({"cache-stats"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StartsWith(text.out, "CACHE ")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "\nspm ")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "\nsessions:    0 open")) << text;
}

TEST_F(E2eTest, DstarLitePlansFromAMovingStartReuseTheirState) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse first =
      PlanJson({"room", "0", "0", "9", "9", "--planner=dstar_lite"});
  EXPECT_FALSE(first.cache_hit());
  EXPECT_NEAR(first.cost(), 9 * kSqrt2, 1e-9);
  // The robot moved one step along its path.
  const ProcessResult moved =
      Ctl({"plan", "room", "1", "1", "9", "9", "--planner=dstar_lite"});
  ASSERT_EQ(moved.exit_code, 0) << moved;
  EXPECT_TRUE(absl::StrContains(moved.out, "cache hit:   yes\n")) << moved;
  EXPECT_TRUE(absl::StrContains(moved.out, "repaired:    0 cells\n")) << moved;
  EXPECT_TRUE(absl::StrContains(moved.out, "cost:        11.313708")) << moved;
  // Other planners do not claim a cache.
  const ProcessResult astar = Ctl({"plan", "room", "1", "1", "9", "9"});
  EXPECT_FALSE(absl::StrContains(astar.out, "cache hit")) << astar;
}

// Plans a spread of the benchmark's own scenarios on the bundled map and
// checks the optimal lengths it publishes.
TEST_F(E2eTest, Arena2ScenariosHaveTheirOptimalLengths) {
  const std::string source_dir = PATHD_SOURCE_DIR;
  const ProcessResult created = Ctl(
      {"maps", "create", "arena2", "--from", source_dir + "/maps/arena2.map"});
  ASSERT_EQ(created.exit_code, 0) << created;
  EXPECT_TRUE(absl::StrContains(created.out, "281 x 209 cells")) << created;

  const std::vector<std::string> lines =
      absl::StrSplit(ReadFile(source_dir + "/maps/arena2.map.scen"), '\n',
                     absl::SkipWhitespace());
  ASSERT_GT(lines.size(), 100u);
  std::vector<size_t> picks;
  for (size_t i = 1; i < lines.size(); i += 97) picks.push_back(i);
  picks.push_back(lines.size() - 1);  // the longest
  for (size_t i : picks) {
    SCOPED_TRACE(lines[i]);
    // bucket, map, width, height, start x, start y, goal x, goal y, length
    const std::vector<std::string> f =
        absl::StrSplit(lines[i], absl::ByAnyChar(" \t"), absl::SkipEmpty());
    ASSERT_EQ(f.size(), 9u);
    double optimal = 0;
    ASSERT_TRUE(absl::SimpleAtod(f[8], &optimal));
    // Half a unit in the last stored decimal, plus float slack.
    const size_t dot = f[8].find('.');
    const int decimals =
        dot == std::string::npos ? 0 : static_cast<int>(f[8].size() - dot - 1);
    const double tolerance = 0.5 * std::pow(10.0, -decimals) + 1e-6;

    const v1::PlanResponse astar = PlanJson({"arena2", f[4], f[5], f[6], f[7]});
    ASSERT_TRUE(astar.found()) << astar.reason();
    EXPECT_NEAR(astar.length(), optimal, tolerance);
    // Every cell is free or lethal, so cost equals length.
    EXPECT_NEAR(astar.cost(), astar.length(), 1e-6);
    EXPECT_EQ(astar.path(0).x(), std::stoi(f[4]));
    EXPECT_EQ(astar.path(0).y(), std::stoi(f[5]));
    EXPECT_EQ(astar.path(astar.path_size() - 1).x(), std::stoi(f[6]));
    EXPECT_EQ(astar.path(astar.path_size() - 1).y(), std::stoi(f[7]));
  }
  const std::vector<std::string> longest =
      absl::StrSplit(lines.back(), absl::ByAnyChar(" \t"), absl::SkipEmpty());
  const v1::PlanResponse dijkstra =
      PlanJson({"arena2", longest[4], longest[5], longest[6], longest[7],
                "--planner=dijkstra"});
  double optimal = 0;
  ASSERT_TRUE(absl::SimpleAtod(longest[8], &optimal));
  EXPECT_NEAR(dijkstra.length(), optimal, 1e-3);
}

TEST_F(E2eTest, SigtermExitsCleanly) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_EQ(Ctl({"plan", "room", "0", "0", "9", "9"}).exit_code, 0);
  const std::string address = address_;
  EXPECT_EQ(StopDaemon(), 0);
  // With the daemon gone the client reports the transport error, exit 5.
  const ProcessResult r = RunPathctl(
      {absl::StrCat("--server=", address), "--timeout=5s", "maps", "list"});
  EXPECT_EQ(r.exit_code, 5) << r;
  EXPECT_TRUE(absl::StartsWith(r.err, "error: UNAVAILABLE: ")) << r;
}

// A hall 30 x 12 cells walled round, for the kinematic session: rows as
// tests/testing/test_grids.h reads them ('#' lethal), and the same map as
// Moving AI text for pathd.
std::vector<std::string> HallRows() {
  std::vector<std::string> rows;
  for (int y = 0; y < 12; ++y) {
    rows.push_back(y == 0 || y == 11 ? std::string(30, '#')
                                     : "#" + std::string(28, '.') + "#");
  }
  return rows;
}

std::string MovingAiText(const std::vector<std::string>& rows) {
  std::string text = absl::StrCat("type octile\nheight ", rows.size(), "\nwidth ",
                                  rows[0].size(), "\nmap\n");
  for (std::string row : rows) {
    std::replace(row.begin(), row.end(), '#', '@');
    text += row + "\n";
  }
  return text;
}

std::vector<Pose> PosesOf(const v1::PlanResponse& plan) {
  std::vector<Pose> poses;
  for (const v1::CellPose& p : plan.poses()) poses.push_back(Pose{p.x(), p.y(), p.yaw()});
  return poses;
}

v1::CellPose MakeCellPose(double x, double y, double yaw) {
  v1::CellPose pose;
  pose.set_x(x);
  pose.set_y(y);
  pose.set_yaw(yaw);
  return pose;
}

v1::NavigateRequest PoseMessage(uint64_t seq, const v1::CellPose& pose) {
  v1::NavigateRequest request;
  request.set_seq(seq);
  *request.mutable_pose()->mutable_cell_pose() = pose;
  return request;
}

// The issue's kinematic session: a rectangular Dubins robot drives its
// path, another client (pathctl) walls off the corridor ahead of it, and the
// pushed replan starts at the robot's last reported pose and passes the
// independent checker (footprint sampled densely against every obstacle
// cell with Boost.Geometry, curvature within 1 / r_min) on the new map; an
// update away from the path pushes nothing. Once per kinematic planner.
class KinematicNavigateTest : public E2eTest {
 protected:
  void Drive(v1::Planner planner_kind);
};

void KinematicNavigateTest::Drive(v1::Planner planner_kind) {
  std::vector<std::string> rows = HallRows();
  ASSERT_NO_FATAL_FAILURE(CreateMap("hall", MovingAiText(rows)));
  auto channel = grpc::CreateChannel(address_, grpc::InsecureChannelCredentials());
  auto planner = v1::PlannerService::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto stream = planner->Navigate(&context);

  testing::KinematicCheck check;
  check.footprint = {{1.0, 0.6}, {1.0, -0.6}, {-1.0, -0.6}, {-1.0, 0.6}};
  check.min_turning_radius = 2.0;
  check.curvature_slack = 0.02;
  check.allow_reverse = false;
  check.step_cells = 0.05;
  check.goal = Pose{26.5, 3.5, 0.0};
  check.goal_tolerance = 1e-3;
  check.goal_yaw_tolerance = 1e-3;

  v1::NavigateRequest open;
  open.set_seq(1);
  v1::NavigateOpen* o = open.mutable_open();
  o->set_map("hall");
  o->set_planner(planner_kind);
  o->set_replan_max_expansions(20000);
  *o->mutable_start()->mutable_cell_pose() = MakeCellPose(3.5, 3.5, 0.0);
  *o->mutable_goal()->mutable_cell_pose() = MakeCellPose(26.5, 3.5, 0.0);
  for (const auto& [x, y] : check.footprint) {
    v1::CellPoint* p = o->mutable_options()->mutable_footprint()->add_polygon_cells();
    p->set_x(x);
    p->set_y(y);
  }
  o->mutable_options()->set_min_turning_radius_cells(2.0);
  o->mutable_options()->set_motion_model(v1::MOTION_MODEL_DUBINS);
  ASSERT_TRUE(stream->Write(open));
  v1::NavigateResponse answer;
  ASSERT_TRUE(stream->Read(&answer));
  ASSERT_EQ(answer.event(), v1::NAVIGATE_EVENT_OPENED);
  ASSERT_TRUE(answer.plan().found()) << answer.ShortDebugString();
  EXPECT_EQ(answer.replan_max_expansions(), 20000);
  EXPECT_FALSE(answer.kept_previous_path());
  EXPECT_GT(answer.plan().length_m(), 22.0);
  Grid grid = MakeGrid(rows);
  check.start = Pose{3.5, 3.5, 0.0};
  EXPECT_EQ(testing::CheckKinematicPath(grid, PosesOf(answer.plan()), {}, check), "");

  // Four steps along the path, each answered from the pose reported.
  v1::CellPose robot;
  uint64_t seq = 1;
  for (int step = 0; step < 4; ++step) {
    ASSERT_GE(answer.plan().poses_size(), 3);
    robot = answer.plan().poses(2);
    ASSERT_TRUE(stream->Write(PoseMessage(++seq, robot)));
    ASSERT_TRUE(stream->Read(&answer));
    ASSERT_EQ(answer.event(), v1::NAVIGATE_EVENT_MOVED);
    ASSERT_EQ(answer.seq(), seq);
    ASSERT_TRUE(answer.plan().found()) << answer.ShortDebugString();
    check.start = Pose{robot.x(), robot.y(), robot.yaw()};
    EXPECT_EQ(testing::CheckKinematicPath(grid, PosesOf(answer.plan()), {}, check), "")
        << "step " << step;
  }

  // An update far from the path (it runs along row 3): no replan is pushed,
  // so the next message read is the answer to the next pose. The push job
  // would be queued before UpdateMap returns, ahead of the pose message.
  ASSERT_EQ(Ctl({"maps", "set", "hall", "27", "10", "lethal"}).exit_code, 0);
  rows[10][27] = '#';
  ASSERT_TRUE(stream->Write(PoseMessage(++seq, robot)));
  ASSERT_TRUE(stream->Read(&answer));
  EXPECT_EQ(answer.event(), v1::NAVIGATE_EVENT_MOVED) << answer.ShortDebugString();
  EXPECT_EQ(answer.seq(), seq);
  EXPECT_EQ(answer.plan().map_version(), 2u);

  // Another client walls off the corridor's lower half ahead of the robot.
  const ProcessResult wall = Ctl({"maps", "rect", "hall", "15", "1", "16", "6", "lethal"});
  ASSERT_EQ(wall.exit_code, 0) << wall;
  for (int y = 1; y <= 6; ++y) rows[y][15] = rows[y][16] = '#';
  ASSERT_TRUE(stream->Read(&answer));
  ASSERT_EQ(answer.event(), v1::NAVIGATE_EVENT_MAP_CHANGED) << answer.ShortDebugString();
  EXPECT_EQ(answer.seq(), 0u);
  EXPECT_EQ(answer.plan().map_version(), 3u);
  ASSERT_TRUE(answer.plan().found()) << answer.ShortDebugString();
  EXPECT_NEAR(answer.robot_pose().x(), robot.x(), 1e-9);
  EXPECT_NEAR(answer.robot_pose().y(), robot.y(), 1e-9);
  grid = MakeGrid(rows);
  check.start = Pose{robot.x(), robot.y(), robot.yaw()};
  const std::vector<Pose> detour = PosesOf(answer.plan());
  EXPECT_EQ(testing::CheckKinematicPath(grid, detour, {}, check), "");
  // It goes round the wall: above row 7 somewhere.
  EXPECT_TRUE(std::any_of(detour.begin(), detour.end(),
                          [](const Pose& p) { return p.y > 7.0; }));
  ASSERT_EQ(answer.plan().world_poses_size(), answer.plan().poses_size());
  EXPECT_EQ(answer.plan().frame_id(), "map");

  // The robot's own sensor, for this session only: a pillar on the detour.
  // The answer plans on the shared map plus the pillar (version unchanged)
  // and the session's bytes now count its private view of the map.
  const Pose through = *std::find_if(detour.begin(), detour.end(),
                                     [](const Pose& p) { return p.y > 7.0; });
  const int pillar_x = static_cast<int>(through.x), pillar_y = static_cast<int>(through.y);
  v1::NavigateRequest observe;
  observe.set_seq(++seq);
  observe.mutable_observe()->set_session_only(true);
  v1::CellChange* change = observe.mutable_observe()->add_changes();
  change->mutable_cell()->set_x(pillar_x);
  change->mutable_cell()->set_y(pillar_y);
  change->set_cost(254);
  ASSERT_TRUE(stream->Write(observe));
  ASSERT_TRUE(stream->Read(&answer));
  ASSERT_EQ(answer.event(), v1::NAVIGATE_EVENT_OBSERVED) << answer.ShortDebugString();
  EXPECT_EQ(answer.plan().map_version(), 3u);
  ASSERT_TRUE(answer.plan().found()) << answer.ShortDebugString();
  std::vector<std::string> private_rows = rows;
  private_rows[pillar_y][pillar_x] = '#';
  EXPECT_EQ(testing::CheckKinematicPath(MakeGrid(private_rows), PosesOf(answer.plan()), {},
                                        check),
            "");
  // The detour pushed before would hit the pillar.
  EXPECT_EQ(testing::CheckKinematicPath(MakeGrid(private_rows), detour, {}, check).empty(),
            false);
  grpc::ClientContext stats_context;
  v1::GetCacheStatsResponse stats;
  ASSERT_TRUE(planner->GetCacheStats(&stats_context, v1::GetCacheStatsRequest(), &stats).ok());
  EXPECT_EQ(stats.sessions(), 1);
  // Its obstacle distance field and heuristic (4 + 4 bytes per cell) and
  // the private grid copy (1 per cell).
  EXPECT_GE(stats.session_bytes(), 9 * 30 * 12);
  // pathctl sessions lists it with the answer it just sent (ListSessions),
  // and a filter on another map lists nothing.
  const ProcessResult listed = Ctl({"sessions", "--json"});
  ASSERT_EQ(listed.exit_code, 0) << listed;
  const auto sessions = ParseJson<v1::ListSessionsResponse>(listed.out);
  ASSERT_EQ(sessions.sessions_size(), 1) << listed;
  EXPECT_EQ(sessions.sessions(0).session_id(), answer.session_id());
  EXPECT_EQ(sessions.sessions(0).last().seq(), answer.seq());
  EXPECT_EQ(sessions.sessions(0).last().plan().poses_size(), answer.plan().poses_size());
  EXPECT_EQ(sessions.sessions(0).last().robot_pose().x(), answer.robot_pose().x());
  const ProcessResult elsewhere = Ctl({"sessions", "elsewhere", "--json"});
  ASSERT_EQ(elsewhere.exit_code, 0) << elsewhere;
  EXPECT_EQ(ParseJson<v1::ListSessionsResponse>(elsewhere.out).sessions_size(), 0) << elsewhere;

  stream->WritesDone();
  while (stream->Read(&answer)) {
  }
  const grpc::Status status = stream->Finish();
  EXPECT_TRUE(status.ok()) << status.error_message();
}

TEST_F(KinematicNavigateTest, HybridAStarSessionGetsAFeasiblePushWhenItsPathIsBlocked) {
  Drive(v1::PLANNER_HYBRID_ASTAR);
}

TEST_F(KinematicNavigateTest, StateLatticeSessionGetsAFeasiblePushWhenItsPathIsBlocked) {
  Drive(v1::PLANNER_STATE_LATTICE);
}

// pathctl navigate with the plan command's robot flags on the bundled
// warehouse: a kinematic session that prints poses and follows them.
TEST_F(E2eTest, PathctlNavigatesAKinematicRobotOnTheWarehouse) {
  const std::string source_dir = PATHD_SOURCE_DIR;
  ASSERT_EQ(Ctl({"maps", "create", "warehouse", "--from",
                 source_dir + "/maps/warehouse.yaml"})
                .exit_code,
            0);
  // The shipped example script, as docs/pathctl.md runs it.
  const ProcessResult r =
      Ctl({"navigate", "warehouse", "4", "3", "36", "3", "--planner", "hybrid_astar",
           "--footprint", "[[0.15,0.1],[0.15,-0.1],[-0.15,-0.1],[-0.15,0.1]]",
           "--min_turning_radius", "0.2", "--start_yaw", "0", "--goal_yaw", "0",
           "--max_expansions", "5000", "--script",
           source_dir + "/examples/navigate/warehouse_robot.nav"});
  ASSERT_EQ(r.exit_code, 0) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "[OPENED] seq 1")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "budget 5000, from (4.50,3.50,0.000)")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "  poses (")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "> step 3/3: pose (6.00,3.50,0.000)")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "from (6.20,3.60,0.100)")) << r;
  // The pallets' answer (seen by this session only) is a path round them,
  // from the reported pose.
  EXPECT_TRUE(absl::StrContains(r.out, "[OBSERVED] seq 6, session 1, map version 1: found"))
      << r;
  EXPECT_FALSE(absl::StrContains(r.out, "no path")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "closed: 8 answers")) << r;
  // The first step round them reports a pose of that path: hybrid_astar's
  // replan from there (an 8.5 m detour when this was written) is dearer than
  // the rest of the path, which stays the answer.
  EXPECT_TRUE(absl::StrContains(
      r.out, "budget 5000, from (6.58,3.64,0.100), the previous path (no dearer than the "
             "replan's)"))
      << r;

  // A budget too small for the first step round the pallets (the step after
  // the observation took 1085 expansions when this was written): the answer
  // keeps the rest of the previous path, which the robot is on.
  const ProcessResult tight =
      Ctl({"navigate", "warehouse", "4", "3", "36", "3", "--planner", "hybrid_astar",
           "--footprint", "[[0.15,0.1],[0.15,-0.1],[-0.15,-0.1],[-0.15,0.1]]",
           "--min_turning_radius", "0.2", "--start_yaw", "0", "--goal_yaw", "0",
           "--max_expansions", "400", "--script",
           source_dir + "/examples/navigate/warehouse_robot.nav"});
  ASSERT_EQ(tight.exit_code, 0) << tight;
  EXPECT_TRUE(absl::StrContains(tight.out, "[OBSERVED] seq 6, session 2, map version 1: found"))
      << tight;
  EXPECT_TRUE(absl::StrContains(
      tight.out, "[MOVED] seq 7, session 2, map version 1: replan stopped (EXPANSION_LIMIT), "
                 "kept the previous path"))
      << tight;
  EXPECT_TRUE(absl::StrContains(tight.out, "budget 400, from (6.58,3.64,0.100)")) << tight;

  // --world: the start and goal in metres, the poses printed in metres.
  const ProcessResult world =
      Ctl({"navigate", "warehouse", "-2.55", "-1.65", "0.65", "-1.65", "--world", "--planner",
           "hybrid_astar", "--footprint", "[[0.15,0.1],[0.15,-0.1],[-0.15,-0.1],[-0.15,0.1]]",
           "--min_turning_radius", "0.2", "--start_yaw", "0", "--goal_yaw", "0"});
  ASSERT_EQ(world.exit_code, 0) << world;
  EXPECT_TRUE(absl::StrContains(world.out, "> open warehouse (-2.55, -1.65) m facing 0 rad"))
      << world;
  EXPECT_TRUE(absl::StrContains(world.out, "world x,y,yaw in m): (-2.550,-1.650,0.000) "))
      << world;
}

}  // namespace pathd::e2e_test
