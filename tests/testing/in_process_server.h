// The one in-process server fixture of the tests under tests/server: a real
// PathdServer (server/server.h) on 127.0.0.1:0 with the test's options, a
// channel with MapService and PlannerService stubs to it, and helpers that
// create maps through the RPC (calls use call_context.h's deadline).
// ServeOnLoopback puts a lone gRPC service on a port for one-service tests.
#ifndef PATHD_TESTS_TESTING_IN_PROCESS_SERVER_H_
#define PATHD_TESTS_TESTING_IN_PROCESS_SERVER_H_

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "absl/time/time.h"
#include "core/map/grid.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/server.h"
#include "tests/testing/call_context.h"

namespace pathd::testing {

// What most server tests run with: 127.0.0.1:0, 2 workers, a queue of 64,
// 2 s shutdown grace; the rest as ServerOptions' defaults.
server::ServerOptions TestServerOptions();

// Raw cells from rows of text, row 0 first: '.' free, '#' lethal (254),
// '?' unknown (255), a digit d cost 10 * d; anything else free.
std::string CellsFromRows(const std::vector<std::string>& rows);

// A CreateMapRequest of raw cells.
v1::CreateMapRequest RawMapRequest(const std::string& name, int width, int height,
                                   std::string cells);

// Constructed stopped, so a test can reach the server (e.g. add a store
// listener) before Start(). The destructor closes the client side, then
// shuts the server down.
class InProcessServer {
 public:
  // options.address is replaced by 127.0.0.1:0.
  explicit InProcessServer(server::ServerOptions options = TestServerOptions());
  ~InProcessServer();
  InProcessServer(const InProcessServer&) = delete;
  InProcessServer& operator=(const InProcessServer&) = delete;

  // Starts the server (PathdServer::Start's errors), then opens a plaintext
  // channel with `channel_args` and the stubs.
  absl::Status Start(const grpc::ChannelArguments& channel_args = {});
  // PathdServer::Shutdown; the stubs stay (calls then fail UNAVAILABLE).
  void Shutdown() { server_->Shutdown(); }

  server::PathdServer& server() { return *server_; }
  server::MapStore& store() { return server_->store(); }
  const server::ServerOptions& options() const { return server_->options(); }
  std::string listen_address() const { return server_->listen_address(); }
  int port() const { return server_->port(); }
  int metrics_port() const { return server_->metrics_port(); }
  const server::MapWatchers& map_watchers() const { return server_->map_watchers(); }

  // Valid after a successful Start.
  const std::shared_ptr<grpc::Channel>& channel() const { return channel_; }
  v1::MapService::Stub& maps() { return *maps_; }
  v1::PlannerService::Stub& planner() { return *planner_; }

  // CreateMap through the RPC with Context()'s deadline; `response` may be
  // null.
  grpc::Status CreateMap(const v1::CreateMapRequest& request,
                         v1::CreateMapResponse* response = nullptr);
  grpc::Status CreateRawMap(const std::string& name, int width, int height,
                            std::string cells, double resolution = 0.0,
                            bool replace = false,
                            v1::CreateMapResponse* response = nullptr);
  // A width x height map of free cells.
  grpc::Status CreateFreeMap(const std::string& name, int width, int height);
  // A map from rows of text (CellsFromRows).
  grpc::Status CreateMapFromRows(const std::string& name,
                                 const std::vector<std::string>& rows,
                                 double resolution = 0.0, bool replace = false);

  // From now on keeps every version of every map the store publishes (an
  // update, a replacing create), so a test can check an answer against the
  // version it names. Call before Start.
  void KeepMapVersions();
  // Keeps `snapshot` as `name`'s version (e.g. one made by store().Create,
  // which publishes nothing).
  void KeepMapVersion(std::string_view name,
                      const std::shared_ptr<const server::MapSnapshot>& snapshot);
  // A kept version; null when not kept.
  std::shared_ptr<const Grid> MapVersion(const std::string& name,
                                         uint64_t version) const;

 private:
  // Declared before the server, whose store's listener writes them.
  mutable absl::Mutex versions_mu_;
  std::map<std::pair<std::string, uint64_t>, std::shared_ptr<const Grid>> versions_
      ABSL_GUARDED_BY(versions_mu_);
  std::unique_ptr<server::PathdServer> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::PlannerService::Stub> planner_;
};

// A gRPC server holding only `service` on a free loopback port, and a
// plaintext channel to it, for tests of one service with its own parts.
struct LoopbackServer {
  std::unique_ptr<grpc::Server> server;
  std::shared_ptr<grpc::Channel> channel;
};
absl::StatusOr<LoopbackServer> ServeOnLoopback(grpc::Service* service);

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_IN_PROCESS_SERVER_H_
