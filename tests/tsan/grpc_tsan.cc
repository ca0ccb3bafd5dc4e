// ThreadSanitizer-only shim for the one hand-off of gRPC's C++ callback API
// that TSan cannot see: a batch of operations started on one thread and
// completed on another. Linked into test executables of the PATHD_TSAN build
// only (never into pathd).
//
// The C++ layer (grpc::internal::CallOpSet, the ServerBidiReactor/unary
// reactor glue, interceptor state, the serialised message) is header code,
// compiled and instrumented in our binary. It writes a CallOpSet on the thread
// that calls PerformOps (a pool worker answering a Plan, a Navigate session
// writing), then libgrpc (uninstrumented) queues the batch and a completion
// thread reads the same CallOpSet in FinishOp. The synchronisation between the
// two is inside libgrpc's completion queue, invisible to TSan, so every such
// batch was reported as a race. Here the executable interposes the C API
// calls on both sides of that hand-off (libgrpc++ calls them through the PLT)
// and tells TSan: release on the batch's tag when it is handed to gRPC,
// acquire on the tag an event returns. That is exactly the ordering gRPC
// guarantees ("the tag completes after the batch started"), nothing more, so
// races in our code on either side are still reported.
#include <dlfcn.h>
#include <grpc/grpc.h>
#include <sanitizer/tsan_interface.h>

#include <cstdio>
#include <cstdlib>

namespace {

template <typename Fn>
Fn Real(const char* name) {
  void* fn = dlsym(RTLD_NEXT, name);
  if (fn == nullptr) {
    std::fprintf(stderr, "grpc_tsan: %s not found in libgrpc\n", name);
    std::abort();
  }
  return reinterpret_cast<Fn>(fn);
}

void Acquire(const grpc_event& event) {
  if (event.type == GRPC_OP_COMPLETE && event.tag != nullptr)
    __tsan_acquire(event.tag);
}

}  // namespace

extern "C" {

grpc_call_error grpc_call_start_batch(grpc_call* call, const grpc_op* ops,
                                      size_t nops, void* tag, void* reserved) {
  static const auto real =
      Real<grpc_call_error (*)(grpc_call*, const grpc_op*, size_t, void*,
                               void*)>("grpc_call_start_batch");
  if (tag != nullptr) __tsan_release(tag);
  return real(call, ops, nops, tag, reserved);
}

grpc_call_error grpc_server_request_call(
    grpc_server* server, grpc_call** call, grpc_call_details* details,
    grpc_metadata_array* request_metadata,
    grpc_completion_queue* cq_bound_to_call,
    grpc_completion_queue* cq_for_notification, void* tag_new) {
  static const auto real = Real<grpc_call_error (*)(
      grpc_server*, grpc_call**, grpc_call_details*, grpc_metadata_array*,
      grpc_completion_queue*, grpc_completion_queue*, void*)>(
      "grpc_server_request_call");
  if (tag_new != nullptr) __tsan_release(tag_new);
  return real(server, call, details, request_metadata, cq_bound_to_call,
              cq_for_notification, tag_new);
}

grpc_call_error grpc_server_request_registered_call(
    grpc_server* server, void* registered_method, grpc_call** call,
    gpr_timespec* deadline, grpc_metadata_array* request_metadata,
    grpc_byte_buffer** optional_payload,
    grpc_completion_queue* cq_bound_to_call,
    grpc_completion_queue* cq_for_notification, void* tag_new) {
  static const auto real = Real<grpc_call_error (*)(
      grpc_server*, void*, grpc_call**, gpr_timespec*, grpc_metadata_array*,
      grpc_byte_buffer**, grpc_completion_queue*, grpc_completion_queue*,
      void*)>("grpc_server_request_registered_call");
  if (tag_new != nullptr) __tsan_release(tag_new);
  return real(server, registered_method, call, deadline, request_metadata,
              optional_payload, cq_bound_to_call, cq_for_notification, tag_new);
}

grpc_event grpc_completion_queue_next(grpc_completion_queue* cq,
                                      gpr_timespec deadline, void* reserved) {
  static const auto real =
      Real<grpc_event (*)(grpc_completion_queue*, gpr_timespec, void*)>(
          "grpc_completion_queue_next");
  const grpc_event event = real(cq, deadline, reserved);
  Acquire(event);
  return event;
}

grpc_event grpc_completion_queue_pluck(grpc_completion_queue* cq, void* tag,
                                       gpr_timespec deadline, void* reserved) {
  static const auto real =
      Real<grpc_event (*)(grpc_completion_queue*, void*, gpr_timespec, void*)>(
          "grpc_completion_queue_pluck");
  const grpc_event event = real(cq, tag, deadline, reserved);
  Acquire(event);
  return event;
}

}  // extern "C"
