// security_test: tokens and roles on every RPC, typed calls, Navigate's
// shared observations, TLS with tokens, and client credentials.
#include "tests/server/security_fixture.h"

namespace pathd::server::security_test {

TEST_F(SecurityTest, EveryPathdRpcChecksTheTokenAndTheRole) {
  ASSERT_TRUE(StartServer(TokenOptions()).ok());
  const std::shared_ptr<grpc::Channel> channel = client::MakeChannel(
      server_->listen_address(), client::ClientCredentials{});
  const std::vector<std::string> methods = ServedMethods(/*pathd_only=*/true);
  // MapService's 8 (with UploadMap and DownloadMap), PlannerService's 13
  // (with Table, Nearest, Trip, Isochrone, PlanFleet and ListSessions).
  ASSERT_EQ(methods.size(), 21u);
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
  EXPECT_EQ(writes, 4);  // CreateMap, DeleteMap, UpdateMap, UploadMap
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

}  // namespace pathd::server::security_test
