// Bad input through the real pathd binary: a table of malformed requests to
// every RPC of MapService, PlannerService and Health (bad names, dimensions,
// cell arrays, coordinates, non-finite numbers, unknown enum values, empty
// batches, oversized messages, map file garbage, --map_dir escapes), each
// expecting a status code and a message naming the problem. After every case
// a good request must still succeed, and the daemon must be alive at the end;
// map files are also tried at start-up and through bad --map_dir flags. The
// test prints how many cases it tried.
#include "tests/e2e/bad_input_fixture.h"

namespace pathd::bad_input_test {

void BadInputTest::AddNameCases(std::vector<Case>& cases) {
  const std::string huge_name(size_t{1} << 20, 'm');
  const std::string nul_name("ro\0om", 5);
  // Bad names, tried on every RPC that takes one.
  struct Name {
    std::string what;
    std::string name;
    StatusCode code;
    std::string message;
  };
  const std::vector<Name> names = {
      {"empty name", "", StatusCode::INVALID_ARGUMENT, "map name is empty"},
      {"1 MiB name", huge_name, StatusCode::INVALID_ARGUMENT,
       "map name is 1048576 characters long; the limit is 128"},
      {"name with '/'", "maps/room", StatusCode::INVALID_ARGUMENT,
       "character 0x2f"},
      {"name '..'", "..", StatusCode::INVALID_ARGUMENT,
       "must not start with '.'"},
      {"name '../room'", "../room", StatusCode::INVALID_ARGUMENT,
       "must not start with '.'"},
      {"name with NUL", nul_name, StatusCode::INVALID_ARGUMENT,
       "character 0x00"},
      {"unknown name", "nosuchmap", StatusCode::NOT_FOUND,
       "map 'nosuchmap' not found"},
  };
  for (const Name& n : names) {
    const std::string name = n.name;
    const auto add = [&](const std::string& rpc,
                         std::function<grpc::Status()> call) {
      cases.push_back({rpc, n.what, std::move(call), n.code, n.message});
    };
    if (n.code != StatusCode::NOT_FOUND) {
      add("CreateMap", [=, this] { return CreateMap(RawMap(name, 2, 2, 4)); });
    }
    add("GetMap", [=, this] { return GetMap(name); });
    add("DeleteMap", [=, this] { return DeleteMap(name); });
    add("UpdateMap", [=, this] {
      v1::UpdateMapRequest request;
      request.set_name(name);
      v1::CellChange* change = request.add_changes();
      *change->mutable_cell() = CellPos(0, 0).cell();
      return UpdateMap(request);
    });
    add("WatchMap", [=, this] { return WatchMap(name); });
    v1::PlanRequest plan = GoodPlan();
    plan.set_map(name);
    add("Plan", [=, this] { return Plan(plan); });
    add("PlanStream", [=, this] { return PlanStream(plan); });
    add("PlanBatch", [=, this] { return PlanBatchItem(plan); });
    add("Navigate", [=, this] { return Navigate({NavigateOpen(plan)}); });
    add("IsPathValid", [=, this] {
      v1::IsPathValidRequest request = PathCheck({CellPos(1, 1)});
      request.set_map(name);
      return IsPathValid(request);
    });
    add("CostToGo", [=, this] { return CostToGo(Field(name)); });
  }

  // Non-UTF-8 bytes in a `string` field: the request does not parse. gRPC's
  // own answer would be UNIMPLEMENTED with no message.
  {
    const auto raw = [&](const std::string& rpc, const std::string& method,
                         const google::protobuf::Message& request,
                         StatusCode code = StatusCode::INVALID_ARGUMENT,
                         const std::string& message =
                             "does not parse as its protobuf") {
      const grpc::ByteBuffer bytes = WithNonUtf8(request);
      cases.push_back({rpc, "non-UTF-8 name",
                       [=, this] { return Raw(method, bytes); }, code,
                       message});
    };
    v1::CreateMapRequest create = RawMap(kUtf8Marker, 2, 2, 4);
    raw("CreateMap", "/pathd.v1.MapService/CreateMap", create);
    v1::GetMapRequest get;
    get.set_name(kUtf8Marker);
    raw("GetMap", "/pathd.v1.MapService/GetMap", get);
    v1::DeleteMapRequest del;
    del.set_name(kUtf8Marker);
    raw("DeleteMap", "/pathd.v1.MapService/DeleteMap", del);
    v1::UpdateMapRequest update;
    update.set_name(kUtf8Marker);
    raw("UpdateMap", "/pathd.v1.MapService/UpdateMap", update);
    v1::WatchMapRequest watch;
    watch.set_name(kUtf8Marker);
    raw("WatchMap", "/pathd.v1.MapService/WatchMap", watch);
    v1::PlanRequest plan = GoodPlan();
    plan.set_map(kUtf8Marker);
    raw("Plan", "/pathd.v1.PlannerService/Plan", plan);
    raw("PlanStream", "/pathd.v1.PlannerService/PlanStream", plan);
    v1::PlanBatchRequest item;
    item.set_request_id(kUtf8Marker);
    *item.mutable_request() = GoodPlan();
    // On a bidi stream gRPC hands the handler a message that does not parse
    // as the end of the client's stream, with nothing to tell the two apart:
    // the stream ends OK with nothing answered (docs/decisions.md).
    raw("PlanBatch", "/pathd.v1.PlannerService/PlanBatch", item, StatusCode::OK,
        "");
    v1::NavigateRequest open = NavigateOpen(plan);
    raw("Navigate", "/pathd.v1.PlannerService/Navigate", open, StatusCode::OK,
        "");
    v1::IsPathValidRequest check = PathCheck({CellPos(1, 1)});
    check.set_map(kUtf8Marker);
    raw("IsPathValid", "/pathd.v1.PlannerService/IsPathValid", check);
    v1::CostToGoRequest field = Field(kUtf8Marker);
    raw("CostToGo", "/pathd.v1.PlannerService/CostToGo", field);
    grpc::health::v1::HealthCheckRequest health;
    health.set_service(kUtf8Marker);
    // gRPC's own health service parses its requests itself.
    raw("Health.Check", "/grpc.health.v1.Health/Check", health,
        StatusCode::INVALID_ARGUMENT, "could not parse request");
  }
  // Bytes that are no protobuf message at all (a truncated field).
  {
    grpc::Slice slice(std::string("\x0a\xff\xff\xff\x0f", 5));
    const grpc::ByteBuffer junk(&slice, 1);
    for (const std::string method :
         {"/pathd.v1.MapService/ListMaps",
          "/pathd.v1.PlannerService/GetCacheStats",
          "/pathd.v1.MapService/GetMap", "/pathd.v1.MapService/WatchMap",
          "/pathd.v1.MapService/DownloadMap"}) {
      cases.push_back(
          {method, "unparsable bytes", [=, this] { return Raw(method, junk); },
           StatusCode::INVALID_ARGUMENT,
           absl::StrCat("the request to ", method, " does not parse")});
    }
    const std::string health = "/grpc.health.v1.Health/Check";
    cases.push_back({health, "unparsable bytes",
                     [=, this] { return Raw(health, junk); },
                     StatusCode::INVALID_ARGUMENT, "could not parse request"});
  }
}

TEST_F(BadInputTest, EveryRpcAnswersBadInputAndKeepsServing) {
  ASSERT_NO_FATAL_FAILURE(StartDaemon());

  // ---- start-up: every bad --map_dir file is skipped with a reason ----
  {
    const std::string log = daemon_->Log();
    for (const File& f : bad_files_) {
      const std::string prefix =
          absl::StrCat("skipping map file ", f.name, ": ");
      const size_t at = log.find(prefix);
      EXPECT_NE(at, std::string::npos) << f.name << "\n" << log;
      if (at == std::string::npos) continue;
      const std::string line = log.substr(at, log.find('\n', at) - at);
      EXPECT_THAT(line, HasSubstr(f.complaint)) << f.name;
      ++tried_;
    }
    v1::ListMapsResponse list;
    ASSERT_TRUE(
        map_->ListMaps(Context().get(), v1::ListMapsRequest(), &list).ok());
    std::set<std::string> names;
    for (const v1::MapInfo& info : list.maps()) names.insert(info.name());
    EXPECT_EQ(names, (std::set<std::string>{"big", "room"}));
  }


  std::vector<Case> cases;
  AddNameCases(cases);
  AddMapCases(cases);
  AddPlannerCases(cases);
  AddFleetCases(cases);
  AddControlCases(cases);

  ASSERT_NO_FATAL_FAILURE(Run(cases));

  // The maps the good requests use were never changed by a bad one.
  v1::GetMapRequest get;
  get.set_name("room");
  v1::GetMapResponse room;
  ASSERT_TRUE(map_->GetMap(Context().get(), get, &room).ok());
  EXPECT_EQ(room.info().version(), 1u);
  EXPECT_TRUE(daemon_->Running());

  // The request log quotes bad names escaped and cut short: one line each,
  // none holding the 1 MiB name.
  const std::string log = daemon_->Log();
  std::istringstream lines(log);
  for (std::string line; std::getline(lines, line);) {
    EXPECT_LE(line.size(), 2048u) << line.substr(0, 200);
  }
  EXPECT_THAT(log, HasSubstr("rpc=GetMap map=ro\\x00om "));
  EXPECT_THAT(log, HasSubstr("(1048576 bytes)"));
  EXPECT_THAT(
      log,
      HasSubstr(
          "rpc=ListMaps map=- unparsable request status=INVALID_ARGUMENT"));
  std::printf("bad_input_test: tried %d bad-input cases; pathd kept serving\n",
              tried_);
}

// --map_dir itself is bad: the daemon refuses to start and says why.
TEST_F(BadInputTest, BadMapDirFlagStopsStartUp) {
  WriteFile(temp_ / "plain_file", "x");
  const std::vector<std::pair<std::string, std::string>> dirs = {
      {(temp_ / "plain_file").string(), "is not a directory"},
      {(temp_ / "missing").string(), "does not exist"},
  };
  for (const auto& [dir, message] : dirs) {
    const std::unique_ptr<e2e::PathdProcess> daemon =
        StartPathd(temp_ / "refused.log", {"--map_dir=" + dir});
    EXPECT_TRUE(daemon->address().empty());
    EXPECT_NE(daemon->WaitForExit(), 0);
    EXPECT_THAT(daemon->Log(), HasSubstr(message)) << dir;
  }
  std::printf("bad_input_test: %zu bad --map_dir flags refused\n", dirs.size());
}

}  // namespace pathd::bad_input_test
