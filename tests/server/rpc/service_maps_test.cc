// service_test: Health, start-up from --map_dir, and MapService: create from
// raw cells, Moving AI text, ROS maps and --map_dir files, get, list, delete
// and update.
#include "tests/server/rpc/service_fixture.h"

#include "absl/time/clock.h"
#include "absl/time/time.h"

namespace pathd::server::service_test {

testing::TempDir* ServiceTest::scratch_ = nullptr;
const std::shared_ptr<grpc::Channel>* ServiceTest::channel_ = nullptr;
const fs::path* ServiceTest::root_ = nullptr;

TEST_F(ServiceTest, HealthServiceReportsServing) {
  // grpc.health.v1.Health/Check with an empty request (service ""); the reply
  // HealthCheckResponse{status: SERVING} encodes as field 1 varint 1.
  grpc::GenericStub stub(*channel_);
  grpc::Slice empty("");
  grpc::ByteBuffer request(&empty, 1);
  grpc::ByteBuffer response;
  grpc::ClientContext context;
  Prepare(context);
  std::promise<grpc::Status> done;
  stub.UnaryCall(&context, "/grpc.health.v1.Health/Check", grpc::StubOptions(),
                 &request, &response,
                 [&done](grpc::Status s) { done.set_value(std::move(s)); });
  const grpc::Status status = done.get_future().get();
  ASSERT_TRUE(status.ok()) << status.error_message();
  std::vector<grpc::Slice> slices;
  ASSERT_TRUE(response.Dump(&slices).ok());
  std::string bytes;
  for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  EXPECT_EQ(bytes, std::string("\x08\x01", 2));
}

TEST_F(ServiceTest, StartUpLoadsMapDirAndSkipsBadFiles) {
  v1::ListMapsResponse list;
  grpc::ClientContext context;
  Prepare(context);
  ASSERT_TRUE(maps_->ListMaps(&context, v1::ListMapsRequest(), &list).ok());
  std::vector<std::string> names;
  for (const auto& info : list.maps()) names.push_back(info.name());
  EXPECT_THAT(names, ::testing::IsSupersetOf({"room", "small"}));
  // broken.map does not parse, link_out.map and sneaky.yaml escape the dir.
  EXPECT_THAT(names, ::testing::Not(::testing::Contains("broken")));
  EXPECT_THAT(names, ::testing::Not(::testing::Contains("link_out")));
  EXPECT_THAT(names, ::testing::Not(::testing::Contains("sneaky")));
}

TEST_F(ServiceTest, CreateFromRawGetListDelete) {
  v1::CreateMapResponse created;
  std::string cells(12, '\0');
  cells[5] = static_cast<char>(254);
  ASSERT_TRUE(CreateRaw("raw-a", 4, 3, cells, &created, 0.25).ok());
  EXPECT_EQ(created.info().name(), "raw-a");
  EXPECT_EQ(created.info().version(), 1u);
  EXPECT_EQ(created.info().width(), 4);
  EXPECT_EQ(created.info().height(), 3);
  EXPECT_DOUBLE_EQ(created.info().resolution(), 0.25);
  EXPECT_EQ(created.info().free_cells(), 11);
  EXPECT_EQ(created.info().blocked_cells(), 1);

  v1::CreateMapResponse dup;
  EXPECT_EQ(CreateRaw("raw-a", 4, 3, cells, &dup).error_code(),
            grpc::StatusCode::ALREADY_EXISTS);

  {
    v1::GetMapRequest request;
    request.set_name("raw-a");
    v1::GetMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->GetMap(&context, request, &response).ok());
    EXPECT_EQ(response.info().version(), 1u);
    EXPECT_TRUE(response.cells().empty());
  }
  {
    v1::GetMapRequest request;
    request.set_name("raw-a");
    request.set_include_cells(true);
    v1::GetMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->GetMap(&context, request, &response).ok());
    EXPECT_EQ(response.cells(), cells);
  }
  {
    ASSERT_TRUE(CreateFree("raw-0", 2, 2).ok());
    v1::ListMapsResponse list;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->ListMaps(&context, v1::ListMapsRequest(), &list).ok());
    std::vector<std::string> names;
    for (const auto& info : list.maps()) names.push_back(info.name());
    EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
    EXPECT_THAT(names, ::testing::IsSupersetOf({"raw-0", "raw-a"}));
  }
  {
    v1::DeleteMapRequest request;
    request.set_name("raw-a");
    v1::DeleteMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    ASSERT_TRUE(maps_->DeleteMap(&context, request, &response).ok());
    EXPECT_EQ(response.last_version(), 1u);
  }
  {
    v1::GetMapRequest request;
    request.set_name("raw-a");
    v1::GetMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = maps_->GetMap(&context, request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
    EXPECT_EQ(status.error_message(), "map 'raw-a' not found");
  }
}

TEST_F(ServiceTest, CreateRejectsBadInput) {
  v1::CreateMapResponse response;
  const grpc::Status bad_name = CreateRaw("no/slash", 1, 1, std::string(1, '\0'), &response);
  EXPECT_EQ(bad_name.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad_name.error_message(), HasSubstr("map name"));

  const grpc::Status short_cells = CreateRaw("short", 3, 3, std::string(8, '\0'), &response);
  EXPECT_EQ(short_cells.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(short_cells.error_message(), HasSubstr("needs 9 cells, got 8"));

  const grpc::Status too_big =
      CreateRaw("huge", 300, 300, std::string(90000, '\0'), &response);
  EXPECT_EQ(too_big.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(too_big.error_message(), HasSubstr("max_map_cells"));

  const grpc::Status bad_resolution =
      CreateRaw("res", 1, 1, std::string(1, '\0'), &response, -1.0);
  EXPECT_EQ(bad_resolution.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad_resolution.error_message(), HasSubstr("resolution"));

  v1::CreateMapRequest no_source;
  no_source.set_name("nosrc");
  grpc::ClientContext context;
  Prepare(context);
  EXPECT_EQ(maps_->CreateMap(&context, no_source, &response).error_code(),
            grpc::StatusCode::INVALID_ARGUMENT);
}

TEST_F(ServiceTest, CreateFromMovingAiText) {
  v1::CreateMapRequest request;
  request.set_name("mai");
  request.set_movingai_text(kSmallMovingAi);
  request.set_resolution(2.0);
  request.mutable_origin()->set_x(10.0);
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = maps_->CreateMap(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.info().width(), 5);
  EXPECT_EQ(response.info().height(), 4);
  EXPECT_EQ(response.info().blocked_cells(), 4);
  EXPECT_DOUBLE_EQ(response.info().resolution(), 2.0);
  EXPECT_DOUBLE_EQ(response.info().origin().x(), 10.0);

  v1::CreateMapRequest broken;
  broken.set_name("mai-broken");
  broken.set_movingai_text("type octile\nwidth 3\nheight 3\nmap\n...\n");
  grpc::ClientContext context2;
  Prepare(context2);
  const grpc::Status bad = maps_->CreateMap(&context2, broken, &response);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(bad.error_message(), HasSubstr("movingai_text"));
}

TEST_F(ServiceTest, CreateFromRosMap) {
  v1::CreateMapRequest request;
  request.set_name("ros");
  request.mutable_ros_map()->set_yaml(kRosYaml);
  request.mutable_ros_map()->set_image(kRosPgm);
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = maps_->CreateMap(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.info().width(), 3);
  EXPECT_EQ(response.info().height(), 2);
  EXPECT_DOUBLE_EQ(response.info().resolution(), 0.5);
  EXPECT_DOUBLE_EQ(response.info().origin().x(), 1.0);
  EXPECT_DOUBLE_EQ(response.info().origin().y(), -2.0);
  EXPECT_EQ(response.info().blocked_cells(), 1);

  v1::GetMapRequest get;
  get.set_name("ros");
  get.set_include_cells(true);
  v1::GetMapResponse map;
  grpc::ClientContext context2;
  Prepare(context2);
  ASSERT_TRUE(maps_->GetMap(&context2, get, &map).ok());
  // Image top row is grid row 1 (OccupancyGrid order): its middle is lethal.
  ASSERT_EQ(map.cells().size(), 6u);
  EXPECT_EQ(static_cast<uint8_t>(map.cells()[4]), kLethalCost);
  EXPECT_EQ(static_cast<uint8_t>(map.cells()[1]), kFreeCost);
}

TEST_F(ServiceTest, CreateFromMapDirFile) {
  v1::CreateMapRequest request;
  request.set_name("from-dir");
  request.set_map_dir_file("sub/inner.map");
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = maps_->CreateMap(&context, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(response.info().width(), 5);

  // ".." that stays inside the directory is fine.
  request.set_name("from-dir-2");
  request.set_map_dir_file("sub/../room.yaml");
  grpc::ClientContext context2;
  Prepare(context2);
  const grpc::Status inside = maps_->CreateMap(&context2, request, &response);
  ASSERT_TRUE(inside.ok()) << inside.error_message();
  EXPECT_DOUBLE_EQ(response.info().resolution(), 0.5);
}

TEST_F(ServiceTest, MapDirFileCannotEscapeTheDirectory) {
  const std::string secret = (*root_ / "secret.map").string();
  for (const std::string& file :
       {std::string("../secret.map"), std::string("sub/../../secret.map"), secret,
        std::string("link_out.map"), std::string("sneaky.yaml"), std::string("..")}) {
    v1::CreateMapRequest request;
    request.set_name("escape");
    request.set_map_dir_file(file);
    v1::CreateMapResponse response;
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = maps_->CreateMap(&context, request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT)
        << file << ": " << status.error_message();
  }
  v1::CreateMapRequest missing;
  missing.set_name("missing");
  missing.set_map_dir_file("nope.map");
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  const grpc::Status status = maps_->CreateMap(&context, missing, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_THAT(status.error_message(), HasSubstr("nope.map"));
}

TEST_F(ServiceTest, MapDirFileWithoutMapDirIsFailedPrecondition) {
  ServerOptions options = testing::TestServerOptions();
  options.threads = 1;
  testing::InProcessServer bare(options);
  ASSERT_TRUE(bare.Start().ok());
  v1::MapService::Stub* stub = &bare.maps();
  v1::CreateMapRequest request;
  request.set_name("x");
  request.set_map_dir_file("small.map");
  v1::CreateMapResponse response;
  grpc::ClientContext context;
  Prepare(context);
  EXPECT_EQ(stub->CreateMap(&context, request, &response).error_code(),
            grpc::StatusCode::FAILED_PRECONDITION);
}

TEST_F(ServiceTest, UpdateBumpsVersionAndRejectsStaleExpectedVersion) {
  ASSERT_TRUE(CreateFree("upd", 8, 8).ok());
  v1::UpdateMapRequest request;
  request.set_name("upd");
  auto* change = request.add_changes();
  change->mutable_rect()->set_x_min(2);
  change->mutable_rect()->set_y_min(0);
  change->mutable_rect()->set_x_max(2);
  change->mutable_rect()->set_y_max(6);
  change->set_cost(254);
  request.set_expected_version(1);
  v1::UpdateMapResponse response;
  {
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = maps_->UpdateMap(&context, request, &response);
    ASSERT_TRUE(status.ok()) << status.error_message();
    EXPECT_EQ(response.version(), 2u);
    EXPECT_EQ(response.cells_changed(), 7);
  }
  {
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status stale = maps_->UpdateMap(&context, request, &response);
    EXPECT_EQ(stale.error_code(), grpc::StatusCode::ABORTED);
    EXPECT_EQ(stale.error_message(), "map 'upd' is at version 2, expected 1");
  }
  {
    v1::UpdateMapRequest off = request;
    off.clear_expected_version();
    off.add_changes()->mutable_cell()->set_x(8);
    grpc::ClientContext context;
    Prepare(context);
    const grpc::Status status = maps_->UpdateMap(&context, off, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_THAT(status.error_message(), HasSubstr("change 1"));
  }
  {
    v1::UpdateMapRequest empty;
    empty.set_name("upd");
    grpc::ClientContext context;
    Prepare(context);
    EXPECT_EQ(maps_->UpdateMap(&context, empty, &response).error_code(),
              grpc::StatusCode::INVALID_ARGUMENT);
  }
  {
    v1::UpdateMapRequest unknown = request;
    unknown.set_name("nope");
    grpc::ClientContext context;
    Prepare(context);
    EXPECT_EQ(maps_->UpdateMap(&context, unknown, &response).error_code(),
              grpc::StatusCode::NOT_FOUND);
  }
}

// UploadMap's budget: the uploads in progress hold at most --max_map_cells
// (65536 here) together, reserved at the header; a finished or cancelled
// upload gives its cells back. DownloadMap sends what UploadMap took.
TEST_F(ServiceTest, UploadsInProgressShareOneBudget) {
  const auto header = [](const std::string& name, int32_t w, int32_t h) {
    v1::UploadMapRequest m;
    m.mutable_header()->set_name(name);
    m.mutable_header()->set_width(w);
    m.mutable_header()->set_height(h);
    return m;
  };
  const auto band = [](int32_t first_row, const std::string& cells) {
    v1::UploadMapRequest m;
    m.mutable_band()->set_first_row(first_row);
    m.mutable_band()->set_cells(cells);
    return m;
  };
  // Upload "a" (200 x 300 = 60000 cells): the header and its first 100 rows.
  std::string cells(200 * 300, '\0');
  for (size_t i = 0; i < cells.size(); i += 13) cells[i] = static_cast<char>(i % 255);
  grpc::ClientContext a_context;
  Prepare(a_context);
  v1::CreateMapResponse a_response;
  auto a = maps_->UploadMap(&a_context, &a_response);
  ASSERT_TRUE(a->Write(header("up-a", 200, 300)));
  ASSERT_TRUE(a->Write(band(0, cells.substr(0, 200 * 100))));

  // "b" (100 x 100) would take the uploads past 65536 cells: refused at its
  // header. Once "a" is done, the same upload goes through.
  const auto upload_b = [&] {
    grpc::ClientContext context;
    Prepare(context);
    v1::CreateMapResponse response;
    auto b = maps_->UploadMap(&context, &response);
    if (b->Write(header("up-b", 100, 100)) && b->Write(band(0, std::string(10000, '\0')))) {
      b->WritesDone();
    }
    return b->Finish();
  };
  // The server reserves "a"'s cells when it reads a's header, which a
  // returned Write does not promise: a "b" that raced ahead of it went
  // through, and is deleted and tried again (polled; a hang guard bounds it).
  const auto delete_b = [&] {
    v1::DeleteMapRequest del;
    del.set_name("up-b");
    v1::DeleteMapResponse deleted;
    grpc::ClientContext context;
    Prepare(context);
    return maps_->DeleteMap(&context, del, &deleted);
  };
  grpc::Status refused = upload_b();
  for (int attempt = 0; attempt < 500 && refused.ok(); ++attempt) {
    ASSERT_TRUE(delete_b().ok());
    absl::SleepFor(absl::Milliseconds(10));
    refused = upload_b();
  }
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_THAT(refused.error_message(),
              HasSubstr("uploads in progress hold 60000 cells; this upload's 10000 would "
                        "pass the server's limit of 65536 cells (--max_map_cells)"));

  ASSERT_TRUE(a->Write(band(100, cells.substr(200 * 100))));
  ASSERT_TRUE(a->WritesDone());
  const grpc::Status a_status = a->Finish();
  ASSERT_TRUE(a_status.ok()) << a_status.error_message();
  EXPECT_EQ(a_response.info().width(), 200);
  EXPECT_EQ(a_response.info().version(), 1u);
  const grpc::Status b_status = upload_b();
  ASSERT_TRUE(b_status.ok()) << b_status.error_message();

  // A cancelled upload creates nothing and gives its cells back (polled: the
  // server sees the cancellation after the client returns; a hang guard).
  {
    grpc::ClientContext context;
    Prepare(context);
    v1::CreateMapResponse response;
    auto c = maps_->UploadMap(&context, &response);
    ASSERT_TRUE(c->Write(header("up-c", 200, 300)));
    ASSERT_TRUE(c->Write(band(0, cells.substr(0, 200 * 10))));
    context.TryCancel();
    EXPECT_EQ(c->Finish().error_code(), grpc::StatusCode::CANCELLED);
  }
  grpc::Status again;
  for (const absl::Time guard = absl::Now() + absl::Seconds(30); absl::Now() < guard;
       absl::SleepFor(absl::Milliseconds(10))) {
    delete_b();
    if ((again = upload_b()).ok()) break;
  }
  EXPECT_TRUE(again.ok()) << again.error_message();
  v1::GetMapRequest get;
  get.set_name("up-c");
  v1::GetMapResponse got;
  grpc::ClientContext get_context;
  Prepare(get_context);
  EXPECT_EQ(maps_->GetMap(&get_context, get, &got).error_code(), grpc::StatusCode::NOT_FOUND);

  // DownloadMap: the metadata, then bands that tile the map.
  grpc::ClientContext d_context;
  Prepare(d_context);
  v1::DownloadMapRequest request;
  request.set_name("up-a");
  auto d = maps_->DownloadMap(&d_context, request);
  v1::DownloadMapResponse message;
  ASSERT_TRUE(d->Read(&message));
  ASSERT_TRUE(message.has_info());
  EXPECT_EQ(message.info().height(), 300);
  std::string back;
  while (d->Read(&message)) {
    ASSERT_TRUE(message.has_band());
    EXPECT_EQ(int64_t{message.band().first_row()} * 200, static_cast<int64_t>(back.size()));
    back += message.band().cells();
  }
  ASSERT_TRUE(d->Finish().ok());
  EXPECT_EQ(back, cells);
}

}  // namespace pathd::server::service_test
