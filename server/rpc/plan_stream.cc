// PlanStream: the plan runs as Plan's and answers through PlanCall::on_finish
// instead of a unary reactor. The stream's mutable state lives in a shared
// object held by the reactor and by the job's on_finish, so a job that is
// still returning from the call that led to Finish never uses a reactor gRPC
// has already deleted (OnDone may run on another thread as soon as Finish is
// called). gRPC never runs reactions inline from Start*/Finish, so those are
// called with the state's mutex held.
#include "server/rpc/plan_stream.h"

#include <cmath>
#include <memory>
#include <optional>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/clock.h"
#include "core/search/stop_condition.h"
#include "server/grpc_status.h"

namespace pathd::server {
namespace {

class PlanStreamState final : public ProgressSink {
 public:
  PlanStreamState(absl::Duration interval, grpc::CallbackServerContext* context,
                  absl::Time received)
      : ProgressSink(interval), context_(context), received_(received) {}

  // Must be called before the plan can finish; `reactor` must stay valid
  // until this state calls its Finish.
  void Attach(grpc::ServerWriteReactor<v1::PlanStreamEvent>* reactor) {
    absl::MutexLock lock(&mu_);
    reactor_ = reactor;
  }

  // Where the plan job writes its response.
  v1::PlanResponse* response() { return &response_; }

  // The plan's answer (PlanCall::on_finish): queues the final event.
  void OnPlanFinished(const absl::Status& status) {
    absl::MutexLock lock(&mu_);
    final_.emplace();
    if (status.ok()) {
      *final_->mutable_result() = std::move(response_);
    } else {
      *final_->mutable_error() = ToPlanError(status);
      if (const v1::PlanOutcome typed = OutcomeOfStatus(status);
          IsRejectionOutcome(typed)) {
        context_->AddTrailingMetadata(kPlanOutcomeMetadataKey,
                                      v1::PlanOutcome_Name(typed));
      }
    }
    final_status_ = ToGrpcStatus(status);
    progress_.reset();
    PumpLocked();
  }

  void OnWriteDone(bool ok) {
    absl::MutexLock lock(&mu_);
    writing_ = false;
    if (!ok) broken_ = true;
    PumpLocked();
  }

 private:
  void Report(int64_t expansions, double best_f, absl::Time now) override {
    v1::PlanStreamEvent event;
    v1::PlanProgress* progress = event.mutable_progress();
    progress->set_expansions(expansions);
    if (!std::isnan(best_f)) progress->set_best_f(best_f);
    progress->set_elapsed_us(absl::ToInt64Microseconds(now - received_));
    absl::MutexLock lock(&mu_);
    progress_ = std::move(event);
    PumpLocked();
  }

  // Starts the next write, or finishes once the final event is written (or
  // can no longer be).
  void PumpLocked() ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_) {
    if (writing_ || finished_) return;
    if (final_.has_value() && (final_sent_ || broken_)) {
      finished_ = true;
      reactor_->Finish(final_status_);
      return;
    }
    if (broken_) return;  // the plan is being cancelled; wait for its end
    if (final_.has_value()) {
      out_ = std::move(*final_);
      final_sent_ = true;
    } else if (progress_.has_value()) {
      out_ = std::move(*progress_);
      progress_.reset();
    } else {
      return;
    }
    writing_ = true;
    reactor_->StartWrite(&out_);
  }

  grpc::CallbackServerContext* const context_;
  const absl::Time received_;
  // Written by the plan job before on_finish, read by on_finish.
  v1::PlanResponse response_;

  absl::Mutex mu_;
  grpc::ServerWriteReactor<v1::PlanStreamEvent>* reactor_ ABSL_GUARDED_BY(mu_) =
      nullptr;
  std::optional<v1::PlanStreamEvent> progress_ ABSL_GUARDED_BY(mu_);
  std::optional<v1::PlanStreamEvent> final_ ABSL_GUARDED_BY(mu_);
  grpc::Status final_status_ ABSL_GUARDED_BY(mu_);
  // Owned by gRPC between StartWrite and OnWriteDone.
  v1::PlanStreamEvent out_ ABSL_GUARDED_BY(mu_);
  bool writing_ ABSL_GUARDED_BY(mu_) = false;
  bool final_sent_ ABSL_GUARDED_BY(mu_) = false;
  // A write failed: the client is gone.
  bool broken_ ABSL_GUARDED_BY(mu_) = false;
  bool finished_ ABSL_GUARDED_BY(mu_) = false;
};

class PlanStreamReactor final : public grpc::ServerWriteReactor<v1::PlanStreamEvent> {
 public:
  PlanStreamReactor(std::shared_ptr<PlanCall> call,
                    std::shared_ptr<PlanStreamState> state)
      : call_(std::move(call)), state_(std::move(state)) {}

  void OnCancel() override { call_->cancelled.store(true, std::memory_order_relaxed); }
  void OnWriteDone(bool ok) override {
    // A failed write means nobody reads the rest: stop planning.
    if (!ok) call_->cancelled.store(true, std::memory_order_relaxed);
    state_->OnWriteDone(ok);
  }
  void OnDone() override { delete this; }

 private:
  std::shared_ptr<PlanCall> call_;
  std::shared_ptr<PlanStreamState> state_;
};

}  // namespace

grpc::ServerWriteReactor<v1::PlanStreamEvent>* ServePlanStream(
    const PlanDeps& deps, absl::Duration progress_interval,
    grpc::CallbackServerContext* context, const v1::PlanRequest* request) {
  auto call = std::make_shared<PlanCall>();
  call->received = absl::Now();
  call->request = request;
  call->deadline = DeadlineOf(*context);
  call->rpc = "PlanStream";
  auto state =
      std::make_shared<PlanStreamState>(progress_interval, context, call->received);
  call->response = state->response();
  call->progress = state.get();
  call->on_finish = [state](const absl::Status& s) { state->OnPlanFinished(s); };
  auto* reactor = new PlanStreamReactor(call, state);
  state->Attach(reactor);

  if (absl::Status s = PreparePlan(deps, *call); !s.ok()) {
    FinishPlanCall(*call, s, "REJECTED");
    return reactor;
  }
  if (absl::Status s = deps.pool.Submit(MakePlanJob(deps, call)); !s.ok()) {
    FinishPlanCall(*call, s, "REJECTED");
  }
  return reactor;
}

}  // namespace pathd::server
