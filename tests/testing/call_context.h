// Client contexts with a deadline for tests that call pathd over gRPC, in
// process (in_process_server.h) or as a separate process (the e2e tests):
// the deadline is a hang guard, never a timing assertion.
#ifndef PATHD_TESTS_TESTING_CALL_CONTEXT_H_
#define PATHD_TESTS_TESTING_CALL_CONTEXT_H_

#include <chrono>
#include <memory>

#include <grpcpp/client_context.h>

#include "absl/time/time.h"

namespace pathd::testing {

inline constexpr absl::Duration kCallDeadline = absl::Seconds(60);

// Sets `context`'s deadline to `deadline` from now.
inline void SetDeadline(grpc::ClientContext& context,
                        absl::Duration deadline = kCallDeadline) {
  context.set_deadline(std::chrono::system_clock::now() +
                       absl::ToChronoMilliseconds(deadline));
}

// A new client context whose deadline is `deadline` from now.
inline std::unique_ptr<grpc::ClientContext> Context(
    absl::Duration deadline = kCallDeadline) {
  auto context = std::make_unique<grpc::ClientContext>();
  SetDeadline(*context, deadline);
  return context;
}

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_CALL_CONTEXT_H_
