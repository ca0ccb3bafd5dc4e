// Token authentication and role-based authorization of pathd's RPCs
// (--auth_tokens). The method -> role table in auth.cc is the single source
// of truth for which role each RPC needs; every pathd handler starts with
// RefuseUnauthorized, and security_test (tests/server/security_*_test.cc)
// proves that every method of the service descriptors has a role and is
// refused without one.
#ifndef PATHD_SERVER_AUTH_H_
#define PATHD_SERVER_AUTH_H_

#include <grpcpp/server_context.h>
#include <grpcpp/support/server_callback.h>

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "server/grpc_status.h"
#include "server/request_log.h"

namespace pathd::server {

// Ordered: each role may do everything the roles before it may.
enum class Role {
  // Needs no token (health probes, reflection).
  kPublic = 0,
  // Plan, inspect and watch maps.
  kRead = 1,
  // Also create, update and delete maps.
  kWrite = 2,
  // Everything; no RPC needs more than write today.
  kAdmin = 3,
};

// "public", "read", "write", "admin".
std::string_view RoleName(Role role);

// The full gRPC method names ("/package.Service/Method") the handlers pass
// to RefuseUnauthorized.
inline constexpr char kMethodCreateMap[] = "/pathd.v1.MapService/CreateMap";
inline constexpr char kMethodGetMap[] = "/pathd.v1.MapService/GetMap";
inline constexpr char kMethodListMaps[] = "/pathd.v1.MapService/ListMaps";
inline constexpr char kMethodDeleteMap[] = "/pathd.v1.MapService/DeleteMap";
inline constexpr char kMethodUpdateMap[] = "/pathd.v1.MapService/UpdateMap";
inline constexpr char kMethodWatchMap[] = "/pathd.v1.MapService/WatchMap";
inline constexpr char kMethodUploadMap[] = "/pathd.v1.MapService/UploadMap";
inline constexpr char kMethodDownloadMap[] = "/pathd.v1.MapService/DownloadMap";
inline constexpr char kMethodPlan[] = "/pathd.v1.PlannerService/Plan";
inline constexpr char kMethodCostToGo[] = "/pathd.v1.PlannerService/CostToGo";
inline constexpr char kMethodNavigate[] = "/pathd.v1.PlannerService/Navigate";
inline constexpr char kMethodGetCacheStats[] =
    "/pathd.v1.PlannerService/GetCacheStats";
inline constexpr char kMethodIsPathValid[] =
    "/pathd.v1.PlannerService/IsPathValid";
inline constexpr char kMethodPlanStream[] =
    "/pathd.v1.PlannerService/PlanStream";
inline constexpr char kMethodPlanBatch[] = "/pathd.v1.PlannerService/PlanBatch";
inline constexpr char kMethodTable[] = "/pathd.v1.PlannerService/Table";
inline constexpr char kMethodNearest[] = "/pathd.v1.PlannerService/Nearest";
inline constexpr char kMethodTrip[] = "/pathd.v1.PlannerService/Trip";
inline constexpr char kMethodIsochrone[] = "/pathd.v1.PlannerService/Isochrone";
inline constexpr char kMethodPlanFleet[] = "/pathd.v1.PlannerService/PlanFleet";
inline constexpr char kMethodListSessions[] =
    "/pathd.v1.PlannerService/ListSessions";
// Not an RPC: a Navigate observation with session_only = false writes the
// shared map like UpdateMap, so it needs the role UpdateMap needs.
inline constexpr char kNavigateSharedObservation[] =
    "/pathd.v1.PlannerService/Navigate (observation shared with the map)";

// The role `method` needs; nullopt for a method the table does not know
// (refused: a new RPC must be given a role before anyone may call it).
std::optional<Role> RequiredRole(std::string_view method);

// One configured token. Only the SHA-256 of the token is kept.
struct TokenEntry {
  // Shown in logs and PERMISSION_DENIED messages instead of the token.
  std::string name;
  Role role = Role::kRead;
  std::array<uint8_t, 32> sha256{};
};

// The tokens of an --auth_tokens file. Immutable after loading, so
// thread-safe.
class TokenAuthenticator {
 public:
  // Parses the YAML token file text (format in docs/security.md): a
  // top-level `tokens:` list of {name, role, token | sha256}. INVALID_ARGUMENT
  // naming `source`, the entry (tokens[i]) and the key for a malformed file,
  // an unknown role or key, a token shorter than 16 characters or with
  // characters a header cannot carry, a duplicate name or token, or no tokens.
  // Messages never contain a token.
  static absl::StatusOr<std::unique_ptr<TokenAuthenticator>> Parse(
      std::string_view yaml, std::string_view source);
  // Reads and parses `path`; warns (log) when the file is world-readable.
  static absl::StatusOr<std::unique_ptr<TokenAuthenticator>> LoadFile(
      const std::string& path);

  // The entry whose token the call presents in "authorization: Bearer
  // <token>" metadata. UNAUTHENTICATED when the metadata is missing, repeated,
  // not a Bearer token or an unknown token. Compares SHA-256 digests with
  // CRYPTO_memcmp against every entry, so the time taken depends neither on
  // the token's content nor on its length or which entry matched first.
  absl::StatusOr<const TokenEntry*> Authenticate(
      const grpc::ServerContextBase& context) const;

  // Authenticate, then PERMISSION_DENIED "token 'NAME' has role R; METHOD
  // needs role W" when the token's role is below the method's. Public methods
  // pass without a token.
  absl::Status Authorize(const grpc::ServerContextBase& context,
                         std::string_view method) const;

  const std::vector<TokenEntry>& entries() const { return entries_; }

  // Bounds the log lines of calls this authenticator refused (see
  // internal::LogRefusal). Thread-safe, so usable through a const object.
  LogRateLimiter& refusal_log() const { return refusal_log_; }

 private:
  explicit TokenAuthenticator(std::vector<TokenEntry> entries)
      : entries_(std::move(entries)) {}

  std::vector<TokenEntry> entries_;
  mutable LogRateLimiter refusal_log_{absl::Seconds(1)};
};

// `auth->Authorize(context, method)`, or OK when `auth` is null (no
// --auth_tokens: every caller may do everything).
absl::Status Authorize(const TokenAuthenticator* auth,
                       const grpc::ServerContextBase& context,
                       std::string_view method);

namespace internal {

// A stream reactor that only finishes the call with a status.
template <typename Reactor>
class RefusedReactor final : public Reactor {
 public:
  // gRPC queues operations started before the reactor is bound to the call,
  // so finishing in the constructor is allowed.
  explicit RefusedReactor(const grpc::Status& status) { this->Finish(status); }
  void OnDone() override { delete this; }
};

// Logs a call `auth` refused through the request log (never the token), at
// most one line per second per reason (auth.refusal_log()), with the count of
// the lines held back.
void LogRefusal(const TokenAuthenticator& auth, std::string_view method,
                const grpc::ServerContextBase& context, const absl::Status& status);

}  // namespace internal

// The first statement of every pathd handler: null when the call may go on,
// otherwise a reactor that has already finished the call with
// UNAUTHENTICATED or PERMISSION_DENIED (logged). `Reactor` is the handler's
// return type (grpc::ServerUnaryReactor, ServerWriteReactor<T>,
// ServerBidiReactor<Q, R>).
template <typename Reactor = grpc::ServerUnaryReactor>
Reactor* RefuseUnauthorized(const TokenAuthenticator* auth,
                            grpc::CallbackServerContext* context,
                            std::string_view method) {
  const absl::Status status = Authorize(auth, *context, method);
  if (status.ok()) return nullptr;
  // Not OK implies an authenticator.
  internal::LogRefusal(*auth, method, *context, status);
  if constexpr (std::is_same_v<Reactor, grpc::ServerUnaryReactor>) {
    grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
    reactor->Finish(ToGrpcStatus(status));
    return reactor;
  } else {
    return new internal::RefusedReactor<Reactor>(ToGrpcStatus(status));
  }
}

}  // namespace pathd::server

#endif  // PATHD_SERVER_AUTH_H_
