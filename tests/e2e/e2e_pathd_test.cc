// e2e_test: pathd's --help, config file and startup line, check, goal
// tolerance, metrics and plan --progress.
#include "tests/e2e/e2e_fixture.h"

namespace pathd::e2e_test {

// Runs pathd with `args` to its exit (a usage error, or --help).
ProcessResult RunPathd(const std::vector<std::string>& args) {
  return PathctlProcess(args, {}, PATHD_BIN).Finish();
}

// The flags `pathd --help` documents, from its "    --name (meaning)" lines.
std::vector<std::string> HelpFlagNames(const std::string& help) {
  std::vector<std::string> names;
  for (absl::string_view line : absl::StrSplit(help, '\n')) {
    if (!absl::ConsumePrefix(&line, "    --")) continue;
    names.emplace_back(line.substr(0, line.find(' ')));
  }
  std::sort(names.begin(), names.end());
  return names;
}

// The keys a config file sets, from its "name: value" lines.
std::vector<std::string> ConfigKeys(const std::string& yaml) {
  std::vector<std::string> keys;
  for (absl::string_view line : absl::StrSplit(yaml, '\n')) {
    if (line.empty() || line[0] == '#') continue;
    keys.emplace_back(line.substr(0, line.find(':')));
  }
  std::sort(keys.begin(), keys.end());
  return keys;
}

// The shipped examples/pathd.yaml sets every flag --help documents (but
// --config) to its default, and pathd starts with it.
TEST_F(E2eTest, HelpDocumentsEveryFlagAndTheExampleConfigSetsEach) {
  const ProcessResult help = RunPathd({"--help"});
  const std::vector<std::string> flags = HelpFlagNames(help.out);
  for (const char* flag : {"config", "address", "cache_bytes", "max_sessions",
                           "session_idle_timeout", "shutdown_grace"}) {
    EXPECT_NE(std::find(flags.begin(), flags.end(), flag), flags.end())
        << "--help misses --" << flag << "\n" << help;
  }
  // Each flag's entry ends with its default.
  std::vector<absl::string_view> defaults = absl::StrSplit(help.out, "default: ");
  EXPECT_EQ(defaults.size() - 1, flags.size()) << help;
  EXPECT_TRUE(absl::StrContains(help.out, "a flag given on the command line "
                                          "overrides the file"))
      << help;

  const std::string example =
      absl::StrCat(PATHD_SOURCE_DIR, "/examples/pathd.yaml");
  std::vector<std::string> settable = flags;
  settable.erase(std::find(settable.begin(), settable.end(), "config"));
  EXPECT_EQ(ConfigKeys(ReadFile(example)), settable);

  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon({absl::StrCat("--config=", example)}));
  EXPECT_EQ(Ctl({"health"}).out, "SERVING\n");
}

TEST_F(E2eTest, ConfigFileSetsFlagsAndTheCommandLineOverridesIt) {
  // 192.0.2.1 is a documentation address no host has: pathd only starts
  // because StartDaemon's --address=127.0.0.1:0 overrides the file's.
  const std::string config = MapFile(
      "pathd.yaml",
      "address: 192.0.2.1:50051\nmax_expansions: 10\nshutdown_grace: 2s\n");
  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon({absl::StrCat("--config=", config)}));
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse limited =
      PlanJson({"room", "0", "0", "9", "9", "--planner=dijkstra"}, 3);
  EXPECT_EQ(limited.outcome(), v1::PLAN_OUTCOME_EXPANSION_LIMIT);
  EXPECT_TRUE(absl::StrContains(limited.reason(), "expansion limit of 10"))
      << limited.reason();

  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon(
      {absl::StrCat("--config=", config), "--max_expansions=0"}));
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse found =
      PlanJson({"room", "0", "0", "9", "9", "--planner=dijkstra"});
  EXPECT_TRUE(found.found());
  EXPECT_EQ(PathCells(found).size(), 10u);
}

TEST_F(E2eTest, StartupLineShowsTheEffectiveConfiguration) {
  const std::string config =
      MapFile("pathd.yaml", "max_sessions: 7\nshutdown_grace: 2s\n");
  const std::unique_ptr<e2e::PathdProcess> pathd =
      StartOwnPathd({absl::StrCat("--config=", config), "--shutdown_grace=1s"});
  ASSERT_TRUE(pathd->listening());
  const ProcessResult r = StopOwnPathd(*pathd);
  EXPECT_EQ(r.exit_code, 0) << r;
  const size_t at = r.err.find("pathd starting: ");
  ASSERT_NE(at, std::string::npos) << r;
  const std::string line = r.err.substr(at, r.err.find('\n', at) - at);
  for (const std::string& expected :
       {std::string("max_sessions=7"), std::string("shutdown_grace=1s"),
        std::string("address='127.0.0.1:0'"),
        absl::StrCat("config='", config, "'"), std::string("threads=0"),
        std::string("map_dir=''")}) {
    EXPECT_TRUE(absl::StrContains(line, expected))
        << "missing " << expected << " in\n" << line;
  }
  for (const std::string& flag : HelpFlagNames(RunPathd({"--help"}).out)) {
    EXPECT_TRUE(absl::StrContains(line, absl::StrCat(" ", flag, "=")))
        << "missing --" << flag << " in\n" << line;
  }
}

TEST_F(E2eTest, BadConfigFileExitsTwoNamingFileLineAndKey) {
  struct Case {
    std::string yaml;
    std::string says;  // after "pathd: FILE:"
  };
  const std::vector<Case> cases = {
      {"max_expansions: 10\nthreads: many\n",
       "2: key 'threads': Illegal value 'many' specified for flag 'threads'"},
      {"threads: 2\nworkers: 4\n",
       "2: key 'workers': not a pathd setting; valid keys: address, "},
      {"config: other.yaml\n",
       "1: key 'config': only the command line can name the config file"},
      {"threads: 2\nthreads: 3\n", "2: key 'threads': set twice in this file"},
      {"map_dir: [a, b]\n", "1: key 'map_dir': must be a single value"},
      // Range checks name the file's line too.
      {"threads: 1\nqueue_depth: 0\n", "2: key 'queue_depth': must be >= 1"},
      {"log_level: loud\n", "1: key 'log_level': 'loud' is not one of"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.yaml);
    const std::string config = MapFile("bad.yaml", c.yaml);
    const ProcessResult r =
        RunPathd({"--address=127.0.0.1:0", absl::StrCat("--config=", config)});
    EXPECT_EQ(r.exit_code, 2) << r;
    EXPECT_TRUE(absl::StartsWith(r.err, absl::StrCat("pathd: ", config, ":",
                                                     c.says)))
        << r;
    EXPECT_EQ(r.out, "") << r;
  }
  // A value the command line overrides is not the file's problem.
  const std::string config = MapFile("bad.yaml", "queue_depth: 0\n");
  const ProcessResult overridden =
      RunPathd({"--address=127.0.0.1:0", absl::StrCat("--config=", config),
                "--queue_depth=-1"});
  EXPECT_EQ(overridden.exit_code, 2) << overridden;
  EXPECT_TRUE(absl::StartsWith(overridden.err, "pathd: --queue_depth must be >= 1"))
      << overridden;

  const ProcessResult missing = RunPathd(
      {"--address=127.0.0.1:0", absl::StrCat("--config=", temp_dir_.string(),
                                             "/absent.yaml")});
  EXPECT_EQ(missing.exit_code, 2) << missing;
  EXPECT_TRUE(absl::StrContains(missing.err, "cannot read config file ")) << missing;

  // A stray word (a forgotten "--") is refused rather than ignored.
  const ProcessResult stray = RunPathd({"--address=127.0.0.1:0", "threads=2"});
  EXPECT_EQ(stray.exit_code, 2) << stray;
  EXPECT_TRUE(absl::StrContains(stray.err, "unexpected argument 'threads=2'")) << stray;
}

TEST_F(E2eTest, CheckTellsValidFromInvalidPathsAndExitsFour) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  const v1::PlanResponse plan = PlanJson({"room", "0", "0", "9", "9"});
  ASSERT_TRUE(plan.found());
  std::vector<std::string> check = {"check", "room"};
  for (const v1::Cell& c : plan.path()) {
    check.push_back(absl::StrCat(c.x()));
    check.push_back(absl::StrCat(c.y()));
  }
  const ProcessResult valid = Ctl(check);
  ASSERT_EQ(valid.exit_code, 0) << valid;
  EXPECT_TRUE(absl::StrContains(valid.out, "valid:         yes")) << valid;
  EXPECT_TRUE(absl::StrContains(valid.out, "map version:   1")) << valid;
  EXPECT_TRUE(absl::StrContains(valid.out, "poses:         10")) << valid;

  // Block the fourth pose: the same path is now invalid at version 2.
  const v1::Cell blocked = plan.path(3);
  ASSERT_EQ(Ctl({"maps", "set", "room", absl::StrCat(blocked.x()),
                 absl::StrCat(blocked.y()), "lethal"})
                .exit_code,
            0);
  const ProcessResult invalid = Ctl(check);
  EXPECT_EQ(invalid.exit_code, 4) << invalid;
  EXPECT_TRUE(absl::StrContains(invalid.out, "valid:         no")) << invalid;
  EXPECT_TRUE(absl::StrContains(invalid.out, "map version:   2")) << invalid;
  EXPECT_TRUE(absl::StrContains(invalid.out, "invalid poses: 3\n")) << invalid;
  EXPECT_TRUE(absl::StrContains(invalid.out, "reason:        pose 3 (3, 3) is on a "
                                             "blocked cell (cost 254)"))
      << invalid;

  // The same from a file, as JSON; plus a corner cut around the new
  // obstacle and a jump.
  const std::string file = MapFile("path.txt",
                                   "# x y\n"
                                   "2 2\n3 2\n4 3\n\n4 5\n");
  const ProcessResult json = Ctl({"check", "room", "--path_file", file, "--json"});
  EXPECT_EQ(json.exit_code, 4) << json;
  const auto response = ParseJson<v1::IsPathValidResponse>(json.out);
  EXPECT_FALSE(response.valid());
  EXPECT_EQ(response.invalid_indices_size(), 0);
  ASSERT_EQ(response.invalid_steps_size(), 2);
  EXPECT_EQ(response.invalid_steps(0), 2);
  EXPECT_EQ(response.invalid_steps(1), 3);
  EXPECT_EQ(response.map_version(), 2u);

  // An odd number of coordinates is a usage error.
  EXPECT_EQ(Ctl({"check", "room", "1", "2", "3"}).exit_code, 2);
}

TEST_F(E2eTest, GoalToleranceSubstitutesTheNearestFreeCell) {
  ASSERT_NO_FATAL_FAILURE(CreateMap("room", OpenRoomMap()));
  ASSERT_EQ(Ctl({"maps", "set", "room", "9", "9", "lethal"}).exit_code, 0);
  ExpectRpcError({"plan", "room", "0", "0", "9", "9"}, "INVALID_ARGUMENT",
                 {"goal (9, 9) is on a blocked cell"});
  // (9,8) and (8,9) are both 1 away; the smaller row wins.
  const ProcessResult text =
      Ctl({"plan", "room", "0", "0", "9", "9", "--goal_tolerance_cells", "1.5"});
  ASSERT_EQ(text.exit_code, 0) << text;
  EXPECT_TRUE(absl::StrContains(
      text.out, "goal:        (9,8) (substituted for blocked (9,9))\n"))
      << text;
  const v1::PlanResponse plan = PlanJson(
      {"room", "0", "0", "9", "9", "--goal_tolerance_cells=1.5", "--planner=spm"});
  EXPECT_TRUE(plan.goal_substituted());
  EXPECT_EQ(plan.goal().y(), 8);
  EXPECT_EQ(plan.requested_goal().y(), 9);
  ExpectRpcError({"plan", "room", "0", "0", "9", "9", "--goal_tolerance_cells", "0.5"},
                 "INVALID_ARGUMENT", {"goal tolerance of 0.5 cells"});
}

TEST_F(E2eTest, MetricsCountRequestsAndPathctlPrintsThem) {
  // A daemon of its own, to read its metrics port from its log.
  const std::unique_ptr<e2e::PathdProcess> pathd = StartOwnPathd(
      {"--metrics_address=127.0.0.1:0", "--threads=2", "--log_level=debug"});
  ASSERT_TRUE(pathd->listening());
  constexpr char kMetricsLine[] = "serving Prometheus metrics on http://";
  const std::string metrics_line = pathd->WaitForLogLine({kMetricsLine});
  ASSERT_NE(metrics_line, "") << pathd->Log();
  const size_t at = metrics_line.find(kMetricsLine) + strlen(kMetricsLine);
  const std::string metrics_address =
      metrics_line.substr(at, metrics_line.find("/metrics", at) - at);
  const std::string server = absl::StrCat("--server=", pathd->address());
  const std::string metrics_flag = absl::StrCat("--metrics_address=", metrics_address);

  ASSERT_EQ(RunPathctl({server, "maps", "create", "room", "--from",
                        MapFile("room.map", OpenRoomMap())})
                .exit_code,
            0);
  ASSERT_EQ(RunPathctl({server, "plan", "room", "0", "0", "9", "9"}).exit_code, 0);
  ASSERT_EQ(RunPathctl({server, "plan", "room", "0", "0", "9", "9", "--planner=jps"})
                .exit_code,
            0);
  EXPECT_EQ(RunPathctl({server, "plan", "nowhere", "0", "0", "9", "9"}).exit_code, 7);

  const ProcessResult filtered = RunPathctl(
      {"metrics", metrics_flag, "pathd_requests_total", "pathd_maps"});
  ASSERT_EQ(filtered.exit_code, 0) << filtered;
  for (const char* line : {R"(pathd_requests_total{code="OK",rpc="CreateMap"} 1)",
                           R"(pathd_requests_total{code="OK",rpc="Plan"} 2)",
                           R"(pathd_requests_total{code="NOT_FOUND",rpc="Plan"} 1)",
                           "# TYPE pathd_maps gauge", "pathd_maps 1"}) {
    EXPECT_TRUE(absl::StrContains(filtered.out, absl::StrCat(line, "\n")))
        << "missing " << line << "\n" << filtered;
  }
  // Only the asked-for names.
  EXPECT_FALSE(absl::StrContains(filtered.out, "pathd_cache")) << filtered;

  const ProcessResult all = RunPathctl({"metrics", metrics_flag});
  ASSERT_EQ(all.exit_code, 0) << all;
  for (const char* line :
       {"# TYPE pathd_plan_duration_seconds histogram",
        R"(pathd_plan_duration_seconds_count{planner="jps"} 1)",
        R"(pathd_request_duration_seconds_count{rpc="Plan"} 3)",
        R"(pathd_map_version{map="room"} 1)", "pathd_worker_threads 2"}) {
    EXPECT_TRUE(absl::StrContains(all.out, absl::StrCat(line, "\n")))
        << "missing " << line << "\n" << all;
  }

  const ProcessResult daemon = StopOwnPathd(*pathd);
  EXPECT_EQ(daemon.exit_code, 0) << daemon;
  // The debug request log has one line per request, with its planner.
  EXPECT_TRUE(absl::StrContains(
      daemon.err, "rpc=Plan map=room planner=jps outcome=FOUND status=OK us="))
      << daemon;

  // Nobody serves the endpoint any more.
  const ProcessResult gone = RunPathctl({"metrics", metrics_flag, "--timeout=5s"});
  EXPECT_EQ(gone.exit_code, 5) << gone;
  EXPECT_TRUE(absl::StartsWith(gone.err, "error: UNAVAILABLE: cannot fetch")) << gone;
}

TEST_F(E2eTest, PlanProgressStreamsProgressLinesThenTheSamePlan) {
  EXPECT_EQ(StopDaemon(), 0);
  ASSERT_NO_FATAL_FAILURE(StartDaemon({"--progress_interval=1ms"}));
  // Dijkstra on an open 512 x 512 room: about 260 000 expansions, over 250
  // stop-condition polls, so the 1 ms interval passes many times.
  ASSERT_NO_FATAL_FAILURE(CreateMap("big", OpenRoomMap(512, 512)));
  const std::vector<std::string> plan = {"plan", "big", "0", "0", "511", "300",
                                         "--planner=dijkstra"};
  std::vector<std::string> with_progress = plan;
  with_progress.push_back("--progress");
  const ProcessResult streamed = Ctl(with_progress);
  ASSERT_EQ(streamed.exit_code, 0) << streamed;
  // stderr is a pipe here, not a terminal: one line per event.
  const std::vector<std::string> lines =
      absl::StrSplit(streamed.err, '\n', absl::SkipEmpty());
  ASSERT_FALSE(lines.empty()) << streamed;
  for (const std::string& line : lines) {
    EXPECT_TRUE(absl::StartsWith(line, "progress: ")) << line;
    EXPECT_TRUE(absl::StrContains(line, " expansions, best f ")) << line;
  }
  const ProcessResult unary = Ctl(plan);
  ASSERT_EQ(unary.exit_code, 0) << unary;
  EXPECT_EQ(unary.err, "");
  // The same answer, line for line, except the planning time.
  const auto without_time = [](const std::string& out) {
    std::vector<std::string> kept;
    for (absl::string_view line : absl::StrSplit(out, '\n')) {
      if (!absl::StartsWith(line, "time:")) kept.emplace_back(line);
    }
    return kept;
  };
  EXPECT_EQ(without_time(streamed.out), without_time(unary.out));

  ExpectRpcError({"plan", "big", "0", "0", "600", "0", "--progress"},
                 "INVALID_ARGUMENT",
                 {"goal (600, 0) is outside", "(outcome GOAL_OUTSIDE_MAP)"});
}

}  // namespace pathd::e2e_test
