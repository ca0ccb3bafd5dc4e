// The shared machinery of a unary RPC whose work runs on the worker pool,
// written once for Plan, CostToGo and IsPathValid: the call's head, the
// reactor that forwards cancellation, admission (prepare on the gRPC thread,
// then submit) and the pool job that drops unwanted calls, turns exceptions
// into statuses and answers exactly once.
#ifndef PATHD_SERVER_RPC_UNARY_CALL_H_
#define PATHD_SERVER_RPC_UNARY_CALL_H_

#include <atomic>
#include <exception>
#include <functional>
#include <memory>
#include <new>
#include <string_view>
#include <utility>

#include <grpcpp/grpcpp.h>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"
#include "google/protobuf/message.h"
#include "server/grpc_status.h"
#include "server/worker_pool.h"

namespace pathd::server {

// How close to its deadline a cancelled call counts as timed out (see
// CancellableReactor::OnCancel).
inline constexpr absl::Duration kDeadlineSlack = absl::Milliseconds(10);

// The server's copy of the call's deadline; InfiniteFuture when it has none.
absl::Time DeadlineOf(const grpc::CallbackServerContext& context);

// Why a job that waited in the queue should not start: DEADLINE_EXCEEDED or
// CANCELLED, OK when it should. The deadline is checked first because gRPC
// also cancels a call whose deadline passed, and the log should say why.
absl::Status StillWanted(const std::atomic<bool>& cancelled, absl::Time deadline);

// RESOURCE_EXHAUSTED when `response` would not fit in one gRPC message
// (max_bytes 0: unchecked). Checked here because gRPC's own refusal, "Sent
// message larger than max", names neither the response nor the flag.
absl::Status CheckResponseSize(const google::protobuf::Message& response,
                               std::string_view what, int64_t max_bytes);

// What a call's work ended with: its status and the outcome word of the
// request log ("FOUND", "VALID", "ERROR", ...).
struct Verdict {
  absl::Status status;
  std::string_view outcome;
};

// The head every pool-run call shares. gRPC owns request/response and keeps
// them valid until the reactor is done, which cannot happen before Finish;
// Finish is the last thing done with them. The call lives behind a
// shared_ptr, which keeps `cancelled` alive for a search still polling it
// after the reactor was deleted.
template <typename Request, typename Response>
struct UnaryCall {
  // Set by OnCancel on a gRPC thread, polled by the work on a worker.
  std::atomic<bool> cancelled{false};
  grpc::ServerUnaryReactor* reactor = nullptr;
  grpc::CallbackServerContext* context = nullptr;
  const Request* request = nullptr;
  Response* response = nullptr;
  absl::Time received;
  absl::Time deadline = absl::InfiniteFuture();
};

// The reactor of a unary call that runs on the pool: forwards cancellation to
// the call's flag. `Call` has `std::atomic<bool> cancelled` and `absl::Time
// deadline`.
template <typename Call>
class CancellableReactor final : public grpc::ServerUnaryReactor {
 public:
  explicit CancellableReactor(std::shared_ptr<Call> call) : call_(std::move(call)) {}

  // Searches poll the flag every StopCondition::kPollInterval expansions; a
  // queued job sees it before it starts.
  void OnCancel() override {
    // A client whose own deadline fires cancels the call a moment before the
    // server's copy of that deadline (it travels as a relative timeout), so a
    // cancel this close to the deadline is the deadline: the search's own
    // check stops it within kDeadlineSlack and it is reported as a TIMEOUT.
    if (absl::Now() + kDeadlineSlack >= call_->deadline) return;
    call_->cancelled.store(true, std::memory_order_relaxed);
  }
  void OnDone() override { delete this; }

 private:
  std::shared_ptr<Call> call_;
};

// Makes the call and its reactor for a handler: received now, the context's
// deadline, the reactor registered in the call.
template <typename Call, typename Request, typename Response>
std::shared_ptr<Call> StartUnaryCall(grpc::CallbackServerContext* context,
                                     const Request* request, Response* response) {
  auto call = std::make_shared<Call>();
  call->received = absl::Now();
  call->context = context;
  call->request = request;
  call->response = response;
  call->deadline = DeadlineOf(*context);
  call->reactor = new CancellableReactor<Call>(call);
  return call;
}

// Texts of the failures a job reports for exceptions, e.g. {"out of memory
// while planning", "planner failed"}.
struct JobFailureText {
  const char* out_of_memory;
  const char* failed;
};

// A pool job for a call: drops it (CANCELLED/TIMEOUT) when nobody waits any
// more, runs `work`, turns a thrown bad_alloc into RESOURCE_EXHAUSTED and any
// other exception into INTERNAL, and answers with `Finish(call, status,
// outcome)`; at shutdown Drop answers UNAVAILABLE. `Call` has `cancelled`
// and `deadline` as UnaryCall does.
template <typename Call>
class CallJob final : public Job {
 public:
  using Work = std::function<Verdict(Call&, SearchScratch&)>;
  using Finish = void (*)(Call&, const absl::Status&, std::string_view);

  CallJob(std::shared_ptr<Call> call, Work work, Finish finish, JobFailureText text)
      : call_(std::move(call)), work_(std::move(work)), finish_(finish), text_(text) {}

  void Run(SearchScratch& scratch) override {
    Call& call = *call_;
    if (absl::Status s = StillWanted(call.cancelled, call.deadline); !s.ok()) {
      finish_(call, s, absl::IsCancelled(s) ? "CANCELLED" : "TIMEOUT");
      return;
    }
    Verdict verdict;
    try {
      verdict = work_(call, scratch);
    } catch (const std::bad_alloc&) {
      verdict = {absl::ResourceExhaustedError(text_.out_of_memory), "ERROR"};
    } catch (const std::exception& e) {
      verdict = {absl::InternalError(absl::StrFormat("%s: %s", text_.failed, e.what())),
                 "ERROR"};
    }
    finish_(call, verdict.status, verdict.outcome);
  }

  void Drop() override {
    finish_(*call_, absl::UnavailableError("server is shutting down"), "DROPPED");
  }
  // The pool caught what escaped Run (e.g. a test's injected failure):
  // answer with its status rather than Drop's UNAVAILABLE.
  void Fail(const absl::Status& status) override { finish_(*call_, status, "ERROR"); }

 private:
  std::shared_ptr<Call> call_;
  Work work_;
  Finish finish_;
  JobFailureText text_;
};

// How a call's job reaches the pool.
enum class JobLength {
  // Queued for a worker (WorkerPool::Submit).
  kAny,
  // Usually short (Plan, IsPathValid): may run on this gRPC thread at once
  // (WorkerPool::SubmitShort).
  kUsuallyShort,
};

// Admission of a prepared unary call: answers REJECTED with `prepared` when it
// failed, else submits `job`, answering REJECTED with the
// pool's refusal (and a retry-after trailer) when the queue is full or
// closed. Once submitted the job owns the answer and may already have
// finished the call (on a worker, or here for a short job), so the caller
// must not touch `call` after this returns; it returns the reactor to hand
// back to gRPC (a reactor may be finished before gRPC has it).
template <typename Call>
grpc::ServerUnaryReactor* AdmitUnaryCall(WorkerPool& pool, std::shared_ptr<Call> call,
                                         const absl::Status& prepared,
                                         std::unique_ptr<Job> job,
                                         typename CallJob<Call>::Finish finish,
                                         JobLength length = JobLength::kAny) {
  grpc::ServerUnaryReactor* reactor = call->reactor;
  if (!prepared.ok()) {
    finish(*call, prepared, "REJECTED");
    return reactor;
  }
  const absl::Status submitted =
      length == JobLength::kUsuallyShort
          ? pool.SubmitShort(std::move(job), call->deadline - absl::Now())
          : pool.Submit(std::move(job));
  if (absl::Status s = submitted; !s.ok()) {
    AddRetryAfterTrailer(s, *call->context);
    finish(*call, s, "REJECTED");
  }
  return reactor;
}

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_UNARY_CALL_H_
