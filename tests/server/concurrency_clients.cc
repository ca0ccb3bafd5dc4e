// concurrency_test: the client threads' loops (Plan, PlanBatch, UpdateMap and
// Navigate callers), each recording what it saw in its ClientLog.
#include "tests/server/concurrency_fixture.h"

namespace pathd::server::concurrency_test {

void ConcurrencyTest::PlanClient(int thread, ClientLog& log) {
  std::mt19937 rng(100 + thread);
  while (!stop_.load()) {
    RandomPlan plan = MakeRandomPlan(rng);
    plan.what = "Plan " + plan.what;
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
    v1::PlanResponse response;
    Progress(thread, "Plan");
    const grpc::Status status = planner_->Plan(&context, plan.request, &response);
    Progress(thread, "between calls");
    if (!status.ok()) {
      log.failures.push_back(plan.what + ": " + status.error_message());
      continue;
    }
    plan.Record(response, log);
  }
}

void ConcurrencyTest::BatchClient(int thread, ClientLog& log) {
  std::mt19937 rng(300 + thread);
  int round = 0;
  while (!stop_.load()) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
    Progress(thread, "PlanBatch open");
    auto stream = planner_->PlanBatch(&context);
    std::map<std::string, RandomPlan> pending;
    const int burst = 4 + static_cast<int>(rng() % 12);
    for (int i = 0; i < burst; ++i) {
      RandomPlan plan = MakeRandomPlan(rng);
      const std::string id = absl::StrCat(round, "-", i);
      plan.what = absl::StrCat("PlanBatch item ", id, " ", plan.what);
      v1::PlanBatchRequest item;
      item.set_request_id(id);
      *item.mutable_request() = plan.request;
      Progress(thread, "PlanBatch write");
      if (!stream->Write(item)) break;
      pending.emplace(id, std::move(plan));
    }
    Progress(thread, "PlanBatch writes done");
    stream->WritesDone();
    v1::PlanBatchResponse answer;
    while (true) {
      Progress(thread, "PlanBatch read");
      if (!stream->Read(&answer)) break;
      auto it = pending.find(answer.request_id());
      if (it == pending.end()) {
        log.failures.push_back(absl::StrCat("PlanBatch: answer for unknown or "
                                            "repeated id '",
                                            answer.request_id(), "'"));
        continue;
      }
      if (answer.has_error()) {
        log.failures.push_back(it->second.what + ": " + answer.error().message());
      } else {
        it->second.Record(answer.result(), log);
      }
      pending.erase(it);
    }
    Progress(thread, "PlanBatch finish");
    const grpc::Status status = stream->Finish();
    Progress(thread, "between calls");
    if (!status.ok()) {
      log.failures.push_back(absl::StrCat("PlanBatch round ", round, ": ",
                                          status.error_message()));
    }
    for (const auto& [id, plan] : pending) {
      log.failures.push_back(plan.what + ": never answered");
    }
    ++round;
  }
}

void ConcurrencyTest::UpdateClient(int thread, ClientLog& log) {
  std::mt19937 rng(200 + thread);
  while (!stop_.load()) {
    const size_t m = rng() % maps_.size();
    const SharedMap& map = maps_[m];
    const std::vector<MapChange> changes =
        RandomChanges(map, rng, 1 + static_cast<int>(rng() % 3));
    v1::UpdateMapRequest request;
    request.set_name(map.name);
    for (const MapChange& change : changes)
      ToWire(change, request.add_changes());
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
    v1::UpdateMapResponse response;
    Progress(thread, "UpdateMap");
    const grpc::Status status =
        map_stub_->UpdateMap(&context, request, &response);
    Progress(thread, "between calls");
    if (!status.ok()) {
      log.failures.push_back("UpdateMap " + map.name + ": " +
                             status.error_message());
      continue;
    }
    log.versions.push_back(
        Version{m, response.version(), changes, "UpdateMap"});
    // A short pause now and then lets plans finish on a version before the
    // next one replaces it (cache hits as well as repairs).
    if (rng() % 4 == 0)
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void ConcurrencyTest::NavigateClient(int thread, ClientLog& log) {
  std::mt19937 rng(300 + thread);
  while (!stop_.load()) {
    const size_t m = rng() % maps_.size();
    const SharedMap& map = maps_[m];
    const Cell start = map.endpoints[rng() % map.endpoints.size()];
    const Cell goal = map.endpoints[rng() % map.endpoints.size()];
    const std::string what =
        absl::StrFormat("Navigate on %s to %s", map.name, CellToString(goal));
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + kCallDeadline);
    Progress(thread, "Navigate open");
    auto stream = planner_->Navigate(&context);

    // Writes `request` and reads up to its answer; pushes before it are
    // recorded too. Returns the answer, or nullopt when the stream ended.
    std::vector<MapChange> observed;
    auto exchange = [&](const v1::NavigateRequest& request)
        -> std::optional<v1::NavigateResponse> {
      if (!stream->Write(request)) return std::nullopt;
      v1::NavigateResponse response;
      for (;;) {
        Progress(thread, "Navigate read");
        if (!stream->Read(&response)) return std::nullopt;
        Progress(thread, "between calls");
        const bool pushed =
            response.event() == v1::NAVIGATE_EVENT_MAP_CHANGED;
        if (!pushed && response.seq() != request.seq()) {
          log.failures.push_back(
              absl::StrFormat("%s: answer to seq %d, expected %d", what,
                              response.seq(), request.seq()));
        }
        if (CellOf(response.plan().goal()) != goal) {
          log.failures.push_back(
              what + ": answer names goal " +
              CellToString(CellOf(response.plan().goal())));
        }
        log.answers.push_back(RecordPlan(
            m, response.plan(), goal, CostParams(),
            absl::StrFormat("%s: %s", what,
                            v1::NavigateEvent_Name(response.event()))));
        if (pushed) {
          ++log.pushes;
          continue;
        }
        return response;
      }
    };

    v1::NavigateRequest open;
    open.set_seq(1);
    open.mutable_open()->set_map(map.name);
    *open.mutable_open()->mutable_start() = CellPosition(start);
    *open.mutable_open()->mutable_goal() = CellPosition(goal);
    std::optional<v1::NavigateResponse> answer = exchange(open);
    for (uint64_t seq = 2; answer.has_value() && seq < 20 && !stop_.load();
         ++seq) {
      const auto& path = answer->plan().path();
      if (path.size() < 2) break;  // at the goal, or no path on this version
      v1::NavigateRequest request;
      request.set_seq(seq);
      if (rng() % 4 == 0) {
        const std::vector<MapChange> changes = RandomChanges(map, rng, 1);
        for (const MapChange& change : changes) {
          ToWire(change, request.mutable_observe()->add_changes());
        }
        answer = exchange(request);
        if (!answer.has_value()) break;
        if (answer->applied_version() == 0) {
          log.failures.push_back(what +
                                 ": shared observation produced no version");
        } else {
          log.versions.push_back(Version{m, answer->applied_version(),
                                         changes, what + " observation"});
        }
      } else {
        *request.mutable_pose() = CellPosition(CellOf(path[1]));
        answer = exchange(request);
      }
    }
    stream->WritesDone();
    // Pushes sent before the server saw the end of the stream.
    v1::NavigateResponse response;
    Progress(thread, "Navigate drain");
    while (stream->Read(&response)) {
      Progress(thread, "Navigate drain");
      if (response.event() != v1::NAVIGATE_EVENT_MAP_CHANGED) {
        log.failures.push_back(what + ": unasked non-push after WritesDone");
      }
      ++log.pushes;
      log.answers.push_back(RecordPlan(m, response.plan(), goal, CostParams(),
                                       what + ": pushed while closing"));
    }
    Progress(thread, "Navigate finish");
    const grpc::Status status = stream->Finish();
    Progress(thread, "between calls");
    if (!status.ok())
      log.failures.push_back(what + ": " + status.error_message());
  }
}

void ConcurrencyTest::RunClient(int thread, Role role, ClientLog& log) {
  switch (role) {
    case Role::kPlan:
      PlanClient(thread, log);
      break;
    case Role::kBatch:
      BatchClient(thread, log);
      break;
    case Role::kNavigate:
      NavigateClient(thread, log);
      break;
    case Role::kUpdate:
      UpdateClient(thread, log);
      break;
  }
  Progress(thread, "done");
}

}  // namespace pathd::server::concurrency_test
