// Request and response of a unary callback method on one protobuf arena, so
// a response holding a path of N cells costs a few block allocations
// instead of 2N small ones (each Cell and WorldPoint submessage), and the
// whole call's messages go away in one free. Registered with the generated
// SetMessageAllocatorFor_<Method>; thread-safe.
#ifndef PATHD_SERVER_RPC_ARENA_ALLOCATOR_H_
#define PATHD_SERVER_RPC_ARENA_ALLOCATOR_H_

#include <grpcpp/support/message_allocator.h>

#include <cstddef>

#include "google/protobuf/arena.h"

namespace pathd::server {

template <typename Request, typename Response>
class ArenaMessageAllocator final
    : public grpc::MessageAllocator<Request, Response> {
 public:
  grpc::MessageHolder<Request, Response>* AllocateMessages() override {
    return new Holder();
  }

 private:
  // The arena's first block lives inside the holder: a short plan's request
  // and response need no allocation beyond the holder itself.
  static constexpr size_t kFirstBlockBytes = 4096;

  class Holder final : public grpc::MessageHolder<Request, Response> {
   public:
    Holder() : arena_(Options(first_block_)) {
      this->set_request(
          google::protobuf::Arena::CreateMessage<Request>(&arena_));
      this->set_response(
          google::protobuf::Arena::CreateMessage<Response>(&arena_));
    }
    // gRPC is done with both messages.
    void Release() override { delete this; }

   private:
    static google::protobuf::ArenaOptions Options(char* first_block) {
      google::protobuf::ArenaOptions options;
      options.initial_block = first_block;
      options.initial_block_size = kFirstBlockBytes;
      // Later blocks double up to this size (long paths).
      options.max_block_size = 64 * 1024;
      return options;
    }

    alignas(std::max_align_t) char first_block_[kFirstBlockBytes];
    // After first_block_, which it uses: constructed after it, destroyed
    // before it.
    google::protobuf::Arena arena_;
  };
};

}  // namespace pathd::server

#endif  // PATHD_SERVER_RPC_ARENA_ALLOCATOR_H_
