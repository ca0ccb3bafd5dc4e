// e2e_test: batch, via points, bench, the output formats, exit codes and
// progress bars.
#include "tests/e2e/e2e_fixture.h"

namespace pathd::e2e_test {

TEST_F(E2eTest, BatchAnswersEveryLineAndExitsOneOnItemErrors) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_NO_FATAL_FAILURE(CreateMap("hall", OpenRoomMap(30, 5)));
  ASSERT_EQ(Ctl({"maps", "set", "room", "5", "5", "lethal"}).exit_code, 0);
  const std::string good = MapFile("good.txt",
                                   "# ID MAP SX SY GX GY [PLANNER]\n"
                                   "r1 room 0 0 9 9\n"
                                   "\n"
                                   "h1 hall 0 0 29 4 dijkstra\n"
                                   "r2 room 0 9 9 0 jps\n");
  const ProcessResult ok = Ctl({"batch", good, "--cost_weight", "0"});
  ASSERT_EQ(ok.exit_code, 0) << ok;
  std::vector<std::string> lines = absl::StrSplit(ok.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 4u) << ok;
  std::sort(lines.begin(), lines.end() - 1);
  // 25 straight + 4 diagonal moves; r2 cannot cut the corner at (5,5), so
  // 8 diagonal + 2 straight.
  EXPECT_TRUE(absl::StartsWith(lines[0], "h1 found cost 30.656854 ")) << lines[0];
  EXPECT_TRUE(absl::StartsWith(lines[1], "r1 found cost ")) << lines[1];
  EXPECT_TRUE(absl::StartsWith(lines[2], "r2 found cost 13.313708 ")) << lines[2];
  EXPECT_TRUE(absl::StartsWith(lines[3], "summary: 3 of 3 answered: 3 found, 0 no path, "
                                         "0 errors in "))
      << lines[3];

  const std::string mixed = MapFile("mixed.txt",
                                    "a room 0 0 9 9\n"
                                    "b room 5 5 0 0\n"
                                    "c room 0 0 10 0\n"
                                    "d nowhere 0 0 1 1\n"
                                    "e hall 0 0 29 0\n");
  const ProcessResult r = Ctl({"batch", mixed});
  EXPECT_EQ(r.exit_code, 1) << r;
  lines = absl::StrSplit(r.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 6u) << r;
  std::sort(lines.begin(), lines.end() - 1);
  EXPECT_TRUE(absl::StartsWith(lines[0], "a found ")) << lines[0];
  EXPECT_EQ(lines[1],
            "b error INVALID_ARGUMENT START_OCCUPIED: start (5, 5) is on a blocked "
            "cell (cost 254)");
  EXPECT_EQ(lines[2],
            "c error INVALID_ARGUMENT GOAL_OUTSIDE_MAP: goal (10, 0) is outside the "
            "10 x 10 map");
  EXPECT_TRUE(absl::StartsWith(lines[3], "d error NOT_FOUND MAP_NOT_FOUND: ")) << lines[3];
  EXPECT_TRUE(absl::StartsWith(lines[4], "e found ")) << lines[4];
  EXPECT_TRUE(absl::StartsWith(
      lines[5], "summary: 5 of 5 answered: 2 found, 0 no path, 3 errors in "))
      << lines[5];

  const ProcessResult json = Ctl({"batch", mixed, "--json"});
  EXPECT_EQ(json.exit_code, 1) << json;
  // Only JSON on stdout; the summary goes to stderr.
  lines = absl::StrSplit(json.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(lines.size(), 5u) << json;
  EXPECT_TRUE(absl::StartsWith(json.err, "summary: 5 of 5 answered: ")) << json;
  int errors = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    const auto answer = ParseJson<v1::PlanBatchResponse>(lines[i]);
    if (answer.request_id() == "d") {
      EXPECT_EQ(answer.error().outcome(), v1::PLAN_OUTCOME_MAP_NOT_FOUND);
    }
    errors += answer.has_error();
  }
  EXPECT_EQ(errors, 3);

  const std::string malformed = MapFile("bad.txt", "a room 0 0 9 9\nb room 0 x 9 9\n");
  const ProcessResult bad = Ctl({"batch", malformed});
  EXPECT_EQ(bad.exit_code, 2) << bad;
  EXPECT_TRUE(absl::StrContains(bad.err, "bad.txt:2: '0 x' is not two integers")) << bad;
}


TEST_F(E2eTest, PlanThroughViaPointsWithAllowPartialAndExpansions) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  // Through (12,0) and (5,11): the cost is the sum of the three legs alone.
  const v1::PlanResponse via =
      PlanJson({"walled", "2", "2", "17", "3", "--via", "12,0;5,11"});
  ASSERT_TRUE(via.found());
  EXPECT_EQ(via.reached_goal_index(), 2);
  ASSERT_EQ(via.leg_end_indices_size(), 3);
  EXPECT_EQ(via.path(via.leg_end_indices(0)).x(), 12);
  EXPECT_EQ(via.path(via.leg_end_indices(0)).y(), 0);
  EXPECT_EQ(via.path(via.leg_end_indices(1)).x(), 5);
  EXPECT_EQ(via.path(via.leg_end_indices(1)).y(), 11);
  double legs = 0.0;
  for (const auto& leg : std::vector<std::vector<std::string>>{
           {"2", "2", "12", "0"}, {"12", "0", "5", "11"}, {"5", "11", "17", "3"}}) {
    std::vector<std::string> args = {"walled"};
    args.insert(args.end(), leg.begin(), leg.end());
    args.push_back("--planner=dijkstra");
    legs += PlanJson(args).cost();
  }
  EXPECT_NEAR(via.cost(), legs, 1e-9);
  const ProcessResult text =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--via=12,0;5,11"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(text.out, "via:         2 points; reached the goal\n"))
      << text;
  EXPECT_TRUE(absl::StrContains(
      text.out, absl::StrFormat("legs end at: path[%d], path[%d], path[%d]\n",
                                via.leg_end_indices(0), via.leg_end_indices(1),
                                via.leg_end_indices(2))))
      << text;

  // The goal in a walled-off corner: the last leg fails.
  ASSERT_NO_FATAL_FAILURE(CreateMap("pocket", PocketRoomMap()));
  const ProcessResult failed =
      Ctl({"plan", "pocket", "2", "2", "18", "0", "--via", "12,5"});
  EXPECT_EQ(failed.exit_code, 3) << failed;
  EXPECT_TRUE(absl::StrContains(
      failed.out,
      "reason:      leg 1 (via[0] -> goal): no path from (12, 5) to (18, 0)\n"))
      << failed;
  EXPECT_FALSE(absl::StrContains(failed.out, "path (")) << failed;
  const ProcessResult partial =
      Ctl({"plan", "pocket", "2", "2", "18", "0", "--via", "12,5", "--allow_partial"});
  EXPECT_EQ(partial.exit_code, 3) << partial;
  EXPECT_TRUE(absl::StrContains(partial.out, "reached via[0] (goal index 0)")) << partial;
  EXPECT_TRUE(absl::StrContains(partial.out, " (12,5)\n")) << partial;
  const v1::PlanResponse partial_json = PlanJson(
      {"pocket", "2", "2", "18", "0", "--via", "12,5", "--allow_partial"}, 3);
  EXPECT_EQ(partial_json.reached_goal_index(), 0);
  EXPECT_EQ(partial_json.outcome(), v1::PLAN_OUTCOME_NO_PATH);

  ExpectRpcError({"plan", "walled", "2", "2", "17", "3", "--via", "1,1;10,0"},
                 "INVALID_ARGUMENT", {"via[1] (10, 0) is on a blocked cell"});
  EXPECT_EQ(Ctl({"plan", "walled", "2", "2", "17", "3", "--via", "1;2"}).exit_code, 2);

  // --expansions: as many cells as expansions, until the server's cap.
  const v1::PlanResponse expanded =
      PlanJson({"walled", "2", "2", "17", "3", "--expansions"});
  EXPECT_GT(expanded.expansions(), 0);
  EXPECT_EQ(expanded.expanded_size(), expanded.expansions());
  const ProcessResult count =
      Ctl({"plan", "walled", "2", "2", "17", "3", "--expansions"});
  EXPECT_TRUE(absl::StrContains(
      count.out, absl::StrFormat("expanded:    %d cells returned\n",
                                 expanded.expansions())))
      << count;
  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--max_returned_expansions=5"}));
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", WalledRoomMap()));
  const v1::PlanResponse capped =
      PlanJson({"walled", "2", "2", "17", "3", "--expansions"});
  EXPECT_EQ(capped.expanded_size(), 5);
  EXPECT_TRUE(capped.expanded_truncated());
}

// pathctl bench: a one-second closed loop at concurrency 4 against the real
// daemon answers every request (the shape of the report, not its timing),
// and --movingai loads a map and sends exactly its scenarios.
TEST_F(E2eTest, BenchRunsAClosedLoopWithoutErrors) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap(32, 32)));
  const ProcessResult text = Ctl({"bench", "room", "--duration", "1s", "--warmup",
                                  "200ms", "--concurrency", "4", "--planner", "astar"});
  ASSERT_EQ(text.exit_code, 0) << text;
  for (const char* line :
       {"map:         room\n", "planner:     astar\n",
        "queries:     1000 random pairs of free cells\n",
        "load:        4 concurrent requests over 1 channel(s)", "throughput:  ",
        "latency us:  p50 ", "errors:      none\n"}) {
    EXPECT_TRUE(absl::StrContains(text.out, line)) << "missing '" << line << "'\n"
                                                   << text;
  }
  // stderr is a pipe here, not a terminal: no progress line.
  EXPECT_EQ(text.err, "") << text;

  const ProcessResult json = Ctl({"bench", "room", "--duration=1s", "--warmup=0s",
                                  "--concurrency=4", "--channels=2", "--json"});
  ASSERT_EQ(json.exit_code, 0) << json;
  const auto report = ParseJson<google::protobuf::Struct>(json.out);
  const auto& f = report.fields();
  ASSERT_TRUE(f.contains("requests") && f.contains("latency_us")) << json;
  const double requests = f.at("requests").number_value();
  EXPECT_GT(requests, 0) << json;
  EXPECT_EQ(f.at("ok").number_value(), requests) << json;
  EXPECT_EQ(f.at("errors").number_value(), 0) << json;
  EXPECT_EQ(f.at("no_path").number_value(), 0) << json;  // one open room
  EXPECT_TRUE(f.at("errors_by_code").struct_value().fields().empty()) << json;
  EXPECT_EQ(f.at("concurrency").number_value(), 4) << json;
  EXPECT_EQ(f.at("channels").number_value(), 2) << json;
  EXPECT_GT(f.at("requests_per_second").number_value(), 0) << json;
  const auto& latency = f.at("latency_us").struct_value().fields();
  EXPECT_LE(latency.at("min").number_value(), latency.at("p50").number_value());
  EXPECT_LE(latency.at("p50").number_value(), latency.at("p95").number_value());
  EXPECT_LE(latency.at("p95").number_value(), latency.at("p99").number_value());
  EXPECT_LE(latency.at("p99").number_value(), latency.at("max").number_value());

  // --movingai: the map is created under its stem, the queries are its
  // scenarios; --duration 0 --requests 30 sends exactly 30 requests.
  const std::string map = MapFile("open.map", OpenRoomMap());
  WriteFile(map + ".scen",
            "version 1\n"
            "0\topen.map\t10\t10\t0\t0\t9\t9\t12.72792206\n"
            "0\topen.map\t10\t10\t9\t0\t0\t9\t12.72792206\n"
            "0\topen.map\t10\t10\t0\t5\t9\t5\t9.00000000\n");
  const ProcessResult scen =
      Ctl({"bench", "--movingai", map, "--duration=0", "--requests=30", "--json"});
  ASSERT_EQ(scen.exit_code, 0) << scen;
  const auto scen_report = ParseJson<google::protobuf::Struct>(scen.out);
  EXPECT_EQ(scen_report.fields().at("map").string_value(), "open") << scen;
  EXPECT_TRUE(absl::StartsWith(scen_report.fields().at("queries").string_value(),
                               "3 scenarios of "))
      << scen;
  EXPECT_EQ(scen_report.fields().at("requests").number_value(), 30) << scen;
  EXPECT_EQ(scen_report.fields().at("errors").number_value(), 0) << scen;
  EXPECT_EQ(Ctl({"maps", "get", "open"}).exit_code, 0);

  // A map that does not exist fails like any call; bad options are usage.
  ExpectRpcError({"bench", "nope", "--duration=1s"}, "NOT_FOUND");
  EXPECT_EQ(Ctl({"bench"}).exit_code, 2);
  EXPECT_EQ(Ctl({"bench", "room", "--duration=0"}).exit_code, 2);
  EXPECT_EQ(Ctl({"bench", "room", "--concurrency=0"}).exit_code, 2);
  EXPECT_EQ(Ctl({"bench", "room", "--planner=nope"}).exit_code, 2);
}

// --output csv: a header row, then rows, for a single result (maps get), a
// list (maps list), a path (plan), a stream (maps watch, batch) and figures
// (bench, check, cost-to-go).
TEST_F(E2eTest, OutputCsvPrintsAHeaderAndRows) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_NO_FATAL_FAILURE(CreateMap("hall", OpenRoomMap(30, 5)));
  const std::string kMapHeader =
      "name,width,height,resolution,origin_x,origin_y,origin_yaw,version,"
      "free_cells,blocked_cells\n";
  const ProcessResult list = Ctl({"maps", "list", "--output", "csv"});
  ASSERT_EQ(list.exit_code, 0) << list;
  std::vector<std::string> rows = absl::StrSplit(list.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(rows.size(), 3u) << list;
  EXPECT_EQ(rows[0] + "\n", kMapHeader);
  std::sort(rows.begin() + 1, rows.end());
  EXPECT_EQ(rows[1], "hall,30,5,1,0,0,0,1,150,0");
  EXPECT_EQ(rows[2], "room,10,10,1,0,0,0,1,100,0");

  const ProcessResult get = Ctl({"maps", "get", "room", "--output=csv"});
  ASSERT_EQ(get.exit_code, 0) << get;
  EXPECT_EQ(get.out, kMapHeader + "room,10,10,1,0,0,0,1,100,0\n");

  const ProcessResult plan = Ctl({"plan", "room", "0", "0", "3", "3", "--output=csv"});
  ASSERT_EQ(plan.exit_code, 0) << plan;
  EXPECT_EQ(plan.out,
            "x,y,world_x,world_y\n0,0,0.5,0.5\n1,1,1.5,1.5\n2,2,2.5,2.5\n3,3,3.5,3.5\n");
  // No path: the header alone, and the exit code says why.
  ASSERT_EQ(Ctl({"maps", "rect", "room", "0", "5", "9", "5", "lethal"}).exit_code, 0);
  const ProcessResult none = Ctl({"plan", "room", "0", "0", "9", "9", "--output=csv"});
  EXPECT_EQ(none.exit_code, 3) << none;
  EXPECT_EQ(none.out, "x,y,world_x,world_y\n");

  const ProcessResult check =
      Ctl({"check", "room", "0", "0", "1", "1", "--output=csv"});
  ASSERT_EQ(check.exit_code, 0) << check;
  EXPECT_EQ(check.out,
            "valid,map_version,poses,cost,length,invalid_poses,invalid_steps,reason\n"
            "true,2,2,1.41421356,1.41421356,,,\n");

  const ProcessResult field = Ctl(
      {"cost-to-go", "room", "1", "1", "--window", "0,0,2,1", "--output=csv"});
  ASSERT_EQ(field.exit_code, 0) << field;
  EXPECT_EQ(field.out, "x,y,cost\n0,0,1.41421354\n1,0,1\n");

  // A stream: one row per event, the header first.
  std::unique_ptr<PathctlProcess> watch =
      StartCtl({"maps", "watch", "hall", "--output=csv", "--count=2"});
  ASSERT_TRUE(watch->WaitForLine("1,RESYNC,30,5,0,0,")) << watch->Finish();
  ASSERT_EQ(Ctl({"maps", "rect", "hall", "2", "1", "3", "1", "lethal"}).exit_code, 0);
  const ProcessResult events = watch->Finish();
  ASSERT_EQ(events.exit_code, 0) << events;
  EXPECT_EQ(events.out,
            "version,kind,width,height,changed_cells,changed_rects,rects\n"
            "1,RESYNC,30,5,0,0,\n"
            "2,UPDATED,,,2,1,\"(2,1)-(3,1)\"\n");  // quoted: it holds commas

  const std::string items = MapFile("items.txt",
                                    "a hall 0 0 4 0\n"
                                    "b nowhere 0 0 1 1\n");
  const ProcessResult batch = Ctl({"batch", items, "--output=csv"});
  EXPECT_EQ(batch.exit_code, 1) << batch;  // item b errored
  rows = absl::StrSplit(batch.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(rows.size(), 3u) << batch;
  EXPECT_EQ(rows[0], "id,status,outcome,cost,length,expansions,time_us,code,message");
  std::sort(rows.begin() + 1, rows.end());
  EXPECT_TRUE(absl::StartsWith(rows[1], "a,found,FOUND,4,4,")) << rows[1];
  EXPECT_TRUE(absl::StartsWith(rows[2], "b,error,")) << rows[2];
  EXPECT_TRUE(absl::StrContains(rows[2], ",NOT_FOUND,")) << rows[2];
  // The summary is not a row: it goes to stderr.
  EXPECT_TRUE(absl::StartsWith(batch.err, "summary: 2 of 2 answered")) << batch;

  const ProcessResult bench = Ctl({"bench", "hall", "--duration=0", "--requests=20",
                                   "--warmup=0s", "--output=csv"});
  ASSERT_EQ(bench.exit_code, 0) << bench;
  rows = absl::StrSplit(bench.out, '\n', absl::SkipEmpty());
  ASSERT_EQ(rows.size(), 2u) << bench;
  const std::vector<std::string> header = absl::StrSplit(rows[0], ',');
  const std::vector<std::string> figures = absl::StrSplit(rows[1], ',');
  ASSERT_EQ(header.size(), figures.size()) << bench;
  EXPECT_EQ(header[0], "map");
  EXPECT_EQ(figures[0], "hall");
  EXPECT_EQ(header[6], "requests");
  EXPECT_EQ(figures[6], "20");
  EXPECT_EQ(header[9], "errors");
  EXPECT_EQ(figures[9], "0");
}

TEST_F(E2eTest, OutputJsonIsTheJsonAliasAndTableTheDefault) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const ProcessResult alias = Ctl({"plan", "room", "0", "0", "9", "9", "--json"});
  const ProcessResult json = Ctl({"plan", "room", "0", "0", "9", "9", "--output=json"});
  ASSERT_EQ(json.exit_code, 0) << json;
  const v1::PlanResponse a = ParseJson<v1::PlanResponse>(alias.out);
  const v1::PlanResponse j = ParseJson<v1::PlanResponse>(json.out);
  EXPECT_EQ(PathCells(a), PathCells(j));
  EXPECT_EQ(j.cost(), a.cost());
  EXPECT_EQ(Ctl({"maps", "list", "--output", "json"}).out,
            Ctl({"maps", "list", "--json"}).out);

  const ProcessResult table = Ctl({"maps", "list", "--output=table"});
  EXPECT_EQ(table.out, Ctl({"maps", "list"}).out);
  EXPECT_EQ(table.out,
            "NAME  SIZE   RESOLUTION  VERSION  FREE  BLOCKED\n"
            "room  10x10           1        1   100        0\n");
  const ProcessResult health = Ctl({"health", "--output=csv"});
  EXPECT_EQ(health.out, "service,status\n,SERVING\n") << health;
}

TEST_F(E2eTest, FormatsACommandCannotPrintAreUsageErrors) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{"metrics", "--output=json"}, "metrics has no --output json"},
      {{"metrics", "--output=csv"}, "metrics has no --output csv"},
      {{"navigate", "room", "0", "0", "9", "9", "--output=csv"},
       "navigate has no --output csv"},
      {{"maps", "get", "room", "--cells", "--output=csv"},
       "maps get --cells has no --output csv"},
      {{"completion", "bash", "--json"}, "completion has no --output json"},
      {{"maps", "list", "--output=xml"}, "--output: unknown format 'xml'"},
      {{"maps", "list", "--output=csv", "--json"},
       "--json is --output=json; it contradicts --output=csv"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(absl::StrJoin(c.args, " "));
    const ProcessResult r = Ctl(c.args);
    EXPECT_EQ(r.exit_code, 2) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, absl::StrCat("error: ", c.says))) << r;
    EXPECT_EQ(r.out, "") << r;
  }
}

// The exit codes scripts branch on, from real failures: every one is
// documented in --help.
TEST_F(E2eTest, ExitCodesTellScriptsWhatWentWrong) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_NO_FATAL_FAILURE(CreateMap("walled", OpenRoomMap()));
  ASSERT_EQ(Ctl({"maps", "rect", "walled", "0", "5", "9", "5", "lethal"}).exit_code, 0);
  struct Case {
    std::vector<std::string> args;
    int exit_code;
    std::string stderr_starts;
  };
  const std::vector<Case> cases = {
      {{"plan", "room", "0", "0", "9", "9"}, 0, ""},
      {{"maps", "create", "room", "--from", MapFile("again.map", OpenRoomMap())},
       1, "error: ALREADY_EXISTS: "},
      {{"plan", "room", "0", "0"}, 2, "error: plan takes"},
      {{"plan", "walled", "0", "0", "9", "9"}, 3, ""},
      {{"check", "walled", "0", "4", "0", "5"}, 4, ""},
      // A deadline that has passed before the call is sent.
      {{"plan", "room", "0", "0", "9", "9", "--timeout=1ns"}, 6,
       "error: DEADLINE_EXCEEDED: "},
      {{"plan", "nosuch", "0", "0", "9", "9"}, 7, "error: NOT_FOUND: "},
      // A missing folder is NOT_FOUND naming it, not PERMISSION_DENIED.
      {{"cost-to-go", "room", "1", "1", "--cost_to_go_file",
        (temp_dir_ / "no_such_dir" / "field.csv").string()},
       7, "error: NOT_FOUND: cannot write "},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(absl::StrJoin(c.args, " "));
    const ProcessResult r = Ctl(c.args);
    EXPECT_EQ(r.exit_code, c.exit_code) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, c.stderr_starts)) << r;
  }
  // Nobody listens on the daemon's port once it has stopped.
  const std::string address = address_;
  EXPECT_EQ(StopDaemon(), 0);
  const ProcessResult down =
      RunPathctl({absl::StrCat("--server=", address), "--timeout=5s", "health"});
  EXPECT_EQ(down.exit_code, 5) << down;
  EXPECT_TRUE(absl::StartsWith(down.err, "error: UNAVAILABLE: ")) << down;

  const ProcessResult help = RunPathctl({"--help"});
  for (const char* line :
       {"\n  5  UNAVAILABLE", "\n  6  DEADLINE_EXCEEDED", "\n  7  NOT_FOUND",
        "\n  8  UNAUTHENTICATED or PERMISSION_DENIED"}) {
    EXPECT_TRUE(absl::StrContains(help.out, line)) << "missing " << line;
  }
}

// Progress bars are for a person at a terminal: with stdout and stderr piped
// (as here, and in every script) long work draws none.
TEST_F(E2eTest, NoProgressBarsWhenOutputIsNotATerminal) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap(32, 32)));
  std::string items;
  for (int i = 0; i < 200; ++i) {
    absl::StrAppend(&items, "q", i, " room 0 0 ", i % 32, " 31\n");
  }
  const ProcessResult batch = Ctl({"batch", MapFile("many.txt", items)});
  ASSERT_EQ(batch.exit_code, 0) << batch;
  EXPECT_EQ(batch.err, "") << batch;
  EXPECT_FALSE(absl::StrContains(batch.out + batch.err, "\r")) << batch;
  const ProcessResult quiet =
      Ctl({"batch", MapFile("few.txt", "a room 0 0 1 1\n"), "--no_progress"});
  EXPECT_EQ(quiet.exit_code, 0) << quiet;
  EXPECT_EQ(quiet.err, "") << quiet;
}

}  // namespace pathd::e2e_test
