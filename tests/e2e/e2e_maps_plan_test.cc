// e2e_test: maps create/list/get/delete, every planner through pathctl and
// its options, map updates changing the plan, server and usage errors.
#include "tests/e2e/e2e_fixture.h"

namespace pathd::e2e_test {

TEST_F(E2eTest, HealthReportsServing) {
  const ProcessResult r = Ctl({"health"});
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_EQ(r.out, "SERVING\n");
}

TEST_F(E2eTest, ServerAddressFromEnvironment) {
  const ProcessResult r =
      RunPathctl({"health"}, {absl::StrCat("PATHD_SERVER=", address_)});
  EXPECT_EQ(r.exit_code, 0) << r;
  EXPECT_EQ(r.out, "SERVING\n");
}

TEST_F(E2eTest, CreateListGetDelete) {
  const ProcessResult created =
      Ctl({"maps", "create", "room", "--from",
           MapFile("room.map", OpenRoomMap()), "--json"});
  ASSERT_EQ(created.exit_code, 0) << created;
  const auto create = ParseJson<v1::CreateMapResponse>(created.out);
  EXPECT_EQ(create.info().name(), "room");
  EXPECT_EQ(create.info().width(), 10);
  EXPECT_EQ(create.info().height(), 10);
  EXPECT_EQ(create.info().version(), 1u);
  EXPECT_EQ(create.info().free_cells(), 100);
  EXPECT_EQ(create.info().blocked_cells(), 0);

  const ProcessResult list = Ctl({"maps", "list"});
  ASSERT_EQ(list.exit_code, 0) << list;
  EXPECT_TRUE(absl::StrContains(list.out, "room")) << list;
  EXPECT_TRUE(absl::StrContains(list.out, "10x10")) << list;

  const ProcessResult list_json = Ctl({"maps", "list", "--json"});
  ASSERT_EQ(list_json.exit_code, 0) << list_json;
  const auto maps = ParseJson<v1::ListMapsResponse>(list_json.out);
  ASSERT_EQ(maps.maps_size(), 1) << list_json;
  EXPECT_EQ(maps.maps(0).name(), "room");

  const ProcessResult get = Ctl({"maps", "get", "room"});
  ASSERT_EQ(get.exit_code, 0) << get;
  EXPECT_TRUE(absl::StrContains(get.out, "10 x 10 cells")) << get;
  EXPECT_TRUE(absl::StrContains(get.out, "version:     1")) << get;

  ASSERT_EQ(Ctl({"maps", "set", "room", "3", "2", "lethal"}).exit_code, 0);
  ASSERT_EQ(Ctl({"maps", "set", "room", "4", "2", "100"}).exit_code, 0);
  ASSERT_EQ(Ctl({"maps", "set", "room", "5", "2", "unknown"}).exit_code, 0);
  const ProcessResult cells = Ctl({"maps", "get", "room", "--cells"});
  ASSERT_EQ(cells.exit_code, 0) << cells;
  // Row 2 holds lethal, cost 100 (digit 4: 85..112) and unknown.
  EXPECT_TRUE(
      absl::StrContains(cells.out, "\n..........\n..........\n...#4?....\n"))
      << cells;

  const ProcessResult deleted = Ctl({"maps", "delete", "room"});
  ASSERT_EQ(deleted.exit_code, 0) << deleted;
  EXPECT_TRUE(absl::StrContains(deleted.out, "version 4")) << deleted;
  ExpectRpcError({"maps", "get", "room"}, "NOT_FOUND", {"room"});
  const ProcessResult empty = Ctl({"maps", "list"});
  EXPECT_EQ(empty.exit_code, 0) << empty;
  EXPECT_EQ(empty.out, "no maps\n");
}

TEST_F(E2eTest, CreateFromRosMap) {
  // The image lives beside the YAML, which names it relatively: pathctl must
  // resolve it against the YAML's folder, not its own working directory.
  const fs::path ros_dir = temp_dir_ / "ros";
  fs::create_directory(ros_dir);
  // 4x3 P2 image: 254 white (free), 0 black (occupied), 128 grey (unknown).
  WriteFile(ros_dir / "room.pgm",
            "P2\n4 3\n255\n"
            "0 254 254 254\n"
            "254 128 254 254\n"
            "254 254 254 0\n");
  WriteFile(ros_dir / "room.yaml",
            "image: room.pgm\nresolution: 0.05\norigin: [1.0, 2.0, 0.0]\n"
            "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const ProcessResult created =
      Ctl({"maps", "create", "ros_room", "--from",
           (ros_dir / "room.yaml").string(), "--json"});
  ASSERT_EQ(created.exit_code, 0) << created;
  const auto info = ParseJson<v1::CreateMapResponse>(created.out).info();
  EXPECT_EQ(info.width(), 4);
  EXPECT_EQ(info.height(), 3);
  EXPECT_DOUBLE_EQ(info.resolution(), 0.05);
  EXPECT_DOUBLE_EQ(info.origin().x(), 1.0);
  EXPECT_DOUBLE_EQ(info.origin().y(), 2.0);

  // Row 0 is the image's bottom row (OccupancyGrid convention).
  const ProcessResult cells = Ctl({"maps", "get", "ros_room", "--cells"});
  ASSERT_EQ(cells.exit_code, 0) << cells;
  EXPECT_TRUE(absl::EndsWith(cells.out, "\n...#\n.?..\n#...\n")) << cells;

  // A YAML carries its own resolution.
  const ProcessResult r =
      Ctl({"maps", "create", "ros_room2", "--from",
           (ros_dir / "room.yaml").string(), "--resolution=2"});
  EXPECT_EQ(r.exit_code, 2) << r;
}

TEST_F(E2eTest, EveryPlannerFindsTheDiagonal) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  // From corner to corner of an open room the only shortest path is the
  // diagonal: 9 moves of sqrt(2), whatever the planner.
  for (const char* planner : {"astar", "dijkstra", "bfs"}) {
    SCOPED_TRACE(planner);
    const v1::PlanResponse plan = PlanJson(
        {"room", "0", "0", "9", "9", absl::StrCat("--planner=", planner)});
    EXPECT_TRUE(plan.found());
    EXPECT_EQ(plan.outcome(), v1::PLAN_OUTCOME_FOUND);
    EXPECT_EQ(plan.planner(), planner);
    EXPECT_NEAR(plan.cost(), 9 * kSqrt2, 1e-9);
    EXPECT_NEAR(plan.length(), 9 * kSqrt2, 1e-9);
    EXPECT_EQ(plan.path_size(), 10);
    EXPECT_EQ(plan.map_version(), 1u);
    EXPECT_GT(plan.expansions(), 0);
  }
  // 4-connected, the same trip is 18 straight moves.
  const v1::PlanResponse four =
      PlanJson({"room", "0", "0", "9", "9", "--planner", "astar",
                "--connectivity", "4"});
  EXPECT_NEAR(four.cost(), 18.0, 1e-9);
  EXPECT_EQ(four.path_size(), 19);

  // The human-readable form carries the same facts.
  const ProcessResult text = Ctl({"plan", "room", "0", "0", "9", "9"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "found:       yes")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "cost:        12.727922")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "map version: 1")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "path (10 cells): (0,0) (1,1)"))
      << text;
}

TEST_F(E2eTest, EveryPlannerRunsThroughPathctl) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  for (const WirePlanner& entry : WirePlanners()) {
    const std::string planner(entry.name);
    SCOPED_TRACE(planner);
    const ProcessResult r = Ctl({"plan", "walled", "2", "2", "17", "3",
                                 absl::StrCat("--planner=", planner), "--json"});
    // The potential field may stall behind the wall (exit 3, LOCAL_MINIMUM);
    // every complete planner must find the gap.
    ASSERT_TRUE(r.exit_code == 0 || (planner == "potential_field" && r.exit_code == 3))
        << r;
    const auto plan = ParseJson<v1::PlanResponse>(r.out);
    EXPECT_EQ(plan.planner(), planner);
    if (!plan.found()) {
      EXPECT_EQ(plan.outcome(), v1::PLAN_OUTCOME_LOCAL_MINIMUM);
      continue;
    }
    ASSERT_GE(plan.path_size(), 2);
    EXPECT_EQ(plan.path(0).x(), 2);
    EXPECT_EQ(plan.path(0).y(), 2);
    EXPECT_EQ(plan.path(plan.path_size() - 1).x(), 17);
    EXPECT_EQ(plan.path(plan.path_size() - 1).y(), 3);
    // Through the gap: the wall column is only crossed in rows 8..9.
    for (const v1::Cell& c : plan.path()) {
      if (c.x() == 10) {
        EXPECT_TRUE(c.y() == 8 || c.y() == 9) << c.y();
      }
    }
    // Never shorter than the straight line, and A*'s optimum bounds every
    // optimal planner.
    EXPECT_GE(plan.length(), std::hypot(15.0, 1.0) - 1e-9);
    if (planner == "rtaa_star" || planner == "lrta_star") {
      EXPECT_GT(plan.episodes(), 0);
    }
  }
}

TEST_F(E2eTest, RobotRadiusKeepsThePathAwayFromWalls) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap(), {"--resolution=0.5"}));
  // With a 1-cell radius the two-row gap narrows to nothing: cells of rows 8
  // and 9 next to the wall ends are within 1 cell of a lethal cell.
  const v1::PlanResponse blocked =
      PlanJson({"walled", "2", "2", "17", "3", "--robot_radius_cells=1"}, 3);
  EXPECT_EQ(blocked.outcome(), v1::PLAN_OUTCOME_NO_PATH);
  EXPECT_DOUBLE_EQ(blocked.robot_radius_cells(), 1.0);
  // 0.25 m at 0.5 m per cell is half a cell: only lethal cells' centres are
  // within it, so the plan is the plain one.
  const v1::PlanResponse thin =
      PlanJson({"walled", "2", "2", "17", "3", "--robot_radius=0.25"});
  const v1::PlanResponse plain = PlanJson({"walled", "2", "2", "17", "3"});
  EXPECT_DOUBLE_EQ(thin.robot_radius_cells(), 0.5);
  EXPECT_NEAR(thin.cost(), plain.cost(), 1e-9);
  // A start inside the inflated band is refused with the reason.
  ExpectRpcError({"plan", "walled", "9", "2", "17", "3", "--robot_radius_cells=1.5"},
                 "INVALID_ARGUMENT", {"start", "robot radius"});
  ExpectRpcError({"plan", "walled", "2", "2", "17", "3", "--robot_radius_cells=-1"},
                 "INVALID_ARGUMENT", {"robot_radius_cells"});
  const ProcessResult both =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--robot_radius=1",
           "--robot_radius_cells=1"});
  EXPECT_EQ(both.exit_code, 2) << both;
}

// --min_clearance in metres: the path pays for passing near walls, keeps
// the clearance where the room allows, and says how close it came.
TEST_F(E2eTest, MinimumClearanceCostsNearWallsAndIsReported) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap(), {"--resolution=0.5"}));
  const v1::PlanResponse plain = PlanJson({"walled", "2", "2", "17", "3"});
  const v1::PlanResponse wide =
      PlanJson({"walled", "2", "2", "17", "3", "--min_clearance=1.5"});
  ASSERT_EQ(wide.outcome(), v1::PLAN_OUTCOME_FOUND);
  EXPECT_FALSE(plain.has_clearance());
  ASSERT_TRUE(wide.has_clearance());
  // Through the two-row gap in column 10, one cell from the wall ends.
  EXPECT_DOUBLE_EQ(wide.min_clearance_cells(), 1.0);
  EXPECT_DOUBLE_EQ(wide.min_clearance_m(), 0.5);
  EXPECT_GT(wide.cost(), plain.cost());
  // The cached shortest path map and D* Lite plan on the same shaped grid
  // (the clearance is part of their cache key: the plain field is not used).
  for (const char* planner : {"--planner=spm", "--planner=dstar_lite", "--planner=spm"}) {
    const v1::PlanResponse cached =
        PlanJson({"walled", "2", "2", "17", "3", "--min_clearance=1.5", planner});
    EXPECT_NEAR(cached.cost(), wide.cost(), 1e-6) << planner;
    EXPECT_DOUBLE_EQ(cached.min_clearance_cells(), 1.0) << planner;
    EXPECT_NEAR(PlanJson({"walled", "2", "2", "17", "3", planner}).cost(), plain.cost(),
                1e-6)
        << planner;
  }
  // A Navigate session's D* Lite plans on the same shaped grid.
  const ProcessResult nav =
      Ctl({"navigate", "walled", "2", "2", "17", "3", "--min_clearance=1.5"});
  ASSERT_EQ(nav.exit_code, 0) << nav;
  EXPECT_TRUE(
      absl::StrContains(nav.out, absl::StrFormat("found, cost %.6f,", wide.cost())))
      << nav << " want cost " << wide.cost();
  const ProcessResult text =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--min_clearance_cells=3"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "clearance:   1 cells (0.5 m)")) << text;
  ExpectRpcError({"plan", "walled", "2", "2", "17", "3", "--planner=navmesh",
                  "--min_clearance=1"},
                 "INVALID_ARGUMENT", {"min_clearance", "navmesh"});
  ExpectRpcError({"plan", "walled", "2", "2", "17", "3", "--cost_weight=0",
                  "--min_clearance=1"},
                 "INVALID_ARGUMENT", {"min_clearance", "cost_weight 0"});
  const ProcessResult both = Ctl({"plan", "walled", "2", "2", "17", "3",
                                  "--min_clearance=1", "--min_clearance_cells=1"});
  EXPECT_EQ(both.exit_code, 2) << both;
}

// --inflation_radius (Nav2's 0.55 m and factor 10 at 5 cm per cell): from
// beside one wall to beside it again, the plain plan hugs the wall and the
// inflated one keeps to the middle, where the costs are lowest. Every RPC
// that plans plans on the same shaped grid.
TEST_F(E2eTest, InflationRadiusKeepsThePathInTheMiddleOfACorridor) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("corridor", CorridorMap(), {"--resolution=0.05"}));
  const std::vector<std::string> ends = {"corridor", "1", "1", "38", "1"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = ends;
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  auto plan = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = with(std::move(extra));
    args.insert(args.begin(), "plan");
    return args;
  };
  // The row of the path's middle cell, and its smallest distance to a wall
  // along columns 12..27.
  auto middle = [](const v1::PlanResponse& plan) {
    int nearest = 100;
    for (const v1::Cell& c : plan.path()) {
      if (c.x() >= 12 && c.x() <= 27) nearest = std::min({nearest, c.y(), 10 - c.y()});
    }
    return nearest;
  };
  const v1::PlanResponse plain = PlanJson(ends);
  EXPECT_EQ(middle(plain), 1);
  const v1::PlanResponse inflated = PlanJson(with({"--inflation_radius=0.55"}));
  ASSERT_EQ(inflated.outcome(), v1::PLAN_OUTCOME_FOUND);
  EXPECT_EQ(middle(inflated), 5) << "the middle row is 5 cells from both walls";
  EXPECT_GT(inflated.cost(), plain.cost());
  // The factor is Nav2's default: saying so changes nothing; in cells too.
  EXPECT_NEAR(PlanJson(with({"--inflation_radius_cells=11", "--cost_scaling_factor=10"}))
                  .cost(),
              inflated.cost(), 1e-9);
  // Beyond a 0.2 m robot (4 cells) the same decay starts 4 cells out: rows
  // 1..4 are inscribed, so the start is refused, and from the middle the
  // path stays there.
  ExpectRpcError({"plan", "corridor", "1", "1", "38", "1", "--robot_radius=0.2",
                  "--inflation_radius=0.55"},
                 "INVALID_ARGUMENT", {"start", "robot radius"});
  EXPECT_EQ(middle(PlanJson({"corridor", "1", "5", "38", "5", "--robot_radius=0.2",
                             "--inflation_radius=0.55"})),
            5);

  // The cached shortest path map and D* Lite (the inflation is part of their
  // key), a Navigate session, a cost-to-go field and a batch item.
  for (const char* planner : {"--planner=spm", "--planner=dstar_lite"}) {
    EXPECT_NEAR(PlanJson(with({"--inflation_radius=0.55", planner})).cost(),
                inflated.cost(), 1e-6)
        << planner;
    EXPECT_NEAR(PlanJson(with({planner})).cost(), plain.cost(), 1e-6) << planner;
  }
  const ProcessResult nav = Ctl({"navigate", "corridor", "1", "1", "38", "1",
                                 "--inflation_radius=0.55"});
  ASSERT_EQ(nav.exit_code, 0) << nav;
  EXPECT_TRUE(
      absl::StrContains(nav.out, absl::StrFormat("found, cost %.6f,", inflated.cost())))
      << nav << " want cost " << inflated.cost();
  const ProcessResult field =
      Ctl({"cost-to-go", "corridor", "38", "1", "--window", "1,1,1,1", "--output=csv",
           "--inflation_radius=0.55"});
  ASSERT_EQ(field.exit_code, 0) << field;
  // The CSV's last column of its one row (the field is single precision).
  auto last_number = [](const std::string& csv) {
    const std::vector<std::string> rows = absl::StrSplit(csv, '\n', absl::SkipEmpty());
    double value = -1.0;
    if (rows.size() != 2) return -1.0;
    return absl::SimpleAtod(rows[1].substr(rows[1].rfind(',') + 1), &value) ? value : -1.0;
  };
  EXPECT_NEAR(last_number(field.out), inflated.cost(), 1e-4) << field;
  const ProcessResult batch =
      Ctl({"batch", MapFile("items.txt", "a corridor 1 1 38 1\n"), "--output=csv",
           "--inflation_radius=0.55"});
  ASSERT_EQ(batch.exit_code, 0) << batch;
  const std::vector<std::string> item =
      absl::StrSplit(batch.out.substr(batch.out.find('\n') + 1), ',');
  ASSERT_GE(item.size(), 4u) << batch;
  EXPECT_EQ(item[2], "FOUND") << batch;
  double batch_cost = 0.0;
  ASSERT_TRUE(absl::SimpleAtod(item[3], &batch_cost)) << batch;
  EXPECT_NEAR(batch_cost, inflated.cost(), 1e-6) << batch;

  // Refused where costs do not count, and bad values, naming the option.
  ExpectRpcError(plan({"--planner=navmesh", "--inflation_radius=0.55"}),
                 "INVALID_ARGUMENT", {"inflation_radius", "navmesh"});
  ExpectRpcError(plan({"--cost_weight=0", "--inflation_radius=0.55"}),
                 "INVALID_ARGUMENT", {"inflation_radius", "cost_weight 0"});
  ExpectRpcError(plan({"--robot_radius=0.3", "--inflation_radius=0.2"}),
                 "INVALID_ARGUMENT",
                 {"inflation_radius_m", "smaller than the robot radius"});
  ExpectRpcError(plan({"--inflation_radius=0.55", "--cost_scaling_factor=-1"}),
                 "INVALID_ARGUMENT", {"cost_scaling_factor"});
  const ProcessResult both =
      Ctl(plan({"--inflation_radius=1", "--inflation_radius_cells=1"}));
  EXPECT_EQ(both.exit_code, 2) << both;
}

TEST_F(E2eTest, SimplifyKeepsOnlyTheTurns) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const v1::PlanResponse plain = PlanJson({"walled", "2", "2", "17", "3"});
  const v1::PlanResponse simple =
      PlanJson({"walled", "2", "2", "17", "3", "--simplify"});
  EXPECT_FALSE(plain.any_angle());
  EXPECT_TRUE(simple.any_angle());
  EXPECT_LT(simple.path_size(), plain.path_size());
  EXPECT_LE(simple.length(), plain.length() + 1e-9);
  EXPECT_LE(simple.cost(), plain.cost() + 1e-9);
  const ProcessResult text = Ctl({"plan", "walled", "2", "2", "17", "3", "--simplify"});
  EXPECT_TRUE(absl::StrContains(text.out, "vertices, any-angle")) << text;
}

TEST_F(E2eTest, DistanceTransformWritesItsCostToGoField) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const std::string csv = (temp_dir_ / "ctg.csv").string();
  const ProcessResult r =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--planner=distance_transform",
           "--cost_to_go_file", csv});
  ASSERT_EQ(r.exit_code, 0) << r;
  std::ifstream in(csv);
  std::vector<std::vector<std::string>> rows;
  for (std::string line; std::getline(in, line);) {
    rows.push_back(absl::StrSplit(line, ','));
  }
  ASSERT_EQ(rows.size(), 12u);
  for (const auto& row : rows) ASSERT_EQ(row.size(), 20u);
  EXPECT_EQ(rows[3][17], "0.000000");  // the goal
  EXPECT_EQ(rows[0][10], "inf");       // a wall cell
  double start_cost = 0;
  ASSERT_TRUE(absl::SimpleAtod(rows[2][2], &start_cost));
  const v1::PlanResponse astar = PlanJson({"walled", "2", "2", "17", "3"});
  EXPECT_NEAR(start_cost, astar.cost(), 1e-5);
}

TEST_F(E2eTest, AntColonyThroughPathctl) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const ProcessResult text =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--planner=ant_colony",
           "--ant_colony=ants=30,iterations=60,seed=7"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "ant colony:  best path from iteration"))
      << text;
  const std::vector<std::string> args = {"walled", "2", "2", "17", "3",
                                         "--planner=ant_colony",
                                         "--ant_colony=ants=30,iterations=60,seed=7"};
  const v1::PlanResponse a = PlanJson(args);
  const v1::PlanResponse b = PlanJson(args);
  ASSERT_TRUE(a.found());
  EXPECT_GE(a.ant_colony().best_iteration(), 1);
  EXPECT_LE(a.ant_colony().best_iteration(), a.ant_colony().iterations_run());
  EXPECT_LE(a.ant_colony().iterations_run(), 60);
  // One seed, one answer, and never below A*'s optimum.
  EXPECT_EQ(a.path_size(), b.path_size());
  EXPECT_DOUBLE_EQ(a.cost(), b.cost());
  EXPECT_GE(a.cost(), PlanJson({"walled", "2", "2", "17", "3"}).cost() - 1e-9);
  // A bad value is the server's INVALID_ARGUMENT naming the option; an
  // unknown key is pathctl's usage error.
  ExpectRpcError({"plan", "walled", "2", "2", "17", "3", "--planner=ant_colony",
                  "--ant_colony=rho=2"},
                 "INVALID_ARGUMENT", {"options.ant_colony.rho 2"});
  const ProcessResult unknown = Ctl({"plan", "walled", "2", "2", "17", "3",
                                     "--planner=ant_colony", "--ant_colony=ant=3"});
  EXPECT_EQ(unknown.exit_code, 2) << unknown;
  EXPECT_TRUE(absl::StrContains(unknown.err, "unknown key 'ant'")) << unknown;
}

TEST_F(E2eTest, ReactionDiffusionThroughPathctl) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const ProcessResult text = Ctl({"plan", "walled", "2", "2", "17", "3",
                                  "--planner=reaction_diffusion",
                                  "--reaction_diffusion=threshold=0.15"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "vs exact:    arrival time off by")) << text;
  const v1::PlanResponse plan =
      PlanJson({"walled", "2", "2", "17", "3", "--planner=reaction_diffusion"});
  ASSERT_TRUE(plan.found());
  const v1::PlanResponse astar = PlanJson({"walled", "2", "2", "17", "3"});
  EXPECT_NEAR(plan.reaction_diffusion().optimal_cost(), astar.cost(), 1e-9);
  EXPECT_NEAR(plan.reaction_diffusion().cost_ratio(), plan.cost() / astar.cost(), 1e-9);
  EXPECT_GE(plan.reaction_diffusion().cost_ratio(), 1.0 - 1e-12);
  EXPECT_GT(plan.reaction_diffusion().reached_cells(), 0);
  ExpectRpcError({"plan", "walled", "2", "2", "17", "3", "--planner=reaction_diffusion",
                  "--reaction_diffusion=time_step=1"},
                 "INVALID_ARGUMENT", {"options.reaction_diffusion.time_step 1"});
}

TEST_F(E2eTest, PotentialFieldReportsWhereItStalled) {
  // A cup open towards the start: the goal's pull holds the robot inside it.
  std::string text = "type octile\nheight 15\nwidth 15\nmap\n";
  for (int y = 0; y < 15; ++y) {
    std::string row(15, '.');
    if (y >= 4 && y <= 10) row[10] = '@';
    if (y == 4 || y == 10) {
      for (int x = 6; x <= 10; ++x) row[x] = '@';
    }
    text += row + "\n";
  }
  ASSERT_NO_FATAL_FAILURE(CreateMap("cup", text));
  const ProcessResult r =
      Ctl({"plan", "cup", "2", "7", "13", "7", "--planner=potential_field"});
  EXPECT_EQ(r.exit_code, 3) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "outcome:     LOCAL_MINIMUM")) << r;
  EXPECT_TRUE(absl::StrContains(r.out, "stalled at:")) << r;
  const v1::PlanResponse plan =
      PlanJson({"cup", "2", "7", "13", "7", "--planner=potential_field"}, 3);
  EXPECT_GT(plan.stall_point().x(), 5.0);
  EXPECT_LT(plan.stall_point().x(), 10.0);
  // Around the cup's back the field leads straight to the goal.
  const v1::PlanResponse open =
      PlanJson({"cup", "2", "1", "13", "1", "--planner=potential_field"});
  EXPECT_GT(open.trajectory_size(), 1);
}

TEST_F(E2eTest, JpsRefusesWeightedMaps) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const ProcessResult set = Ctl({"maps", "set", "room", "4", "4", "100"});
  ASSERT_EQ(set.exit_code, 0) << set;
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--planner=jps"},
                 "FAILED_PRECONDITION", {"jps", "(4, 4)", "cost_weight 0"});
  // Ignoring cell costs the map is uniform again.
  const v1::PlanResponse flat =
      PlanJson({"room", "0", "0", "9", "9", "--planner=jps", "--cost_weight=0"});
  EXPECT_NEAR(flat.cost(), 9 * kSqrt2, 1e-9);
}

TEST_F(E2eTest, BadPlannerOptionsNameTheField) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--planner=weighted_astar",
                  "--heuristic_weight=0.5"},
                 "INVALID_ARGUMENT", {"heuristic_weight", "0.5"});
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--planner=rtaa_star",
                  "--lookahead=-1"},
                 "INVALID_ARGUMENT", {"lookahead"});
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--planner=potential_field",
                  "--pf_step=-1"},
                 "INVALID_ARGUMENT", {"potential_field.step_size"});
  const ProcessResult shape = Ctl({"plan", "room", "0", "0", "9", "9",
                                   "--planner=potential_field", "--pf_attractive=cubic"});
  EXPECT_EQ(shape.exit_code, 2) << shape;
  // A whole cost-to-go field is refused for maps over 4 Mi cells.
  std::string big = "type octile\nheight 2100\nwidth 2100\nmap\n";
  const std::string row = std::string(2100, '.') + "\n";
  for (int y = 0; y < 2100; ++y) big += row;
  ASSERT_NO_FATAL_FAILURE(CreateMap("big", big));
  ExpectRpcError({"plan", "big", "0", "0", "9", "9", "--planner=distance_transform",
                  "--cost_to_go_file", (temp_dir_ / "big.csv").string()},
                 "INVALID_ARGUMENT", {"return_cost_to_go", "4194304"});
  // The server keeps serving.
  EXPECT_TRUE(PlanJson({"room", "0", "0", "9", "9"}).found());
}

TEST_F(E2eTest, BlockingAPathCellChangesThePlan) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse before = PlanJson({"room", "0", "0", "9", "9"});
  ASSERT_TRUE(before.found());
  ASSERT_GE(before.path_size(), 3);
  const v1::Cell blocked = before.path(before.path_size() / 2);

  const ProcessResult set =
      Ctl({"maps", "set", "room", absl::StrCat(blocked.x()),
           absl::StrCat(blocked.y()), "254"});
  ASSERT_EQ(set.exit_code, 0) << set;
  EXPECT_TRUE(absl::StrContains(set.out, "now at version 2")) << set;

  const v1::PlanResponse after = PlanJson({"room", "0", "0", "9", "9"});
  ASSERT_TRUE(after.found());
  EXPECT_GT(after.map_version(), before.map_version());
  EXPECT_NE(PathCells(after), PathCells(before));
  for (const v1::Cell& c : after.path()) {
    EXPECT_FALSE(c.x() == blocked.x() && c.y() == blocked.y())
        << "path still crosses the blocked cell (" << c.x() << "," << c.y()
        << ")";
  }
  // The diagonal was the unique optimum, so any detour costs more.
  EXPECT_GT(after.cost(), before.cost() + 1e-9);
}

TEST_F(E2eTest, WallingOffTheGoalExitsThree) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const ProcessResult rect =
      Ctl({"maps", "rect", "room", "0", "5", "9", "5", "lethal"});
  ASSERT_EQ(rect.exit_code, 0) << rect;
  EXPECT_TRUE(absl::StrContains(rect.out, "(10 cells changed)")) << rect;

  const v1::PlanResponse plan = PlanJson({"room", "0", "0", "9", "9"}, 3);
  EXPECT_FALSE(plan.found());
  EXPECT_EQ(plan.outcome(), v1::PLAN_OUTCOME_NO_PATH);
  EXPECT_EQ(plan.path_size(), 0);

  const ProcessResult text = Ctl({"plan", "room", "0", "0", "9", "9"});
  EXPECT_EQ(text.exit_code, 3) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "found:       no")) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "outcome:     NO_PATH")) << text;
}

TEST_F(E2eTest, PlansBetweenWorldPoints) {
  ASSERT_NO_FATAL_FAILURE(
      CreateMap("room", OpenRoomMap(), {"--resolution=0.5"}));
  // With 0.5 m cells and the origin at 0, (0.3, 0.2) m lies in cell (0,0) and
  // (4.9, 0.1) m in cell (9,0).
  const v1::PlanResponse plan =
      PlanJson({"room", "0.3", "0.2", "4.9", "0.1", "--world"});
  ASSERT_TRUE(plan.found());
  EXPECT_EQ(plan.start().x(), 0);
  EXPECT_EQ(plan.start().y(), 0);
  EXPECT_EQ(plan.goal().x(), 9);
  EXPECT_EQ(plan.goal().y(), 0);
  EXPECT_NEAR(plan.length(), 9.0, 1e-9);
  ASSERT_EQ(plan.world_path_size(), plan.path_size());
  EXPECT_NEAR(plan.world_path(0).x(), 0.25, 1e-9);
  EXPECT_NEAR(plan.world_path(0).y(), 0.25, 1e-9);

  const ProcessResult text =
      Ctl({"plan", "room", "0.3", "0.2", "4.9", "0.1", "--world"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "world path (m): (0.25,0.25)"))
      << text;
}

TEST_F(E2eTest, ServerErrorsReachTheUser) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));

  ExpectRpcError({"plan", "nosuch", "0", "0", "1", "1"}, "NOT_FOUND",
                 {"nosuch"});
  ExpectRpcError({"maps", "delete", "nosuch"}, "NOT_FOUND");
  ExpectRpcError({"maps", "set", "nosuch", "0", "0", "0"}, "NOT_FOUND");

  ExpectRpcError({"plan", "room", "20", "20", "0", "0"}, "INVALID_ARGUMENT",
                 {"start"});
  ExpectRpcError({"plan", "room", "-1", "0", "0", "0"}, "INVALID_ARGUMENT",
                 {"start"});
  ASSERT_EQ(Ctl({"maps", "set", "room", "9", "9", "lethal"}).exit_code, 0);
  ExpectRpcError({"plan", "room", "0", "0", "9", "9"}, "INVALID_ARGUMENT",
                 {"goal"});
  ExpectRpcError({"maps", "set", "room", "10", "0", "0"}, "INVALID_ARGUMENT");

  // The server parses map files; its message names the problem.
  ExpectRpcError(
      {"maps", "create", "bad", "--from",
       MapFile("bad.map", "type octile\nheight 2\nwidth 3\nmap\n..x\n...\n")},
      "INVALID_ARGUMENT");
  ExpectRpcError(
      {"maps", "create", "room", "--from", MapFile("room2.map", OpenRoomMap())},
      "ALREADY_EXISTS");
  const ProcessResult replaced =
      Ctl({"maps", "create", "room", "--from",
           MapFile("room3.map", OpenRoomMap(5, 5)), "--replace", "--json"});
  ASSERT_EQ(replaced.exit_code, 0) << replaced;
  const auto info = ParseJson<v1::CreateMapResponse>(replaced.out).info();
  EXPECT_EQ(info.width(), 5);
  EXPECT_GT(info.version(), 2u) << "a replaced map's version continues";

  // Optimistic concurrency: an update based on a stale version is refused.
  const uint64_t version = info.version();
  ExpectRpcError({"maps", "set", "room", "1", "1", "lethal",
                  absl::StrCat("--expected_version=", version - 1)},
                 "ABORTED");
  const ProcessResult fresh =
      Ctl({"maps", "set", "room", "1", "1", "lethal", "--expected_version",
           absl::StrCat(version)});
  EXPECT_EQ(fresh.exit_code, 0) << fresh;
  EXPECT_TRUE(
      absl::StrContains(fresh.out, absl::StrCat("version ", version + 1)))
      << fresh;

  // A local file that does not exist never reaches the server; NOT_FOUND
  // exits 7 whether the map or the file is missing.
  const ProcessResult missing = Ctl(
      {"maps", "create", "x", "--from", (temp_dir_ / "missing.map").string()});
  EXPECT_EQ(missing.exit_code, 7) << missing;
  EXPECT_TRUE(absl::StrContains(missing.err, "missing.map")) << missing;
}

TEST_F(E2eTest, UsageErrorsExitTwo) {
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::string txt = MapFile("room.txt", OpenRoomMap());
  const std::vector<Case> cases = {
      {{}, "missing command"},
      {{"frobnicate"}, "unknown command 'frobnicate'"},
      {{"maps"}, "maps needs a subcommand"},
      {{"maps", "shred", "x"}, "unknown maps subcommand 'shred'"},
      {{"maps", "create", "room"}, "--from"},
      {{"maps", "create", "room", "--from", txt}, "unknown map file type"},
      {{"maps", "get"}, "maps get takes one NAME"},
      {{"maps", "set", "room", "0", "0"}, "maps set takes NAME X Y COST"},
      {{"maps", "set", "room", "0", "zero", "0"},
       "Y: 'zero' is not an integer"},
      {{"maps", "set", "room", "0", "0", "300"}, "COST: '300'"},
      {{"maps", "rect", "room", "0", "0", "1", "1"}, "maps rect takes"},
      {{"plan", "room", "0", "0"}, "plan takes NAME SX SY GX GY"},
      {{"plan", "room", "0", "0", "1", "x"}, "GY: 'x' is not an integer"},
      {{"plan", "room", "0", "0", "1", "1", "--planner=warp"},
       "unknown planner 'warp'; valid planners: astar, dijkstra, bfs"},
      {{"plan", "room", "0", "0", "1", "1", "--connectivity=6"},
       "--connectivity"},
      {{"--bogus", "maps", "list"}, "unknown flag --bogus"},
      {{"maps", "list", "--timeout=soon"}, "--timeout"},
      {{"maps", "list", "--server"}, "--server needs a value"},
      {{"navigate", "room", "0", "0", "1"}, "navigate takes NAME SX SY GX GY"},
      {{"navigate", "room", "0", "0", "1", "1", "--planner", "astar"},
       "--planner: navigate plans with dstar_lite or a kinematic planner"},
      {{"navigate", "room", "0", "0", "1", "1", "--script_file", "x"}, "--script_file"},
      {{"cost-to-go", "room", "1"}, "cost-to-go takes NAME GX GY"},
      {{"cost-to-go", "room", "1", "1", "--window=1,2,3"},
       "--window takes X,Y,W,H"},
      {{"cost-to-go", "room", "1", "1", "--window=0,0,0,4"},
       "--window width and height must be positive"},
      {{"cache-stats", "spm"}, "cache-stats takes no arguments"},
      // A flag the command does not read is named, not ignored: plan used
      // to write no picture for -o and say nothing.
      {{"plan", "room", "0", "0", "1", "1", "-o", "x.png"},
       "-o does not apply to plan; simulate, render read it"},
      {{"maps", "list", "--planner=astar"}, "--planner does not apply to maps list"},
      {{"health", "--count=3"}, "--count does not apply to health"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(absl::StrJoin(c.args, " "));
    const ProcessResult r = Ctl(c.args);
    EXPECT_EQ(r.exit_code, 2) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, "error: ")) << r;
    EXPECT_TRUE(absl::StrContains(r.err, c.says)) << r;
    EXPECT_TRUE(absl::StrContains(r.err, "usage:")) << r;
    EXPECT_EQ(r.out, "") << r;
  }
  // A command's usage error shows that command's usage, not every command's.
  const ProcessResult plan = Ctl({"plan", "room", "0", "0"});
  EXPECT_TRUE(absl::StrContains(plan.err, "usage: pathctl [flags] plan NAME SX SY GX GY"))
      << plan;
  EXPECT_TRUE(absl::StrContains(plan.err, "run 'pathctl help plan' for details")) << plan;
  EXPECT_FALSE(absl::StrContains(plan.err, "maps create")) << plan;
  EXPECT_FALSE(fs::exists("x.png"));

  const ProcessResult help = RunPathctl({"--help"});
  EXPECT_EQ(help.exit_code, 0) << help;
  EXPECT_TRUE(absl::StrContains(help.out, "exit codes:")) << help;
  EXPECT_TRUE(absl::StrContains(help.out, "3  plan ran but found no path"))
      << help;
}

}  // namespace pathd::e2e_test
