// A gtest fixture for pathctl command tests: `Fake` (a gRPC service
// implementation) served on 127.0.0.1:0, Options pointing at it, and Ctl()
// running pathctl::Run with captured output.
#ifndef PATHD_TESTS_CLIENT_PATHCTL_COMMAND_FIXTURE_H_
#define PATHD_TESTS_CLIENT_PATHCTL_COMMAND_FIXTURE_H_

#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "client/pathctl/command.h"
#include "grpcpp/server.h"
#include "grpcpp/server_builder.h"
#include "gtest/gtest.h"

namespace pathd::pathctl {

template <typename Fake>
class CommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
    grpc::ServerBuilder builder;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port_);
    builder.RegisterService(&fake_);
    server_ = builder.BuildAndStart();
    ASSERT_NE(server_, nullptr);
    options_.global.server = absl::StrCat("127.0.0.1:", port_);
  }
  void TearDown() override { server_->Shutdown(); }

  // pathctl with `args` against the fake; its exit code, out_ and err_ hold
  // what it printed.
  int Ctl(const std::vector<std::string>& args) {
    out_.str("");
    err_.str("");
    return pathctl::Run(options_, args, out_, err_);
  }

  Fake fake_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  Options options_;
  std::ostringstream out_;
  std::ostringstream err_;
};

}  // namespace pathd::pathctl

#endif  // PATHD_TESTS_CLIENT_PATHCTL_COMMAND_FIXTURE_H_
