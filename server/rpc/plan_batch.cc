// PlanBatch: one stream's state (reads, items in flight, the write queue)
// and its reactor. Items answer through PlanCall::on_finish; the state is
// shared by the reactor and the items' on_finish, for the reason given in
// plan_stream.cc.
#include "server/rpc/plan_batch.h"

#include <deque>
#include <memory>
#include <string>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/container/flat_hash_map.h"
#include "absl/strings/str_format.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "server/grpc_status.h"
#include "server/request_log.h"

namespace pathd::server {
namespace {

// One PlanBatch stream. Items are read while fewer than `max_inflight` are
// outstanding (read, answer not yet written), so a client that sends faster
// than the workers plan, or reads its answers slowly, is held back by gRPC
// flow control instead of growing the server's queues. Answers are written
// in the order they finish. The stream finishes when the client has
// half-closed and every item is answered, or, once the client cancelled or
// stopped reading, when every running item has stopped. Thread-safe.
class PlanBatchState final : public std::enable_shared_from_this<PlanBatchState> {
 public:
  PlanBatchState(const PlanDeps& deps, size_t max_inflight, absl::Time deadline)
      : deps_(deps),
        max_inflight_(max_inflight),
        deadline_(deadline),
        opened_(absl::Now()) {}

  // Starts reading; `reactor` must stay valid until this state calls its
  // Finish.
  void Start(grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>*
                 reactor) {
    absl::MutexLock lock(&mu_);
    reactor_ = reactor;
    reading_ = true;
    reactor_->StartRead(&read_);
  }

  void OnReadDone(bool ok) {
    v1::PlanBatchRequest message;
    {
      absl::MutexLock lock(&mu_);
      reading_ = false;
      if (broken_ || !ok) {
        reads_done_ = true;
        PumpLocked();
        return;
      }
      ++outstanding_;
      ++items_;
      ++accepting_;
      message = std::move(read_);
      read_.Clear();
    }
    Accept(std::move(message));
    absl::MutexLock lock(&mu_);
    ResumeReadingLocked();
    PumpLocked();
  }

  void OnWriteDone(bool ok) {
    absl::MutexLock lock(&mu_);
    writing_ = false;
    --outstanding_;
    if (!ok) BreakLocked(absl::CancelledError("the client stopped reading"));
    ResumeReadingLocked();
    PumpLocked();
  }

  void OnCancel() {
    absl::MutexLock lock(&mu_);
    BreakLocked(absl::CancelledError("the client cancelled the batch"));
    PumpLocked();
  }

 private:
  // An item's request and response; the item's PlanCall points into it.
  struct Item {
    v1::PlanBatchRequest request;
    v1::PlanResponse response;
  };

  // Validates and submits one item; every path ends in exactly one answer
  // (FinishPlanCall -> ItemDone, or an immediate error).
  void Accept(v1::PlanBatchRequest message) {
    auto item = std::make_shared<Item>();
    item->request = std::move(message);
    const std::string& id = item->request.request_id();
    auto call = std::make_shared<PlanCall>();
    call->received = absl::Now();
    call->request = &item->request.request();
    call->response = &item->response;
    call->deadline = deadline_;
    call->rpc = "PlanBatch";
    call->on_finish = [state = shared_from_this(), item](const absl::Status& s) {
      state->ItemDone(*item, s);
    };
    {
      absl::MutexLock lock(&mu_);
      absl::Status refused;
      if (id.empty()) {
        refused = absl::InvalidArgumentError(
            "request_id is empty (give each item a non-empty id)");
      } else if (running_.contains(id)) {
        refused = absl::InvalidArgumentError(absl::StrFormat(
            "request_id '%s' is already in flight on this stream", id));
      } else if (broken_) {
        refused = absl::CancelledError("the batch was cancelled");
      }
      // From here the item is either answered or in running_, both of which
      // keep the stream open.
      --accepting_;
      if (!refused.ok()) {
        v1::PlanBatchResponse answer;
        answer.set_request_id(id);
        *answer.mutable_error() = ToPlanError(refused);
        AnswerLocked(std::move(answer));
        return;
      }
      // Registered before submitting: the job may answer at once.
      running_.emplace(id, call);
    }
    if (absl::Status s = PreparePlan(deps_, *call); !s.ok()) {
      FinishPlanCall(*call, s, "REJECTED");
      return;
    }
    if (absl::Status s =
            deps_.pool.Submit(MakePlanJob(deps_, call), WorkerPool::Priority::kBatch);
        !s.ok()) {
      FinishPlanCall(*call, s, "REJECTED");
    }
  }

  // PlanCall::on_finish of an accepted item, on a worker or gRPC thread.
  void ItemDone(Item& item, const absl::Status& status) {
    // Released after the lock: the caller still holds the call.
    std::shared_ptr<PlanCall> finished;
    absl::MutexLock lock(&mu_);
    const std::string& id = item.request.request_id();
    if (auto it = running_.find(id); it != running_.end()) {
      finished = std::move(it->second);
      running_.erase(it);
    }
    v1::PlanBatchResponse answer;
    answer.set_request_id(id);
    if (status.ok()) {
      *answer.mutable_result() = std::move(item.response);
    } else {
      *answer.mutable_error() = ToPlanError(status);
    }
    AnswerLocked(std::move(answer));
  }

  void AnswerLocked(v1::PlanBatchResponse answer) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (broken_) {
      --outstanding_;  // nobody will read it
    } else {
      pending_.push_back(std::move(answer));
    }
    PumpLocked();
  }

  // The client is gone: cancel what runs, drop what waits, read no more.
  void BreakLocked(const absl::Status& why) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (broken_) return;
    broken_ = true;
    end_status_ = why;
    reads_done_ = true;
    outstanding_ -= pending_.size();
    pending_.clear();
    for (auto& [id, call] : running_) {
      call->cancelled.store(true, std::memory_order_relaxed);
    }
  }

  void ResumeReadingLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (reading_ || reads_done_ || finished_ || outstanding_ >= max_inflight_) {
      return;
    }
    reading_ = true;
    reactor_->StartRead(&read_);
  }

  void PumpLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (finished_ || writing_) return;
    if (!pending_.empty()) {
      out_ = std::move(pending_.front());
      pending_.pop_front();
      writing_ = true;
      reactor_->StartWrite(&out_);
      return;
    }
    // Every running item must have answered first: their on_finish holds
    // this state, but the reactor is deleted soon after Finish. An item
    // still being accepted counts too: a write completing meanwhile may
    // already have started the read that sees the client's half-close.
    if (!reads_done_ || !running_.empty() || accepting_ > 0) return;
    finished_ = true;
    LogRequest("PlanBatch", "-", absl::StrFormat("items=%d", items_), end_status_,
               opened_);
    reactor_->Finish(ToGrpcStatus(end_status_));
  }

  const PlanDeps deps_;
  const size_t max_inflight_;
  const absl::Time deadline_;
  const absl::Time opened_;

  absl::Mutex mu_;
  grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>* reactor_
      ABSL_GUARDED_BY(mu_) = nullptr;
  // Owned by gRPC between StartRead and OnReadDone.
  v1::PlanBatchRequest read_ ABSL_GUARDED_BY(mu_);
  // Owned by gRPC between StartWrite and OnWriteDone.
  v1::PlanBatchResponse out_ ABSL_GUARDED_BY(mu_);
  std::deque<v1::PlanBatchResponse> pending_ ABSL_GUARDED_BY(mu_);
  // Items submitted or being prepared, by request id (for duplicates and
  // cancellation); an item leaves when it is answered.
  absl::flat_hash_map<std::string, std::shared_ptr<PlanCall>> running_
      ABSL_GUARDED_BY(mu_);
  // Items read whose answer is not yet written (or dropped).
  size_t outstanding_ ABSL_GUARDED_BY(mu_) = 0;
  // Items read but not yet answered or registered in running_ (Accept runs
  // outside the lock).
  int accepting_ ABSL_GUARDED_BY(mu_) = 0;
  int64_t items_ ABSL_GUARDED_BY(mu_) = 0;
  bool reading_ ABSL_GUARDED_BY(mu_) = false;
  // The client half-closed, or the stream broke.
  bool reads_done_ ABSL_GUARDED_BY(mu_) = false;
  bool writing_ ABSL_GUARDED_BY(mu_) = false;
  bool broken_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
  absl::Status end_status_ ABSL_GUARDED_BY(mu_);
};

class PlanBatchReactor final
    : public grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse> {
 public:
  explicit PlanBatchReactor(std::shared_ptr<PlanBatchState> state)
      : state_(std::move(state)) {}

  void OnReadDone(bool ok) override { state_->OnReadDone(ok); }
  void OnWriteDone(bool ok) override { state_->OnWriteDone(ok); }
  void OnCancel() override { state_->OnCancel(); }
  void OnDone() override { delete this; }

 private:
  std::shared_ptr<PlanBatchState> state_;
};

}  // namespace

grpc::ServerBidiReactor<v1::PlanBatchRequest, v1::PlanBatchResponse>* ServePlanBatch(
    const PlanDeps& deps, size_t max_inflight, grpc::CallbackServerContext* context) {
  auto state = std::make_shared<PlanBatchState>(deps, max_inflight, DeadlineOf(*context));
  auto* reactor = new PlanBatchReactor(state);
  state->Start(reactor);
  return reactor;
}

}  // namespace pathd::server
