#include "tests/testing/in_process_server.h"

#include <utility>

#include "absl/strings/str_cat.h"

namespace pathd::testing {

server::ServerOptions TestServerOptions() {
  server::ServerOptions options;
  options.address = "127.0.0.1:0";
  options.threads = 2;
  options.queue_depth = 64;
  options.shutdown_grace = absl::Seconds(2);
  return options;
}

std::string CellsFromRows(const std::vector<std::string>& rows) {
  std::string cells;
  for (const std::string& row : rows) {
    for (const char c : row) {
      uint8_t cost = 0;
      if (c == '#') cost = 254;
      if (c == '?') cost = 255;
      if (c >= '1' && c <= '9') cost = static_cast<uint8_t>((c - '0') * 10);
      cells.push_back(static_cast<char>(cost));
    }
  }
  return cells;
}

v1::CreateMapRequest RawMapRequest(const std::string& name, int width, int height,
                                   std::string cells) {
  v1::CreateMapRequest request;
  request.set_name(name);
  request.mutable_raw()->set_width(width);
  request.mutable_raw()->set_height(height);
  request.mutable_raw()->set_cells(std::move(cells));
  return request;
}

InProcessServer::InProcessServer(server::ServerOptions options) {
  options.address = "127.0.0.1:0";
  server_ = std::make_unique<server::PathdServer>(std::move(options));
}

InProcessServer::~InProcessServer() {
  planner_.reset();
  maps_.reset();
  channel_.reset();
  server_->Shutdown();
}

absl::Status InProcessServer::Start(const grpc::ChannelArguments& channel_args) {
  if (absl::Status started = server_->Start(); !started.ok()) return started;
  channel_ = grpc::CreateCustomChannel(server_->listen_address(),
                                       grpc::InsecureChannelCredentials(), channel_args);
  maps_ = v1::MapService::NewStub(channel_);
  planner_ = v1::PlannerService::NewStub(channel_);
  return absl::OkStatus();
}

grpc::Status InProcessServer::CreateMap(const v1::CreateMapRequest& request,
                                        v1::CreateMapResponse* response) {
  v1::CreateMapResponse ignored;
  return maps_->CreateMap(Context().get(), request,
                          response != nullptr ? response : &ignored);
}

grpc::Status InProcessServer::CreateRawMap(const std::string& name, int width,
                                           int height, std::string cells,
                                           double resolution, bool replace,
                                           v1::CreateMapResponse* response) {
  v1::CreateMapRequest request = RawMapRequest(name, width, height, std::move(cells));
  request.set_resolution(resolution);
  request.set_replace(replace);
  return CreateMap(request, response);
}

grpc::Status InProcessServer::CreateFreeMap(const std::string& name, int width,
                                            int height) {
  return CreateRawMap(name, width, height,
                      std::string(static_cast<size_t>(width) * height, '\0'));
}

grpc::Status InProcessServer::CreateMapFromRows(const std::string& name,
                                                const std::vector<std::string>& rows,
                                                double resolution, bool replace) {
  return CreateRawMap(name, static_cast<int>(rows[0].size()),
                      static_cast<int>(rows.size()), CellsFromRows(rows), resolution,
                      replace);
}

void InProcessServer::KeepMapVersions() {
  server_->store().AddListener(
      [this](std::string_view name,
             const std::shared_ptr<const server::MapSnapshot>& snapshot) {
        if (snapshot != nullptr) KeepMapVersion(name, snapshot);
      });
}

void InProcessServer::KeepMapVersion(
    std::string_view name, const std::shared_ptr<const server::MapSnapshot>& snapshot) {
  absl::MutexLock lock(&versions_mu_);
  versions_[{std::string(name), snapshot->version}] = snapshot->grid;
}

std::shared_ptr<const Grid> InProcessServer::MapVersion(const std::string& name,
                                                        uint64_t version) const {
  absl::MutexLock lock(&versions_mu_);
  const auto it = versions_.find({name, version});
  return it == versions_.end() ? nullptr : it->second;
}

absl::StatusOr<LoopbackServer> ServeOnLoopback(grpc::Service* service) {
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
  builder.RegisterService(service);
  LoopbackServer loopback;
  loopback.server = builder.BuildAndStart();
  if (loopback.server == nullptr || port == 0) {
    return absl::UnavailableError("cannot listen on 127.0.0.1:0");
  }
  loopback.channel = grpc::CreateChannel(absl::StrCat("127.0.0.1:", port),
                                         grpc::InsecureChannelCredentials());
  return loopback;
}

}  // namespace pathd::testing
