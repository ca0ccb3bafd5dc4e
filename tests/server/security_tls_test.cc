// security_test: the method -> role table, --auth_tokens file parsing, and
// TLS and mutual TLS: who can connect, and bad TLS files at start.
#include "tests/server/security_fixture.h"

namespace pathd::server::security_test {

fs::path* SecurityTest::dir_ = nullptr;
testing::TestCerts* SecurityTest::certs_ = nullptr;

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

}  // namespace pathd::server::security_test
