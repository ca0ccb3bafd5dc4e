// PlanOptions.path_encoding over a real gRPC channel to a PathdServer on
// 127.0.0.1:0 (issue 19): for grid, any-angle, simplified, partial and
// empty paths, PACKED decodes to exactly the path and world points READABLE
// answers, BOTH carries both, UNSPECIFIED the readable form alone; the same
// through PlanStream, PlanBatch and Navigate; and the C++ client, which
// asks for PACKED, hands back what READABLE answers.
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "client/client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "proto/path_codec.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"
#include "tests/testing/requests.h"
#include "tests/testing/shared_server_test.h"

namespace pathd::server {
namespace {

using testing::CellPos;
using testing::Context;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

// Rooms joined by gaps, and a walled-in pocket around (34, 2).
const std::vector<std::string> kRows = {
    "..........#..............#####..", "..........#...#####......#...#..",
    "..........#...#...#......#...#..", ".....###..#...#####......#####..",
    "................................", "..........#..........#..........",
    "..........#..........#..........", "...####...#######....#....####..",
    "..........#..........#..........", "..........#.....................",
};

class PackedPathTest : public testing::SharedServerTest<PackedPathTest> {
 public:
  static ServerOptions SuiteOptions() { return testing::TestServerOptions(); }

 protected:
  static void SetUpTestSuite() {
    testing::SharedServerTest<PackedPathTest>::SetUpTestSuite();
    // A resolution and an origin that make world points unlike cells.
    v1::CreateMapRequest create;
    create.set_name("rooms");
    create.mutable_raw()->set_width(static_cast<int>(kRows[0].size()));
    create.mutable_raw()->set_height(static_cast<int>(kRows.size()));
    create.mutable_raw()->set_cells(testing::CellsFromRows(kRows));
    create.set_resolution(0.05);
    create.mutable_origin()->set_x(-12.3);
    create.mutable_origin()->set_y(4.56);
    const grpc::Status s = server_->CreateMap(create);
    ASSERT_TRUE(s.ok()) << s.error_message();
  }

  static v1::PlanRequest Request(v1::Planner planner, v1::Position start,
                                 v1::Position goal, v1::PathEncoding encoding) {
    v1::PlanRequest request;
    request.set_map("rooms");
    request.set_planner(planner);
    *request.mutable_start() = start;
    *request.mutable_goal() = goal;
    request.mutable_options()->set_path_encoding(encoding);
    return request;
  }

  static v1::PlanResponse Plan(const v1::PlanRequest& request) {
    v1::PlanResponse response;
    const grpc::Status s =
        server_->planner().Plan(Context().get(), request, &response);
    EXPECT_TRUE(s.ok()) << s.error_message();
    return response;
  }

  // The cases: a request each (encoding left to the caller).
  static std::vector<v1::PlanRequest> Cases() {
    const v1::Position a = CellPos(0, 0);
    const v1::Position b = CellPos(31, 9);
    std::vector<v1::PlanRequest> cases = {
        Request(v1::PLANNER_ASTAR, a, b, {}),
        Request(v1::PLANNER_JPS, a, b, {}),
        Request(v1::PLANNER_THETA_STAR, a, b, {}),
        Request(v1::PLANNER_ASTAR, CellPos(31, 0), CellPos(0, 9), {}),
        // One cell.
        Request(v1::PLANNER_ASTAR, CellPos(5, 5), CellPos(5, 5), {}),
        // No path: into the pocket.
        Request(v1::PLANNER_ASTAR, a, CellPos(27, 2), {}),
    };
    v1::PlanRequest four = Request(v1::PLANNER_ASTAR, a, b, {});
    four.mutable_options()->set_connectivity(v1::CONNECTIVITY_FOUR);
    cases.push_back(four);
    v1::PlanRequest simplified = Request(v1::PLANNER_ASTAR, b, a, {});
    simplified.mutable_options()->set_simplify(true);
    cases.push_back(simplified);
    // A partial path: the via point is reached, the goal (in the pocket) not.
    v1::PlanRequest partial = Request(v1::PLANNER_ASTAR, a, CellPos(27, 2), {});
    *partial.add_via() = CellPos(20, 9);
    partial.set_allow_partial(true);
    cases.push_back(partial);
    return cases;
  }
};

// The readable path of `packed` (a PACKED answer) equals `readable`'s,
// world points bit for bit; everything else in the two answers agrees too.
void ExpectSamePath(v1::PlanResponse packed, v1::PlanResponse readable) {
  EXPECT_THAT(packed.path(), IsEmpty());
  EXPECT_THAT(packed.world_path(), IsEmpty());
  EXPECT_EQ(packed.has_path_frame(), !packed.packed_path().empty());
  ASSERT_TRUE(UnpackPlanPath(&packed).ok());
  packed.clear_planning_time_us();
  readable.clear_planning_time_us();
  EXPECT_EQ(packed.SerializeAsString(), readable.SerializeAsString())
      << packed.DebugString() << "\nvs\n"
      << readable.DebugString();
}

// The final plan of a PlanStream call, read to its end; the call's status.
template <typename Reader>
grpc::Status StreamedPlan(Reader& reader, v1::PlanResponse* plan) {
  v1::PlanStreamEvent event;
  while (reader.Read(&event)) {
    if (event.has_result()) *plan = event.result();
  }
  return reader.Finish();
}

// One item sent on a PlanBatch stream and its answer; the stream's status.
template <typename Stream>
grpc::Status BatchedPlan(Stream& stream, const v1::PlanRequest& request,
                         v1::PlanResponse* plan) {
  v1::PlanBatchRequest item;
  item.set_request_id("a");
  *item.mutable_request() = request;
  v1::PlanBatchResponse answer;
  if (!stream.Write(item))
    return grpc::Status(grpc::StatusCode::INTERNAL, "write failed");
  stream.WritesDone();
  if (stream.Read(&answer)) *plan = answer.result();
  return stream.Finish();
}

TEST_F(PackedPathTest, PackedDecodesToTheReadablePath) {
  int any_angle = 0;
  int partial = 0;
  int empty = 0;
  for (v1::PlanRequest request : Cases()) {
    SCOPED_TRACE(request.ShortDebugString());
    request.mutable_options()->set_path_encoding(v1::PATH_ENCODING_READABLE);
    const v1::PlanResponse readable = Plan(request);
    request.mutable_options()->set_path_encoding(v1::PATH_ENCODING_PACKED);
    const v1::PlanResponse packed = Plan(request);
    ExpectSamePath(packed, readable);
    any_angle += readable.any_angle() && readable.path_size() > 2;
    partial += !readable.found() && readable.path_size() > 0;
    empty += readable.path_size() == 0;
    if (readable.path_size() > 0) {
      const uint8_t format = static_cast<uint8_t>(packed.packed_path()[0]);
      EXPECT_EQ(format, readable.any_angle() && readable.path_size() > 2
                            ? kPackedPathDeltas
                            : kPackedPathMoves);
    }
  }
  EXPECT_EQ(any_angle, 2);  // theta_star, simplified
  EXPECT_EQ(partial, 1);
  EXPECT_EQ(empty, 1);
}

TEST_F(PackedPathTest, BothCarriesBothAndUnspecifiedIsReadable) {
  for (v1::PlanRequest request : Cases()) {
    SCOPED_TRACE(request.ShortDebugString());
    request.mutable_options()->set_path_encoding(v1::PATH_ENCODING_READABLE);
    v1::PlanResponse readable = Plan(request);
    EXPECT_THAT(readable.packed_path(), IsEmpty());
    EXPECT_FALSE(readable.has_path_frame());

    request.mutable_options()->set_path_encoding(v1::PATH_ENCODING_UNSPECIFIED);
    v1::PlanResponse unspecified = Plan(request);
    unspecified.clear_planning_time_us();
    readable.clear_planning_time_us();
    EXPECT_EQ(unspecified.SerializeAsString(), readable.SerializeAsString());

    request.mutable_options()->set_path_encoding(v1::PATH_ENCODING_BOTH);
    v1::PlanResponse both = Plan(request);
    EXPECT_EQ(both.path_size(), readable.path_size());
    EXPECT_EQ(both.world_path_size(), readable.world_path_size());
    EXPECT_EQ(both.packed_path().empty(), readable.path_size() == 0);
    absl::StatusOr<std::vector<PackedCell>> cells =
        DecodePackedPath(both.packed_path());
    ASSERT_TRUE(cells.ok()) << cells.status();
    ASSERT_EQ(static_cast<int>(cells->size()), both.path_size());
    for (int i = 0; i < both.path_size(); ++i) {
      EXPECT_EQ((*cells)[i], (PackedCell{both.path(i).x(), both.path(i).y()}));
      const v1::WorldPoint w =
          PathFrameCellCenter(both.path_frame(), (*cells)[i].x, (*cells)[i].y);
      EXPECT_EQ(w.x(), both.world_path(i).x());
      EXPECT_EQ(w.y(), both.world_path(i).y());
    }
  }
}

TEST_F(PackedPathTest, UnknownEncodingIsInvalidArgumentNamingTheField) {
  v1::PlanRequest request =
      Request(v1::PLANNER_ASTAR, CellPos(0, 0), CellPos(3, 3), {});
  request.mutable_options()->set_path_encoding(
      static_cast<v1::PathEncoding>(9));
  v1::PlanResponse response;
  const grpc::Status s =
      server_->planner().Plan(Context().get(), request, &response);
  EXPECT_EQ(s.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(s.error_message(), HasSubstr("options.path_encoding"));
}

TEST_F(PackedPathTest, StreamsAndBatchesCarryThePackedPath) {
  const v1::PlanRequest base =
      Request(v1::PLANNER_ASTAR, CellPos(0, 0), CellPos(31, 9),
              v1::PATH_ENCODING_READABLE);
  const v1::PlanResponse readable = Plan(base);
  v1::PlanRequest packed = base;
  packed.mutable_options()->set_path_encoding(v1::PATH_ENCODING_PACKED);

  auto context = Context();
  auto reader = server_->planner().PlanStream(context.get(), packed);
  v1::PlanResponse streamed;
  ASSERT_TRUE(StreamedPlan(*reader, &streamed).ok());
  ExpectSamePath(streamed, readable);

  auto batch_context = Context();
  auto batch = server_->planner().PlanBatch(batch_context.get());
  v1::PlanResponse batched;
  ASSERT_TRUE(BatchedPlan(*batch, packed, &batched).ok());
  ExpectSamePath(batched, readable);
}

TEST_F(PackedPathTest, NavigatePushesPackedPlans) {
  auto context = Context();
  auto stream = server_->planner().Navigate(context.get());
  v1::NavigateRequest open;
  v1::NavigateOpen* o = open.mutable_open();
  o->set_map("rooms");
  *o->mutable_start() = CellPos(0, 0);
  *o->mutable_goal() = CellPos(31, 9);
  o->mutable_options()->set_path_encoding(v1::PATH_ENCODING_PACKED);
  ASSERT_TRUE(stream->Write(open));
  v1::NavigateResponse first;
  ASSERT_TRUE(stream->Read(&first));
  // ListSessions (what the viewer draws) lists the path readable.
  v1::ListSessionsRequest list;
  list.set_map("rooms");
  v1::ListSessionsResponse sessions;
  ASSERT_TRUE(
      server_->planner().ListSessions(Context().get(), list, &sessions).ok());
  ASSERT_EQ(sessions.sessions_size(), 1);
  const v1::PlanResponse& listed = sessions.sessions(0).last().plan();
  EXPECT_THAT(listed.packed_path(), IsEmpty());
  EXPECT_GT(listed.path_size(), 1);
  EXPECT_EQ(listed.world_path_size(), listed.path_size());
  stream->WritesDone();
  context->TryCancel();
  stream->Finish();
  ASSERT_TRUE(first.has_plan());
  v1::PlanResponse plan = first.plan();
  EXPECT_THAT(plan.path(), IsEmpty());
  ASSERT_FALSE(plan.packed_path().empty());
  ASSERT_TRUE(UnpackPlanPath(&plan).ok());
  EXPECT_EQ(plan.path(0).x(), 0);
  EXPECT_EQ(plan.path(plan.path_size() - 1).x(), 31);
  EXPECT_EQ(plan.world_path_size(), plan.path_size());
}

TEST_F(PackedPathTest, TripsPlanIsPackedAndTheClientUnpacksIt) {
  v1::TripRequest trip;
  trip.set_map("rooms");
  *trip.add_waypoints() = CellPos(0, 0);
  *trip.add_waypoints() = CellPos(31, 9);
  *trip.add_waypoints() = CellPos(20, 9);
  trip.mutable_options()->set_path_encoding(v1::PATH_ENCODING_READABLE);
  v1::TripResponse readable;
  ASSERT_TRUE(server_->planner().Trip(Context().get(), trip, &readable).ok());
  ASSERT_GT(readable.plan().path_size(), 1);
  trip.mutable_options()->set_path_encoding(v1::PATH_ENCODING_PACKED);
  v1::TripResponse packed;
  ASSERT_TRUE(server_->planner().Trip(Context().get(), trip, &packed).ok());
  ExpectSamePath(packed.plan(), readable.plan());

  trip.mutable_options()->clear_path_encoding();
  const client::PathdClient client(server_->channel());
  absl::StatusOr<v1::TripResponse> answer = client.Trip(trip);
  ASSERT_TRUE(answer.ok()) << answer.status();
  EXPECT_THAT(answer->plan().packed_path(), IsEmpty());
  EXPECT_EQ(answer->plan().path_size(), readable.plan().path_size());
  EXPECT_EQ(answer->plan().world_path(1).y(),
            readable.plan().world_path(1).y());
}

TEST_F(PackedPathTest, TheClientAsksForPackedAndAnswersReadable) {
  const client::PathdClient client(server_->channel());
  for (v1::PlanRequest request : Cases()) {
    SCOPED_TRACE(request.ShortDebugString());
    request.mutable_options()->set_path_encoding(v1::PATH_ENCODING_READABLE);
    v1::PlanResponse readable = Plan(request);
    request.mutable_options()->set_path_encoding(v1::PATH_ENCODING_UNSPECIFIED);
    absl::StatusOr<v1::PlanResponse> answer = client.Plan(request);
    ASSERT_TRUE(answer.ok()) << answer.status();
    EXPECT_THAT(answer->packed_path(), IsEmpty());
    answer->clear_planning_time_us();
    readable.clear_planning_time_us();
    EXPECT_EQ(answer->SerializeAsString(), readable.SerializeAsString());
  }
  // Through the client's streams too.
  v1::PlanRequest request = Request(v1::PLANNER_JPS, CellPos(0, 0),
                                    CellPos(31, 9), v1::PATH_ENCODING_READABLE);
  const v1::PlanResponse readable = Plan(request);
  request.mutable_options()->clear_path_encoding();
  auto context = Context();
  auto reader = client.PlanStream(context.get(), request);
  v1::PlanResponse streamed;
  ASSERT_TRUE(StreamedPlan(*reader, &streamed).ok());
  EXPECT_EQ(streamed.path_size(), readable.path_size());
  EXPECT_THAT(streamed.packed_path(), IsEmpty());
  auto batch_context = Context();
  auto batch = client.PlanBatch(batch_context.get(), "rooms");
  v1::PlanResponse batched;
  ASSERT_TRUE(BatchedPlan(*batch, request, &batched).ok());
  EXPECT_EQ(batched.path_size(), readable.path_size());
  EXPECT_EQ(batched.world_path(3).x(), readable.world_path(3).x());
  EXPECT_THAT(batched.packed_path(), IsEmpty());
}

}  // namespace
}  // namespace pathd::server
