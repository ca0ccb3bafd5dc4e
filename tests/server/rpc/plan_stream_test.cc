// PlanStream, PlanBatch and the typed rejection outcomes over a real gRPC
// channel to PathdServers on 127.0.0.1:0: one with the default batch bound
// and a 5 ms progress interval, one with --batch_max_inflight=1. Random maps
// and queries use fixed seeds; nothing asserts on durations (the progress
// spacing is checked on the server's own timestamps).
#include <chrono>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <random>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/create_channel.h>
#include <grpcpp/security/credentials.h>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/rpc/planner_service.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"
#include "tests/testing/requests.h"

namespace pathd::server {
namespace {

using ::testing::HasSubstr;

constexpr absl::Duration kProgressInterval = absl::Milliseconds(5);
// Big enough that Dijkstra runs for many progress intervals (about a
// million expansions), small enough to keep the suite at a few seconds.
constexpr int kBigSide = 1024;

using testing::CellPos;
using testing::PlanBetween;

std::unique_ptr<grpc::ClientContext> Context() {
  return testing::Context(absl::Seconds(120));
}

// The trailing metadata value of `key`, empty when absent.
std::string Trailer(const grpc::ClientContext& context, const std::string& key) {
  const auto& trailers = context.GetServerTrailingMetadata();
  const auto it = trailers.find(key);
  if (it == trailers.end()) return "";
  return std::string(it->second.data(), it->second.size());
}

class PlanStreamTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    ServerOptions options = testing::TestServerOptions();
    options.queue_depth = 256;
    options.max_map_cells = 1 << 22;
    options.progress_interval = kProgressInterval;
    server_ = new testing::InProcessServer(options);
    ASSERT_TRUE(server_->Start().ok());

    options.batch_max_inflight = 1;
    tiny_server_ = new testing::InProcessServer(options);
    ASSERT_TRUE(tiny_server_->Start().ok());

    for (testing::InProcessServer* server : {server_, tiny_server_}) {
      CreateMap(server->maps(), "big", kBigSide, kBigSide,
                std::string(kBigSide * kBigSide, '\0'));
      CreateMap(server->maps(), "small", 8, 8, std::string(64, '\0'));
    }
    // Two seeded random maps for the batch: 20% lethal cells, a free border
    // so most queries have a path.
    std::mt19937 rng(20240611);
    for (const auto& [name, side] : {std::pair<const char*, int>{"rand_a", 48},
                                     {"rand_b", 96}}) {
      std::string cells(static_cast<size_t>(side * side), '\0');
      std::bernoulli_distribution blocked(0.2);
      for (int y = 1; y < side - 1; ++y) {
        for (int x = 1; x < side - 1; ++x) {
          if (blocked(rng)) cells[static_cast<size_t>(y * side + x)] = static_cast<char>(254);
        }
      }
      CreateMap(server_->maps(), name, side, side, cells);
    }
  }

  static void TearDownTestSuite() {
    delete server_;
    delete tiny_server_;
    server_ = tiny_server_ = nullptr;
  }

  static void CreateMap(v1::MapService::Stub& maps, const std::string& name, int width,
                        int height, const std::string& cells) {
    v1::CreateMapResponse response;
    const grpc::Status s = maps.CreateMap(
        Context().get(), testing::RawMapRequest(name, width, height, cells), &response);
    ASSERT_TRUE(s.ok()) << s.error_message();
  }

  void SetUp() override {
    planner_ = &server_->planner();
    tiny_planner_ = &tiny_server_->planner();
    maps_ = &server_->maps();
  }

  grpc::Status Plan(const v1::PlanRequest& request, v1::PlanResponse* response,
                    std::string* outcome_trailer = nullptr) {
    auto context = Context();
    const grpc::Status status = planner_->Plan(context.get(), request, response);
    if (outcome_trailer != nullptr) {
      *outcome_trailer = Trailer(*context, kPlanOutcomeMetadataKey);
    }
    return status;
  }

  // Every event of a PlanStream call, and its final status and outcome trailer.
  struct StreamRun {
    std::vector<v1::PlanStreamEvent> events;
    grpc::Status status;
    std::string outcome_trailer;
  };
  StreamRun RunStream(const v1::PlanRequest& request) {
    StreamRun run;
    auto context = Context();
    auto reader = planner_->PlanStream(context.get(), request);
    v1::PlanStreamEvent event;
    while (reader->Read(&event)) run.events.push_back(event);
    run.status = reader->Finish();
    run.outcome_trailer = Trailer(*context, kPlanOutcomeMetadataKey);
    return run;
  }

  // Sends `items` on one PlanBatch stream from a writer thread and returns
  // the answers in arrival order.
  static std::vector<v1::PlanBatchResponse> RunBatch(
      v1::PlannerService::Stub& stub, const std::vector<v1::PlanBatchRequest>& items,
      grpc::Status* status) {
    auto context = Context();
    auto stream = stub.PlanBatch(context.get());
    std::thread writer([&] {
      for (const v1::PlanBatchRequest& item : items) {
        if (!stream->Write(item)) break;
      }
      stream->WritesDone();
    });
    std::vector<v1::PlanBatchResponse> answers;
    v1::PlanBatchResponse answer;
    while (stream->Read(&answer)) answers.push_back(answer);
    writer.join();
    *status = stream->Finish();
    return answers;
  }

  static v1::PlanBatchRequest Item(const std::string& id, v1::PlanRequest request) {
    v1::PlanBatchRequest item;
    item.set_request_id(id);
    *item.mutable_request() = std::move(request);
    return item;
  }

  // tiny_server_ runs PlanBatch with one item in flight per stream.
  static testing::InProcessServer* server_;
  static testing::InProcessServer* tiny_server_;
  v1::PlannerService::Stub* planner_ = nullptr;
  v1::PlannerService::Stub* tiny_planner_ = nullptr;
  v1::MapService::Stub* maps_ = nullptr;
};

testing::InProcessServer* PlanStreamTest::server_ = nullptr;
testing::InProcessServer* PlanStreamTest::tiny_server_ = nullptr;

// --- PlanStream --------------------------------------------------------------

TEST_F(PlanStreamTest, StreamReportsProgressThenThePlansResult) {
  const v1::PlanRequest request =
      PlanBetween("big", 0, 0, kBigSide - 1, kBigSide - 1, v1::PLANNER_DIJKSTRA);
  const StreamRun run = RunStream(request);
  ASSERT_TRUE(run.status.ok()) << run.status.error_message();
  ASSERT_GE(run.events.size(), 2u);
  ASSERT_TRUE(run.events.back().has_result());

  int64_t last_expansions = 0;
  double last_best_f = 0.0;
  int64_t last_elapsed_us = -1;
  for (size_t i = 0; i + 1 < run.events.size(); ++i) {
    ASSERT_TRUE(run.events[i].has_progress()) << "event " << i;
    const v1::PlanProgress& p = run.events[i].progress();
    EXPECT_GT(p.expansions(), last_expansions);
    // Dijkstra's open-list minimum g never decreases.
    ASSERT_TRUE(p.has_best_f());
    EXPECT_GE(p.best_f(), last_best_f);
    // The rate bound, on the server's clock: one event per interval at most.
    if (last_elapsed_us >= 0) {
      EXPECT_GE(p.elapsed_us() - last_elapsed_us,
                absl::ToInt64Microseconds(kProgressInterval))
          << "event " << i;
    }
    last_expansions = p.expansions();
    last_best_f = p.best_f();
    last_elapsed_us = p.elapsed_us();
  }
  const v1::PlanResponse& streamed = run.events.back().result();
  EXPECT_GE(streamed.expansions(), last_expansions);
  EXPECT_LE(last_best_f, streamed.cost());

  v1::PlanResponse unary;
  ASSERT_TRUE(Plan(request, &unary).ok());
  ASSERT_TRUE(unary.found());
  EXPECT_EQ(streamed.found(), unary.found());
  EXPECT_DOUBLE_EQ(streamed.cost(), unary.cost());
  EXPECT_EQ(streamed.expansions(), unary.expansions());
  EXPECT_EQ(streamed.path_size(), unary.path_size());
  EXPECT_EQ(streamed.planner(), "dijkstra");
}

TEST_F(PlanStreamTest, EveryPlannerFamilyReportsProgress) {
  // A* is too quick on an open map; a wall with one gap at the far end makes
  // every planner here work through most of the map.
  std::string cells(static_cast<size_t>(kBigSide * kBigSide), '\0');
  const int wall_x = kBigSide / 2;
  for (int y = 0; y < kBigSide - 1; ++y) {
    cells[static_cast<size_t>(y * kBigSide + wall_x)] = static_cast<char>(254);
  }
  CreateMap(*maps_, "walled", kBigSide, kBigSide, cells);
  for (const v1::Planner planner :
       {v1::PLANNER_ASTAR, v1::PLANNER_BFS, v1::PLANNER_DISTANCE_TRANSFORM_EXACT,
        v1::PLANNER_SPM}) {
    SCOPED_TRACE(v1::Planner_Name(planner));
    const StreamRun run =
        RunStream(PlanBetween("walled", 0, 0, kBigSide - 1, 0, planner));
    ASSERT_TRUE(run.status.ok()) << run.status.error_message();
    ASSERT_TRUE(run.events.back().has_result());
    EXPECT_TRUE(run.events.back().result().found());
    ASSERT_GE(run.events.size(), 2u) << "no progress event";
    EXPECT_TRUE(run.events.front().has_progress());
    // BFS keeps no ordered open list: no best f.
    EXPECT_EQ(run.events.front().progress().has_best_f(), planner != v1::PLANNER_BFS);
  }
}

TEST_F(PlanStreamTest, SearchUnderOnePollSendsOnlyTheResult) {
  // Progress comes from the stop condition's polls every 1024 expansions; a
  // search of 64 cells has none after the first, whatever the clock says.
  const StreamRun run = RunStream(PlanBetween("small", 0, 0, 7, 7));
  ASSERT_TRUE(run.status.ok());
  ASSERT_EQ(run.events.size(), 1u);
  ASSERT_TRUE(run.events[0].has_result());
  EXPECT_TRUE(run.events[0].result().found());
}

TEST_F(PlanStreamTest, RejectedStreamEndsWithATypedErrorEvent) {
  const StreamRun outside = RunStream(PlanBetween("small", 0, 0, 8, 3));
  EXPECT_EQ(outside.status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  ASSERT_EQ(outside.events.size(), 1u);
  ASSERT_TRUE(outside.events[0].has_error());
  EXPECT_EQ(outside.events[0].error().code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(outside.events[0].error().outcome(), v1::PLAN_OUTCOME_GOAL_OUTSIDE_MAP);
  EXPECT_THAT(outside.events[0].error().message(), HasSubstr("goal"));
  EXPECT_EQ(outside.outcome_trailer, "PLAN_OUTCOME_GOAL_OUTSIDE_MAP");

  const StreamRun missing = RunStream(PlanBetween("no_such_map", 0, 0, 1, 1));
  EXPECT_EQ(missing.status.error_code(), grpc::StatusCode::NOT_FOUND);
  ASSERT_EQ(missing.events.size(), 1u);
  EXPECT_EQ(missing.events[0].error().outcome(), v1::PLAN_OUTCOME_MAP_NOT_FOUND);
}

TEST_F(PlanStreamTest, CancellingTheStreamCancelsThePlan) {
  auto context = Context();
  auto reader = planner_->PlanStream(
      context.get(),
      PlanBetween("big", 0, 0, kBigSide - 1, kBigSide - 1, v1::PLANNER_DIJKSTRA));
  v1::PlanStreamEvent event;
  ASSERT_TRUE(reader->Read(&event));
  ASSERT_TRUE(event.has_progress());
  context->TryCancel();
  while (reader->Read(&event)) {
    EXPECT_FALSE(event.has_result()) << "the plan ran to the end";
  }
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  // The worker is free again and the server healthy.
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(PlanBetween("small", 0, 0, 7, 7), &response).ok());
  EXPECT_TRUE(response.found());
}

// --- PlanBatch ---------------------------------------------------------------

// What a batch item should come back as.
struct Expected {
  v1::PlanRequest request;
  // UNSPECIFIED: a plan (compared with unary Plan); else the error outcome.
  v1::PlanOutcome error = v1::PLAN_OUTCOME_UNSPECIFIED;
  grpc::StatusCode code = grpc::StatusCode::OK;
};

TEST_F(PlanStreamTest, BatchAnswersEveryItemOnceWithPlansOrTypedErrors) {
  std::mt19937 rng(7);
  const v1::Planner planners[] = {v1::PLANNER_ASTAR, v1::PLANNER_DIJKSTRA,
                                  v1::PLANNER_JPS, v1::PLANNER_THETA_STAR,
                                  v1::PLANNER_BFS};
  std::map<std::string, Expected> expected;
  std::vector<v1::PlanBatchRequest> items;
  // Random endpoints land on blocked cells about a third of the time; unary
  // Plan on the same request says which, below.
  for (int i = 0; i < 100; ++i) {
    const std::string id = "item-" + std::to_string(i);
    const bool on_a = i % 2 == 0;
    const std::string map = on_a ? "rand_a" : "rand_b";
    const int side = on_a ? 48 : 96;
    std::uniform_int_distribution<int> coord(0, side - 1);
    Expected e;
    switch (i % 10) {
      case 7:  // start off the map
        e.request = PlanBetween(map, -1 - i, 0, 0, 0);
        e.error = v1::PLAN_OUTCOME_START_OUTSIDE_MAP;
        e.code = grpc::StatusCode::INVALID_ARGUMENT;
        break;
      case 8:  // goal off the map
        e.request = PlanBetween(map, 0, 0, side + i, 0);
        e.error = v1::PLAN_OUTCOME_GOAL_OUTSIDE_MAP;
        e.code = grpc::StatusCode::INVALID_ARGUMENT;
        break;
      case 9:  // unknown map, or a bad option
        if (i % 20 == 9) {
          e.request = PlanBetween("no_such_map", 0, 0, 1, 1);
          e.error = v1::PLAN_OUTCOME_MAP_NOT_FOUND;
          e.code = grpc::StatusCode::NOT_FOUND;
        } else {
          e.request = PlanBetween(map, 0, 0, 1, 1, v1::PLANNER_WEIGHTED_ASTAR);
          e.request.mutable_options()->set_heuristic_weight(0.5);
          e.error = v1::PLAN_OUTCOME_INVALID_REQUEST;
          e.code = grpc::StatusCode::INVALID_ARGUMENT;
        }
        break;
      default:  // random endpoints: found, no path, or occupied
        e.request = PlanBetween(map, coord(rng), coord(rng), coord(rng), coord(rng),
                                planners[i % 5]);
        e.request.mutable_options()->set_cost_weight(0.0);  // JPS needs it
    }
    expected[id] = e;
    items.push_back(Item(id, e.request));
  }

  grpc::Status status;
  const std::vector<v1::PlanBatchResponse> answers = RunBatch(*planner_, items, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), items.size());
  std::set<std::string> seen;
  int found = 0;
  int occupied = 0;
  for (const v1::PlanBatchResponse& answer : answers) {
    SCOPED_TRACE(answer.request_id());
    ASSERT_TRUE(seen.insert(answer.request_id()).second) << "answered twice";
    ASSERT_TRUE(expected.contains(answer.request_id())) << "unknown id";
    const Expected& e = expected[answer.request_id()];
    // Every item, good or bad, is answered as unary Plan answers it.
    v1::PlanResponse unary;
    std::string trailer;
    const grpc::Status unary_status = Plan(e.request, &unary, &trailer);
    if (e.error != v1::PLAN_OUTCOME_UNSPECIFIED) {
      ASSERT_TRUE(answer.has_error());
      EXPECT_EQ(answer.error().outcome(), e.error);
      EXPECT_EQ(answer.error().code(), e.code);
      EXPECT_EQ(unary_status.error_code(), e.code);
      EXPECT_EQ(trailer, v1::PlanOutcome_Name(e.error));
      continue;
    }
    if (!unary_status.ok()) {
      // A random endpoint on a blocked cell.
      ASSERT_TRUE(answer.has_error());
      EXPECT_EQ(answer.error().code(), unary_status.error_code());
      EXPECT_EQ(answer.error().message(), unary_status.error_message());
      EXPECT_THAT(answer.error().outcome(),
                  ::testing::AnyOf(v1::PLAN_OUTCOME_START_OCCUPIED,
                                   v1::PLAN_OUTCOME_GOAL_OCCUPIED));
      EXPECT_EQ(trailer, v1::PlanOutcome_Name(answer.error().outcome()));
      ++occupied;
      continue;
    }
    ASSERT_TRUE(answer.has_result()) << answer.error().message();
    EXPECT_EQ(answer.result().found(), unary.found());
    EXPECT_EQ(answer.result().outcome(), unary.outcome());
    EXPECT_DOUBLE_EQ(answer.result().cost(), unary.cost());
    EXPECT_EQ(answer.result().planner(), unary.planner());
    if (unary.found()) ++found;
  }
  // The seed gives a mix, so every branch above ran.
  EXPECT_GT(found, 10);
  EXPECT_GT(occupied, 3);
}

TEST_F(PlanStreamTest, BatchAnswersAsPlansFinishNotInOrder) {
  std::vector<v1::PlanBatchRequest> items = {
      Item("slow", PlanBetween("big", 0, 0, kBigSide - 1, kBigSide - 1,
                               v1::PLANNER_DIJKSTRA))};
  for (int i = 0; i < 5; ++i) {
    items.push_back(Item("fast-" + std::to_string(i), PlanBetween("small", 0, 0, 7, i)));
  }
  grpc::Status status;
  const std::vector<v1::PlanBatchResponse> answers = RunBatch(*planner_, items, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), items.size());
  // Two workers: the fast plans pass the slow one, which finishes last.
  EXPECT_EQ(answers.back().request_id(), "slow");
  for (const v1::PlanBatchResponse& answer : answers) {
    ASSERT_TRUE(answer.has_result()) << answer.request_id();
    EXPECT_TRUE(answer.result().found());
  }
}

// Regression: a write completing while the last item was still being
// accepted could start the read that sees the half-close, and the stream
// finished without that item (seen once in an e2e run). Many short batches
// of instant items and errors, half-closed at once, must each answer every
// item.
TEST_F(PlanStreamTest, ShortBatchesHalfClosedAtOnceAnswerEveryItem) {
  for (int round = 0; round < 200; ++round) {
    std::vector<v1::PlanBatchRequest> items;
    for (int i = 0; i < 1 + round % 6; ++i) {
      items.push_back(Item(std::to_string(i),
                           i % 3 == 2 ? PlanBetween("nowhere", 0, 0, 1, 1)
                                      : PlanBetween("small", 0, 0, 7, i % 8)));
    }
    grpc::Status status;
    const std::vector<v1::PlanBatchResponse> answers = RunBatch(*planner_, items, &status);
    ASSERT_TRUE(status.ok()) << "round " << round << ": " << status.error_message();
    ASSERT_EQ(answers.size(), items.size()) << "round " << round;
  }
}

TEST_F(PlanStreamTest, BatchBoundOfOneHoldsTheClientBackWithoutErrors) {
  // With --batch_max_inflight=1 the server reads item k+1 only after item
  // k's answer was written, so a slow first item cannot be overtaken and
  // nothing is refused: flow control, not errors.
  std::vector<v1::PlanBatchRequest> items = {
      Item("slow", PlanBetween("big", 0, 0, kBigSide - 1, kBigSide - 1,
                               v1::PLANNER_DIJKSTRA))};
  for (int i = 0; i < 20; ++i) {
    items.push_back(Item("fast-" + std::to_string(i), PlanBetween("small", 0, 0, 7, i % 8)));
  }
  grpc::Status status;
  const std::vector<v1::PlanBatchResponse> answers =
      RunBatch(*tiny_planner_, items, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), items.size());
  for (size_t i = 0; i < answers.size(); ++i) {
    EXPECT_EQ(answers[i].request_id(), items[i].request_id());
    EXPECT_TRUE(answers[i].has_result()) << answers[i].error().message();
  }
}

TEST_F(PlanStreamTest, BatchRefusesEmptyAndDuplicateIdsPerItem) {
  // "dup" is sent while the first "dup" (a second-long Dijkstra) runs.
  const std::vector<v1::PlanBatchRequest> items = {
      Item("dup", PlanBetween("big", 0, 0, kBigSide - 1, kBigSide - 1,
                              v1::PLANNER_DIJKSTRA)),
      Item("dup", PlanBetween("small", 0, 0, 1, 1)),
      Item("", PlanBetween("small", 0, 0, 1, 1)),
      Item("after", PlanBetween("small", 0, 0, 2, 2)),
  };
  grpc::Status status;
  const std::vector<v1::PlanBatchResponse> answers = RunBatch(*planner_, items, &status);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_EQ(answers.size(), 4u);
  int dup_results = 0;
  int dup_errors = 0;
  for (const v1::PlanBatchResponse& answer : answers) {
    if (answer.request_id() == "dup") {
      if (answer.has_result()) {
        ++dup_results;
        EXPECT_EQ(answer.result().planner(), "dijkstra");
      } else {
        ++dup_errors;
        EXPECT_EQ(answer.error().code(), grpc::StatusCode::INVALID_ARGUMENT);
        EXPECT_EQ(answer.error().outcome(), v1::PLAN_OUTCOME_INVALID_REQUEST);
        EXPECT_THAT(answer.error().message(), HasSubstr("already in flight"));
      }
    } else if (answer.request_id().empty()) {
      ASSERT_TRUE(answer.has_error());
      EXPECT_THAT(answer.error().message(), HasSubstr("request_id"));
    } else {
      EXPECT_EQ(answer.request_id(), "after");
      EXPECT_TRUE(answer.has_result());
    }
  }
  EXPECT_EQ(dup_results, 1);
  EXPECT_EQ(dup_errors, 1);
}

TEST_F(PlanStreamTest, CancellingABatchEndsItCancelled) {
  auto context = Context();
  auto stream = planner_->PlanBatch(context.get());
  ASSERT_TRUE(stream->Write(Item(
      "slow", PlanBetween("big", 0, 0, kBigSide - 1, kBigSide - 1, v1::PLANNER_DIJKSTRA))));
  ASSERT_TRUE(stream->Write(Item("fast", PlanBetween("small", 0, 0, 7, 7))));
  v1::PlanBatchResponse answer;
  ASSERT_TRUE(stream->Read(&answer));
  EXPECT_EQ(answer.request_id(), "fast");
  context->TryCancel();
  while (stream->Read(&answer)) {
  }
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  v1::PlanResponse response;
  ASSERT_TRUE(Plan(PlanBetween("small", 0, 0, 7, 7), &response).ok());
}

// --- typed outcomes on unary Plan ---------------------------------------------

TEST_F(PlanStreamTest, UnaryPlanRejectionsCarryTheOutcomeTrailer) {
  std::string blocked_rows(64, '\0');
  blocked_rows[0] = static_cast<char>(254);                // (0,0)
  blocked_rows[7 * 8 + 7] = static_cast<char>(254);        // (7,7)
  blocked_rows[3 * 8 + 4] = static_cast<char>(254);        // (4,3): radius test
  CreateMap(*maps_, "blocked", 8, 8, blocked_rows);

  struct Case {
    const char* name;
    v1::PlanRequest request;
    grpc::StatusCode code;
    const char* outcome;
  };
  v1::PlanRequest world_goal = PlanBetween("blocked", 1, 1, 0, 0);
  world_goal.mutable_goal()->mutable_world()->set_x(100.0);
  world_goal.mutable_goal()->mutable_world()->set_y(1.0);
  v1::PlanRequest radius = PlanBetween("blocked", 4, 4, 1, 1);
  radius.mutable_options()->set_robot_radius_cells(1.5);
  v1::PlanRequest tolerance = PlanBetween("blocked", 1, 1, 7, 7);
  tolerance.mutable_options()->set_goal_tolerance_cells(0.5);
  v1::PlanRequest bad_option = PlanBetween("blocked", 1, 1, 2, 2);
  bad_option.mutable_options()->set_max_expansions(-1);
  const Case cases[] = {
      {"start outside", PlanBetween("blocked", 9, 1, 1, 1),
       grpc::StatusCode::INVALID_ARGUMENT, "PLAN_OUTCOME_START_OUTSIDE_MAP"},
      {"goal outside (world point)", world_goal, grpc::StatusCode::INVALID_ARGUMENT,
       "PLAN_OUTCOME_GOAL_OUTSIDE_MAP"},
      {"start blocked", PlanBetween("blocked", 0, 0, 1, 1),
       grpc::StatusCode::INVALID_ARGUMENT, "PLAN_OUTCOME_START_OCCUPIED"},
      {"goal blocked", PlanBetween("blocked", 1, 1, 7, 7),
       grpc::StatusCode::INVALID_ARGUMENT, "PLAN_OUTCOME_GOAL_OCCUPIED"},
      {"start within the robot radius", radius, grpc::StatusCode::INVALID_ARGUMENT,
       "PLAN_OUTCOME_START_OCCUPIED"},
      {"no free goal within the tolerance", tolerance,
       grpc::StatusCode::INVALID_ARGUMENT, "PLAN_OUTCOME_GOAL_OCCUPIED"},
      {"bad option", bad_option, grpc::StatusCode::INVALID_ARGUMENT,
       "PLAN_OUTCOME_INVALID_REQUEST"},
      {"unknown map", PlanBetween("no_such_map", 0, 0, 1, 1),
       grpc::StatusCode::NOT_FOUND, "PLAN_OUTCOME_MAP_NOT_FOUND"},
      {"found", PlanBetween("blocked", 1, 1, 6, 6), grpc::StatusCode::OK, ""},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    v1::PlanResponse response;
    std::string trailer;
    const grpc::Status status = Plan(c.request, &response, &trailer);
    EXPECT_EQ(status.error_code(), c.code) << status.error_message();
    EXPECT_EQ(trailer, c.outcome);
  }
}

}  // namespace
}  // namespace pathd::server
