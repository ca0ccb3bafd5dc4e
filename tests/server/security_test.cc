// TLS, mutual TLS and token authentication against a real PathdServer on
// 127.0.0.1:0, with certificates the test makes with the openssl tool and
// clients built by client::MakeChannel (the channel pathctl uses). The
// method -> role table is checked against the service descriptors, and every
// pathd RPC is called generically so that a new RPC whose handler forgets
// the check fails here.
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

namespace pathd::server {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

// Tokens of the test's --auth_tokens file: 64 hex digits like `openssl rand
// -hex 32`, distinctive enough that finding one in a log is no accident.
constexpr char kReadToken[] =
    "read0123456789abcdef0123456789abcdef0123456789abcdef0123456789";
constexpr char kWriteToken[] =
    "write123456789abcdef0123456789abcdef0123456789abcdef012345678";
constexpr char kAdminToken[] =
    "admin123456789abcdef0123456789abcdef0123456789abcdef012345678";
// Configured by its hash only (sha256 key): printf %s TOKEN | sha256sum.
constexpr char kHashedToken[] =
    "hashed0123456789abcdef0123456789abcdef0123456789abcdef01234567";
constexpr char kHashedTokenSha256[] =
    "49e5477fc3082207401c7b1b018d5ea6f170758c5d13c6d54668129cc932eeea";
constexpr char kWrongToken[] =
    "wrong123456789abcdef0123456789abcdef0123456789abcdef012345678";

constexpr char kOpenRoom[] =
    "type octile\nheight 4\nwidth 5\nmap\n.....\n.....\n.....\n.....\n";

void WriteFile(const fs::path& path, const std::string& contents) {
  std::ofstream out(path, std::ios::binary);
  out << contents;
  ASSERT_TRUE(out.good()) << path;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string TokensYaml() {
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

fs::path* SecurityTest::dir_ = nullptr;
testing::TestCerts* SecurityTest::certs_ = nullptr;

// One call of any method through the generic stub: one empty request
// message, half-close, read everything, finish. Works for unary and
// streaming methods alike, so the test needs no per-method code.
grpc::Status CallGeneric(const std::shared_ptr<grpc::Channel>& channel,
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
std::vector<std::string> ServedMethods(bool pathd_only) {
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

TEST(MethodRoleTable, GivesEveryServedMethodARole) {
  const std::vector<std::string> methods = ServedMethods(/*pathd_only=*/false);
  EXPECT_GE(methods.size(), 13u + 2u + 1u);
  for (const std::string& method : methods) {
    EXPECT_TRUE(RequiredRole(method).has_value())
        << method << " has no role in server/auth.cc kMethodRoles";
  }
  EXPECT_EQ(RequiredRole("/pathd.v1.MapService/NoSuchMethod"), std::nullopt);
  EXPECT_EQ(RequiredRole("/grpc.health.v1.Health/Check"), Role::kPublic);
  EXPECT_EQ(RequiredRole(kMethodUpdateMap), Role::kWrite);
  EXPECT_EQ(RequiredRole(kMethodPlan), Role::kRead);
}

TEST(TokenFile, RejectsMalformedFilesWithoutQuotingTokens) {
  const std::string good = "abcdefghijklmnopqrstuvwxyz0123456789";
  struct Case {
    std::string yaml;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"", "expected a mapping with a 'tokens:' list"},
      {"tokens: []\n", "'tokens' is empty"},
      {"tokens:\n  - {name: a, role: read, token: " + good + "}\nextra: 1\n",
       "unknown key 'extra'"},
      {"tokens:\n  - {role: read, token: " + good + "}\n",
       "tokens[0]: 'name' is missing"},
      {"tokens:\n  - {name: a, token: " + good + "}\n", "'role' is missing"},
      {"tokens:\n  - {name: a, role: root, token: " + good + "}\n",
       "role 'root' is not one of read, write, admin"},
      {"tokens:\n  - {name: a, role: read}\n",
       "exactly one of 'token' and 'sha256'"},
      {"tokens:\n  - {name: a, role: read, token: short}\n",
       "'token' is 5 characters; use at least 16"},
      {"tokens:\n  - {name: a, role: read, token: \"" + good + " x\"}\n",
       "only visible ASCII"},
      {"tokens:\n  - {name: a, role: read, sha256: abc}\n", "64 hex digits"},
      {"tokens:\n  - {name: a, role: read, token: " + good + ", colour: red}\n",
       "unknown key 'colour'"},
      {"tokens:\n  - {name: a, role: read, token: " + good +
           "}\n  - {name: a, role: write, token: " + good + "x}\n",
       "tokens[1]: name 'a' is used twice"},
      {"tokens:\n  - {name: a, role: read, token: " + good +
           "}\n  - {name: b, role: write, token: " + good + "}\n",
       "tokens[1]: same token as 'a'"},
      {"tokens: [\n", "invalid YAML"},
  };
  for (const Case& c : cases) {
    const auto parsed = TokenAuthenticator::Parse(c.yaml, "tokens.yaml");
    ASSERT_FALSE(parsed.ok()) << c.yaml;
    EXPECT_EQ(parsed.status().code(), absl::StatusCode::kInvalidArgument)
        << c.yaml;
    EXPECT_THAT(std::string(parsed.status().message()), HasSubstr(c.message))
        << c.yaml;
    EXPECT_THAT(std::string(parsed.status().message()),
                HasSubstr("tokens.yaml"));
    EXPECT_THAT(std::string(parsed.status().message()), Not(HasSubstr(good)));
  }
  // The sha256 form: sha256sum of the token, so the file holds no secret.
  // printf %s abcdefghijklmnopqrstuvwxyz0123456789 | sha256sum
  const auto hashed = TokenAuthenticator::Parse(
      "tokens:\n  - name: hashed\n    role: write\n    sha256: "
      "011fc2994e39d251141540f87a69092b3f22a86767f7283de7eeedb3897bedf6\n",
      "tokens.yaml");
  ASSERT_TRUE(hashed.ok()) << hashed.status();
  ASSERT_EQ((*hashed)->entries().size(), 1u);
  EXPECT_EQ((*hashed)->entries()[0].role, Role::kWrite);
}

TEST_F(SecurityTest, TlsServesPlansAndHealth) {
  ASSERT_TRUE(StartServer(TlsOptions()).ok());
  const client::PathdClient client = Client(Tls(certs_->ca));
  ASSERT_TRUE(client.CreateMap(OpenRoom("room")).ok());
  const absl::StatusOr<v1::PlanResponse> plan = client.Plan(PlanAcross("room"));
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_TRUE(plan->found());
  const auto health = client.CheckHealth();
  ASSERT_TRUE(health.ok()) << health.status();
  EXPECT_EQ(health->status(), grpc::health::v1::HealthCheckResponse::SERVING);
  // The certificate names localhost too.
  const std::string localhost = absl::StrCat("localhost:", server_->port());
  EXPECT_TRUE(Client(Tls(certs_->ca), localhost).ListMaps().ok());
}

TEST_F(SecurityTest, PlaintextClientCannotTalkToATlsServer) {
  ASSERT_TRUE(StartServer(TlsOptions()).ok());
  const absl::Status status = Client({}).ListMaps().status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnavailable) << status;
  EXPECT_EQ(Client({}).CheckHealth().status().code(),
            absl::StatusCode::kUnavailable);
}

TEST_F(SecurityTest, ServerSignedByAnotherCaIsRefused) {
  ASSERT_TRUE(StartServer(TlsOptions()).ok());
  const absl::Status status = Client(Tls(certs_->other_ca)).ListMaps().status();
  EXPECT_EQ(status.code(), absl::StatusCode::kUnavailable) << status;
}

TEST_F(SecurityTest, ServerNameOverrideAcceptsACertificateForAnotherName) {
  ServerOptions options;
  options.tls_cert = certs_->other_name_cert;  // says pathd.test only
  options.tls_key = certs_->other_name_key;
  ASSERT_TRUE(StartServer(options).ok());
  EXPECT_EQ(Client(Tls(certs_->ca)).ListMaps().status().code(),
            absl::StatusCode::kUnavailable);
  client::ClientCredentials credentials = Tls(certs_->ca);
  credentials.tls_server_name = "pathd.test";
  const absl::Status status = Client(credentials).ListMaps().status();
  EXPECT_TRUE(status.ok()) << status;
}

TEST_F(SecurityTest, MutualTlsRequiresAClientCertificateFromTheClientCa) {
  ServerOptions options = TlsOptions();
  options.tls_client_ca = certs_->ca;
  ASSERT_TRUE(StartServer(options).ok());

  EXPECT_EQ(Client(Tls(certs_->ca)).ListMaps().status().code(),
            absl::StatusCode::kUnavailable);

  client::ClientCredentials intruder = Tls(certs_->ca);
  intruder.tls_cert_pem = ReadFile(certs_->other_client_cert);
  intruder.tls_key_pem = ReadFile(certs_->other_client_key);
  EXPECT_EQ(Client(intruder).ListMaps().status().code(),
            absl::StatusCode::kUnavailable);

  client::ClientCredentials robot = Tls(certs_->ca);
  robot.tls_cert_pem = ReadFile(certs_->client_cert);
  robot.tls_key_pem = ReadFile(certs_->client_key);
  const client::PathdClient client = Client(robot);
  ASSERT_TRUE(client.CreateMap(OpenRoom("room")).ok());
  const auto plan = client.Plan(PlanAcross("room"));
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_TRUE(plan->found());
}

TEST_F(SecurityTest, BadTlsFilesFailStartNamingFlagAndFile) {
  struct Case {
    std::string cert, key, client_ca;
    absl::StatusCode code;
    std::string message;
  };
  const std::string missing = (*dir_ / "missing.pem").string();
  const std::vector<Case> cases = {
      {certs_->server_cert, "", "", absl::StatusCode::kInvalidArgument,
       "--tls_cert and --tls_key must be given together"},
      {"", "", certs_->ca, absl::StatusCode::kInvalidArgument,
       "--tls_client_ca needs --tls_cert"},
      {missing, certs_->server_key, "", absl::StatusCode::kNotFound, missing},
      {certs_->server_key, certs_->server_key, "",
       absl::StatusCode::kInvalidArgument, "holds no PEM certificate"},
      {certs_->server_cert, certs_->server_cert, "",
       absl::StatusCode::kInvalidArgument,
       "holds no unencrypted PEM private key"},
      {certs_->server_cert, certs_->client_key, "",
       absl::StatusCode::kInvalidArgument, "is not the key of the certificate"},
      {certs_->server_cert, certs_->server_key, certs_->server_key,
       absl::StatusCode::kInvalidArgument, "--tls_client_ca"},
  };
  for (const Case& c : cases) {
    ServerOptions options;
    options.tls_cert = c.cert;
    options.tls_key = c.key;
    options.tls_client_ca = c.client_ca;
    const absl::Status status = StartServer(options);
    EXPECT_EQ(status.code(), c.code) << status;
    EXPECT_THAT(std::string(status.message()), HasSubstr(c.message));
  }
}

TEST_F(SecurityTest, EveryPathdRpcChecksTheTokenAndTheRole) {
  ASSERT_TRUE(StartServer(TokenOptions()).ok());
  const std::shared_ptr<grpc::Channel> channel = client::MakeChannel(
      server_->listen_address(), client::ClientCredentials{});
  const std::vector<std::string> methods = ServedMethods(/*pathd_only=*/true);
  ASSERT_EQ(methods.size(), 13u);
  int writes = 0;
  for (const std::string& method : methods) {
    SCOPED_TRACE(method);
    const grpc::Status none = CallGeneric(channel, method, "");
    EXPECT_EQ(none.error_code(), grpc::StatusCode::UNAUTHENTICATED)
        << none.error_message();
    const grpc::Status wrong = CallGeneric(channel, method, kWrongToken);
    EXPECT_EQ(wrong.error_code(), grpc::StatusCode::UNAUTHENTICATED);
    EXPECT_THAT(wrong.error_message(), Not(HasSubstr(kWrongToken)));

    const grpc::Status read = CallGeneric(channel, method, kReadToken);
    if (RequiredRole(method) == Role::kWrite) {
      ++writes;
      EXPECT_EQ(read.error_code(), grpc::StatusCode::PERMISSION_DENIED);
      EXPECT_EQ(read.error_message(),
                absl::StrCat("token 'robot-7' has role read; ", method,
                             " needs role write"));
    } else {
      EXPECT_NE(read.error_code(), grpc::StatusCode::UNAUTHENTICATED);
      EXPECT_NE(read.error_code(), grpc::StatusCode::PERMISSION_DENIED);
    }
    for (const char* token : {kWriteToken, kAdminToken}) {
      const grpc::Status allowed = CallGeneric(channel, method, token);
      EXPECT_NE(allowed.error_code(), grpc::StatusCode::UNAUTHENTICATED);
      EXPECT_NE(allowed.error_code(), grpc::StatusCode::PERMISSION_DENIED)
          << allowed.error_message();
    }
  }
  EXPECT_EQ(writes, 3);  // CreateMap, DeleteMap, UpdateMap
}

TEST_F(SecurityTest, RolesGovernTypedCallsAndHealthNeedsNoToken) {
  LogCapture log;
  ASSERT_TRUE(StartServer(TokenOptions()).ok());
  const client::PathdClient anonymous = Client({});
  const client::PathdClient robot = Client(WithToken(kReadToken));
  const client::PathdClient mapper = Client(WithToken(kWriteToken));
  const client::PathdClient ops = Client(WithToken(kAdminToken));

  // Probes work without a secret.
  const auto health = anonymous.CheckHealth();
  ASSERT_TRUE(health.ok()) << health.status();
  EXPECT_EQ(health->status(), grpc::health::v1::HealthCheckResponse::SERVING);

  EXPECT_EQ(anonymous.ListMaps().status().code(),
            absl::StatusCode::kUnauthenticated);
  EXPECT_EQ(robot.CreateMap(OpenRoom("room")).status().code(),
            absl::StatusCode::kPermissionDenied);
  ASSERT_TRUE(mapper.CreateMap(OpenRoom("room")).ok());

  const auto plan = robot.Plan(PlanAcross("room"));
  ASSERT_TRUE(plan.ok()) << plan.status();
  EXPECT_TRUE(plan->found());
  const client::PathdClient auditor = Client(WithToken(kHashedToken));
  EXPECT_TRUE(auditor.Plan(PlanAcross("room")).ok());
  EXPECT_THAT(std::string(auditor.DeleteMap("room").status().message()),
              HasSubstr("token 'auditor' has role read"));
  const absl::Status denied = robot.UpdateMap(BlockCell("room", 2, 2)).status();
  EXPECT_EQ(denied.code(), absl::StatusCode::kPermissionDenied);
  EXPECT_EQ(
      denied.message(),
      "token 'robot-7' has role read; /pathd.v1.MapService/UpdateMap needs "
      "role write");
  const auto updated = mapper.UpdateMap(BlockCell("room", 2, 2));
  ASSERT_TRUE(updated.ok()) << updated.status();
  EXPECT_EQ(updated->version(), 2u);

  // Streams carry the token too.
  {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() +
                         std::chrono::seconds(20));
    auto stream = robot.PlanStream(&context, PlanAcross("room"));
    v1::PlanStreamEvent event;
    while (stream->Read(&event)) {
    }
    const grpc::Status status = stream->Finish();
    EXPECT_TRUE(status.ok()) << status.error_message();
    EXPECT_TRUE(event.has_result() && event.result().found());
  }

  EXPECT_TRUE(ops.GetCacheStats().ok());
  EXPECT_TRUE(ops.DeleteMap("room").ok());

  const std::string text = log.text();
  EXPECT_THAT(text, HasSubstr("refused UpdateMap"));
  EXPECT_THAT(text,
              HasSubstr("rpc=UpdateMap map=room"));  // the request log runs
  for (const char* token :
       {kReadToken, kWriteToken, kAdminToken, kHashedToken}) {
    EXPECT_THAT(text, Not(HasSubstr(token)));
  }
}

TEST_F(SecurityTest, NavigateSharedObservationsNeedTheWriteRole) {
  ASSERT_TRUE(StartServer(TokenOptions()).ok());
  ASSERT_TRUE(Client(WithToken(kWriteToken)).CreateMap(OpenRoom("room")).ok());

  // Sends open + one observation; returns the status the session ends with
  // and how many answers came back.
  auto navigate = [this](const std::string& token, bool session_only,
                         int* answers) {
    const client::PathdClient client = Client(WithToken(token));
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() +
                         std::chrono::seconds(20));
    auto stream = client.Navigate(&context, "room");
    v1::NavigateRequest open;
    open.set_seq(1);
    open.mutable_open()->set_map("room");
    *open.mutable_open()->mutable_start() = PlanAcross("room").start();
    *open.mutable_open()->mutable_goal() = PlanAcross("room").goal();
    v1::NavigateRequest observe;
    observe.set_seq(2);
    observe.mutable_observe()->set_session_only(session_only);
    *observe.mutable_observe()->add_changes() =
        BlockCell("room", 1, 1).changes(0);
    v1::NavigateResponse response;
    *answers = 0;
    if (stream->Write(open) && stream->Read(&response)) ++*answers;
    if (stream->Write(observe) && stream->Read(&response)) ++*answers;
    stream->WritesDone();
    while (stream->Read(&response)) ++*answers;
    return stream->Finish();
  };
  int answers = 0;
  grpc::Status status = navigate(kReadToken, /*session_only=*/true, &answers);
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(answers, 2);

  status = navigate(kReadToken, /*session_only=*/false, &answers);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_THAT(status.error_message(),
              HasSubstr("token 'robot-7' has role read"));
  EXPECT_THAT(status.error_message(),
              HasSubstr("observation shared with the map"));
  EXPECT_EQ(answers, 1);  // opened, then refused
  const auto map = Client(WithToken(kReadToken)).GetMap([] {
    v1::GetMapRequest request;
    request.set_name("room");
    return request;
  }());
  ASSERT_TRUE(map.ok());
  EXPECT_EQ(map->info().version(), 1u)
      << "a refused observation changed the map";

  status = navigate(kWriteToken, /*session_only=*/false, &answers);
  EXPECT_TRUE(status.ok()) << status.error_message();
  EXPECT_EQ(answers, 2);
}

TEST_F(SecurityTest, TlsAndTokensTogether) {
  ServerOptions options = TlsOptions();
  options.auth_tokens = TokenOptions().auth_tokens;
  ASSERT_TRUE(StartServer(options).ok());
  client::ClientCredentials credentials = Tls(certs_->ca);
  credentials.token = kWriteToken;
  const client::PathdClient client = Client(credentials);
  ASSERT_TRUE(client.CreateMap(OpenRoom("room")).ok());
  EXPECT_TRUE(client.Plan(PlanAcross("room")).ok());
  EXPECT_EQ(Client(Tls(certs_->ca)).ListMaps().status().code(),
            absl::StatusCode::kUnauthenticated);
}

TEST_F(SecurityTest, WorldReadableTokenFileIsLoadedWithAWarning) {
  const fs::path file = *dir_ / "open_tokens.yaml";
  WriteFile(file, TokensYaml());
  chmod(file.c_str(), 0644);
  LogCapture log;
  ServerOptions options;
  options.auth_tokens = file.string();
  ASSERT_TRUE(StartServer(options).ok());
  EXPECT_THAT(log.text(), HasSubstr("is readable by every user (mode 644)"));
  ServerOptions missing;
  missing.auth_tokens = (*dir_ / "no_such_tokens.yaml").string();
  const absl::Status status = StartServer(missing);
  EXPECT_EQ(status.code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(status.message()), HasSubstr("--auth_tokens"));
}

TEST(ClientCredentials, LoadChecksFlagCombinationsAndReadsFiles) {
  client::CredentialSources sources;
  sources.tls_cert = "client.crt";
  EXPECT_THAT(
      std::string(client::LoadClientCredentials(sources).status().message()),
      HasSubstr("--tls_cert and --tls_key must be given together"));
  sources.tls_key = "client.key";
  EXPECT_THAT(
      std::string(client::LoadClientCredentials(sources).status().message()),
      HasSubstr("--tls_cert needs --tls_ca"));
  client::CredentialSources name_only;
  name_only.tls_server_name = "pathd.test";
  EXPECT_THAT(
      std::string(client::LoadClientCredentials(name_only).status().message()),
      HasSubstr("--tls_server_name needs --tls_ca"));
  client::CredentialSources both;
  both.token = kReadToken;
  both.token_file = "token";
  EXPECT_EQ(client::LoadClientCredentials(both).status().code(),
            absl::StatusCode::kInvalidArgument);
  client::CredentialSources spaced;
  spaced.token = "two words";
  const absl::Status bad = client::LoadClientCredentials(spaced).status();
  EXPECT_THAT(std::string(bad.message()), HasSubstr("visible ASCII"));
  EXPECT_THAT(std::string(bad.message()), Not(HasSubstr("two words")));

  char tmpl[] = "/tmp/pathd_credentials_XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const fs::path dir = tmpl;
  WriteFile(dir / "token", absl::StrCat("  ", kReadToken, "\n"));
  client::CredentialSources from_file;
  from_file.token_file = (dir / "token").string();
  const auto loaded = client::LoadClientCredentials(from_file);
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_EQ(loaded->token, kReadToken);
  from_file.token_file = (dir / "missing").string();
  EXPECT_EQ(client::LoadClientCredentials(from_file).status().code(),
            absl::StatusCode::kNotFound);
  fs::remove_all(dir);

  EXPECT_TRUE(client::IsLoopbackAddress("127.0.0.1:50051"));
  EXPECT_TRUE(client::IsLoopbackAddress("localhost:50051"));
  EXPECT_TRUE(client::IsLoopbackAddress("[::1]:50051"));
  EXPECT_TRUE(client::IsLoopbackAddress("unix:/run/pathd.sock"));
  EXPECT_FALSE(client::IsLoopbackAddress("10.0.0.7:50051"));
  EXPECT_FALSE(client::IsLoopbackAddress("pathd.internal:50051"));
}

}  // namespace
}  // namespace pathd::server
