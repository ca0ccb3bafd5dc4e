// The fixture and helpers of security_test, whose tests are split over
// tests/server/security_*_test.cc: a real PathdServer with TLS, mutual TLS and
// tokens, certificates made with the openssl tool at run time, and a generic
// caller for every RPC.
#ifndef PATHD_TESTS_SERVER_SECURITY_FIXTURE_H_
#define PATHD_TESTS_SERVER_SECURITY_FIXTURE_H_

#include <google/protobuf/descriptor.h>
#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/support/byte_buffer.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "client/client.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "server/auth.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"
#include "tests/testing/requests.h"
#include "tests/testing/test_certs.h"

namespace pathd::server::security_test {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

// Tokens of the test's --auth_tokens file: 64 hex digits like `openssl rand
// -hex 32`, distinctive enough that finding one in a log is no accident.
inline constexpr char kReadToken[] =
    "read0123456789abcdef0123456789abcdef0123456789abcdef0123456789";
inline constexpr char kWriteToken[] =
    "write123456789abcdef0123456789abcdef0123456789abcdef012345678";
inline constexpr char kAdminToken[] =
    "admin123456789abcdef0123456789abcdef0123456789abcdef012345678";
// Configured by its hash only (sha256 key): printf %s TOKEN | sha256sum.
inline constexpr char kHashedToken[] =
    "hashed0123456789abcdef0123456789abcdef0123456789abcdef01234567";
inline constexpr char kHashedTokenSha256[] =
    "49e5477fc3082207401c7b1b018d5ea6f170758c5d13c6d54668129cc932eeea";
inline constexpr char kWrongToken[] =
    "wrong123456789abcdef0123456789abcdef0123456789abcdef012345678";

inline constexpr char kOpenRoom[] =
    "type octile\nheight 4\nwidth 5\nmap\n.....\n.....\n.....\n.....\n";

inline void WriteFile(const fs::path& path, const std::string& contents) {
  std::ofstream out(path, std::ios::binary);
  out << contents;
  ASSERT_TRUE(out.good()) << path;
}

inline std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

inline std::string TokensYaml() {
  return absl::StrCat(
      "tokens:\n", "  - {name: robot-7, role: read, token: ", kReadToken, "}\n",
      "  - {name: mapper, role: write, token: ", kWriteToken, "}\n",
      "  - {name: ops, role: admin, token: ", kAdminToken, "}\n",
      "  - {name: auditor, role: read, sha256: ", kHashedTokenSha256, "}\n");
}

// Everything spdlog writes while the test suite runs, at trace level: the
// daemon's whole log as an operator could configure it.
class LogCapture {
 public:
  LogCapture() {
    sink_ = std::make_shared<spdlog::sinks::ostream_sink_mt>(stream_);
    previous_ = spdlog::default_logger();
    auto logger = std::make_shared<spdlog::logger>("security_test", sink_);
    logger->set_level(spdlog::level::trace);
    spdlog::set_default_logger(logger);
    spdlog::set_level(spdlog::level::trace);
  }
  ~LogCapture() { spdlog::set_default_logger(previous_); }

  std::string text() {
    sink_->flush();
    return stream_.str();
  }

 private:
  std::ostringstream stream_;
  std::shared_ptr<spdlog::sinks::ostream_sink_mt> sink_;
  std::shared_ptr<spdlog::logger> previous_;
};

class SecurityTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    char tmpl[] = "/tmp/pathd_security_test_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = new fs::path(tmpl);
    certs_ = new testing::TestCerts();
    ASSERT_TRUE(testing::MakeTestCerts(*dir_, certs_))
        << "the openssl tool failed (is Debian's openssl package installed?)";
    WriteFile(*dir_ / "tokens.yaml", TokensYaml());
    chmod((*dir_ / "tokens.yaml").c_str(), 0600);
  }

  static void TearDownTestSuite() {
    std::error_code ignored;
    fs::remove_all(*dir_, ignored);
    delete certs_;
    delete dir_;
  }

  void TearDown() override {
    server_.reset();  // shuts down
  }

  // Starts a server with `options` (address, threads and grace filled in);
  // the tests connect with Client(), not the fixture's plaintext stubs.
  absl::Status StartServer(ServerOptions options) {
    options.threads = 2;
    options.shutdown_grace = absl::Seconds(2);
    server_ = std::make_unique<testing::InProcessServer>(std::move(options));
    return server_->Start();
  }

  ServerOptions TlsOptions() const {
    ServerOptions options;
    options.tls_cert = certs_->server_cert;
    options.tls_key = certs_->server_key;
    return options;
  }

  ServerOptions TokenOptions() const {
    ServerOptions options;
    options.auth_tokens = (*dir_ / "tokens.yaml").string();
    return options;
  }

  client::PathdClient Client(const client::ClientCredentials& credentials,
                             const std::string& address = "") const {
    return client::PathdClient(
        client::MakeChannel(
            address.empty() ? server_->listen_address() : address, credentials),
        absl::Seconds(20));
  }

  static client::ClientCredentials Tls(const std::string& ca_file) {
    client::ClientCredentials credentials;
    credentials.tls_ca_pem = ReadFile(ca_file);
    return credentials;
  }

  static client::ClientCredentials WithToken(const std::string& token) {
    client::ClientCredentials credentials;
    credentials.token = token;
    return credentials;
  }

  static v1::CreateMapRequest OpenRoom(const std::string& name) {
    v1::CreateMapRequest request;
    request.set_name(name);
    request.set_movingai_text(kOpenRoom);
    request.set_replace(true);
    return request;
  }

  static v1::PlanRequest PlanAcross(const std::string& map) {
    return testing::PlanBetween(map, 0, 0, 4, 3, v1::PLANNER_UNSPECIFIED);
  }

  static v1::UpdateMapRequest BlockCell(const std::string& map, int x, int y) {
    v1::UpdateMapRequest request;
    request.set_name(map);
    v1::CellChange* change = request.add_changes();
    change->mutable_cell()->set_x(x);
    change->mutable_cell()->set_y(y);
    change->set_cost(254);
    return request;
  }

  static fs::path* dir_;
  static testing::TestCerts* certs_;
  std::unique_ptr<testing::InProcessServer> server_;
};

// One call of any method through the generic stub: one empty request
// message, half-close, read everything, finish. Works for unary and
// streaming methods alike, so the test needs no per-method code.
inline grpc::Status CallGeneric(const std::shared_ptr<grpc::Channel>& channel,
                                const std::string& method, const std::string& token) {
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() +
                       std::chrono::seconds(20));
  if (!token.empty())
    context.AddMetadata("authorization", absl::StrCat("Bearer ", token));
  grpc::CompletionQueue cq;
  auto wait = [&cq] {
    void* tag;
    bool ok = false;
    cq.Next(&tag, &ok);
    return ok;
  };
  std::unique_ptr<grpc::GenericClientAsyncReaderWriter> call =
      stub.PrepareCall(&context, method, &cq);
  call->StartCall(nullptr);
  wait();
  grpc::Slice empty("");
  grpc::ByteBuffer request(&empty, 1);
  call->Write(request, nullptr);
  wait();
  call->WritesDone(nullptr);
  wait();
  grpc::ByteBuffer response;
  do {
    call->Read(&response, nullptr);
  } while (wait());
  grpc::Status status;
  call->Finish(&status, nullptr);
  wait();
  cq.Shutdown();
  void* tag;
  bool ok;
  while (cq.Next(&tag, &ok)) {
  }
  return status;
}


// Every method of the services pathd serves, as "/package.Service/Method".
inline std::vector<std::string> ServedMethods(bool pathd_only) {
  std::vector<std::string> services = {"pathd.v1.MapService",
                                       "pathd.v1.PlannerService"};
  if (!pathd_only) {
    services.push_back("grpc.health.v1.Health");
    services.push_back("grpc.reflection.v1alpha.ServerReflection");
  }
  std::vector<std::string> methods;
  for (const std::string& name : services) {
    const google::protobuf::ServiceDescriptor* service =
        google::protobuf::DescriptorPool::generated_pool()->FindServiceByName(
            name);
    EXPECT_NE(service, nullptr) << name;
    if (service == nullptr) continue;
    for (int i = 0; i < service->method_count(); ++i) {
      methods.push_back(absl::StrCat("/", service->full_name(), "/",
                                     service->method(i)->name()));
    }
  }
  return methods;
}

}  // namespace pathd::server::security_test

#endif  // PATHD_TESTS_SERVER_SECURITY_FIXTURE_H_
