// The non-template parts of the unary-call helper.
#include "server/rpc/unary_call.h"

#include <chrono>

#include "absl/strings/str_format.h"

namespace pathd::server {

absl::Time DeadlineOf(const grpc::CallbackServerContext& context) {
  const auto deadline = context.deadline();
  // gRPC reports "no deadline" as time_point::max(), which absl::FromChrono
  // would have to saturate; say what it means instead.
  if (deadline == std::chrono::system_clock::time_point::max()) {
    return absl::InfiniteFuture();
  }
  return absl::FromChrono(deadline);
}

absl::Status StillWanted(const std::atomic<bool>& cancelled, absl::Time deadline) {
  if (absl::Now() >= deadline) {
    return absl::DeadlineExceededError(
        "deadline passed while the request waited for a worker");
  }
  if (cancelled.load(std::memory_order_relaxed)) {
    return absl::CancelledError("cancelled before planning started");
  }
  return absl::OkStatus();
}

absl::Status CheckResponseSize(const google::protobuf::Message& response,
                               std::string_view what, int64_t max_bytes) {
  const size_t bytes = response.ByteSizeLong();
  if (max_bytes <= 0 || bytes <= static_cast<size_t>(max_bytes)) {
    return absl::OkStatus();
  }
  return absl::ResourceExhaustedError(absl::StrFormat(
      "the %s would be %d bytes, more than the limit of %d bytes "
      "(--max_message_bytes)",
      what, bytes, max_bytes));
}

}  // namespace pathd::server
