// Token file parsing, constant-time token lookup and the method -> role table.
#include "server/auth.h"

#include <openssl/crypto.h>
#include <openssl/sha.h>
#include <sys/stat.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <optional>
#include <set>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/time/clock.h"
#include "core/map_io/map_io.h"
#include "server/request_log.h"
#include "spdlog/spdlog.h"

namespace pathd::server {
namespace {

struct MethodRole {
  std::string_view method;
  Role role;
};

// Which role each method needs. The gRPC health service and reflection are
// served by gRPC itself, so no pathd handler checks them; they are listed as
// public so that this table describes every method the server answers.
// Health is public so container and load-balancer probes need no secret;
// reflection only describes the published .proto schema.
constexpr MethodRole kMethodRoles[] = {
    {kMethodCreateMap, Role::kWrite},
    {kMethodGetMap, Role::kRead},
    {kMethodListMaps, Role::kRead},
    {kMethodDeleteMap, Role::kWrite},
    {kMethodUpdateMap, Role::kWrite},
    {kMethodWatchMap, Role::kRead},
    {kMethodUploadMap, Role::kWrite},
    {kMethodDownloadMap, Role::kRead},
    {kMethodPlan, Role::kRead},
    {kMethodCostToGo, Role::kRead},
    // Opening a session and session_only observations change nothing shared.
    {kMethodNavigate, Role::kRead},
    {kNavigateSharedObservation, Role::kWrite},
    {kMethodGetCacheStats, Role::kRead},
    {kMethodIsPathValid, Role::kRead},
    {kMethodPlanStream, Role::kRead},
    {kMethodPlanBatch, Role::kRead},
    {kMethodTable, Role::kRead},
    {kMethodNearest, Role::kRead},
    {kMethodTrip, Role::kRead},
    {kMethodIsochrone, Role::kRead},
    {kMethodPlanFleet, Role::kRead},
    {kMethodListSessions, Role::kRead},
    {"/grpc.health.v1.Health/Check", Role::kPublic},
    {"/grpc.health.v1.Health/Watch", Role::kPublic},
    {"/grpc.reflection.v1alpha.ServerReflection/ServerReflectionInfo",
     Role::kPublic},
};

// Shorter tokens could be guessed by a client allowed to try many times.
constexpr size_t kMinTokenLength = 16;
constexpr char kAuthorizationKey[] = "authorization";
constexpr char kBearerPrefix[] = "bearer ";

std::array<uint8_t, 32> Sha256(std::string_view text) {
  std::array<uint8_t, 32> digest;
  SHA256(reinterpret_cast<const unsigned char*>(text.data()), text.size(),
         digest.data());
  return digest;
}

// Visible ASCII: what an HTTP/2 header value and a Bearer token can carry
// without quoting, so a token accepted here is one a client can send.
bool IsTokenText(std::string_view token) {
  for (const char c : token) {
    if (c < 0x21 || c > 0x7e) return false;
  }
  return !token.empty();
}

std::optional<Role> ParseRole(std::string_view text) {
  if (text == "read") return Role::kRead;
  if (text == "write") return Role::kWrite;
  if (text == "admin") return Role::kAdmin;
  return std::nullopt;
}

int LineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() || mark.line < 0 ? 0 : mark.line + 1;
}

absl::Status EntryError(std::string_view source, size_t index,
                        const YAML::Node& node, const std::string& problem) {
  return absl::InvalidArgumentError(
      absl::StrFormat("%s:%d: tokens[%d]: %s", std::string(source),
                      LineOf(node), index, problem));
}

absl::StatusOr<TokenEntry> ParseEntry(std::string_view source, size_t index,
                                      const YAML::Node& node) {
  if (!node.IsMap()) {
    return EntryError(source, index, node,
                      "expected a mapping {name: ..., role: ..., token: ...}");
  }
  TokenEntry entry;
  std::optional<std::string> token;
  std::optional<std::string> sha256_hex;
  bool has_role = false;
  for (const auto& field : node) {
    const std::string key = field.first.Scalar();
    const YAML::Node& value = field.second;
    if (!value.IsScalar()) {
      return EntryError(source, index, value,
                        absl::StrCat("key '", key, "' must be a single value"));
    }
    if (key == "name") {
      entry.name = value.Scalar();
    } else if (key == "role") {
      const std::optional<Role> role = ParseRole(value.Scalar());
      if (!role.has_value()) {
        return EntryError(source, index, value,
                          absl::StrCat("role '", value.Scalar(),
                                       "' is not one of read, write, admin"));
      }
      entry.role = *role;
      has_role = true;
    } else if (key == "token") {
      token = value.Scalar();
    } else if (key == "sha256") {
      sha256_hex = value.Scalar();
    } else {
      return EntryError(
          source, index, field.first,
          absl::StrCat("unknown key '", key,
                       "' (expected name, role, token or sha256)"));
    }
  }
  if (entry.name.empty())
    return EntryError(source, index, node, "'name' is missing");
  if (!has_role) return EntryError(source, index, node, "'role' is missing");
  if (token.has_value() == sha256_hex.has_value()) {
    return EntryError(source, index, node,
                      "give exactly one of 'token' and 'sha256'");
  }
  if (token.has_value()) {
    // The messages describe the token but never quote it.
    if (!IsTokenText(*token)) {
      return EntryError(source, index, node,
                        "'token' may hold only visible ASCII characters (no "
                        "spaces)");
    }
    if (token->size() < kMinTokenLength) {
      return EntryError(
          source, index, node,
          absl::StrFormat("'token' is %d characters; use at least %d (e.g. "
                          "openssl rand -hex 32)",
                          token->size(), kMinTokenLength));
    }
    entry.sha256 = Sha256(*token);
  } else {
    std::string bytes;
    if (sha256_hex->size() != 64 ||
        !std::all_of(sha256_hex->begin(), sha256_hex->end(),
                     [](char c) { return absl::ascii_isxdigit(c); })) {
      return EntryError(source, index, node,
                        "'sha256' must be 64 hex digits (sha256sum of the "
                        "token)");
    }
    bytes = absl::HexStringToBytes(*sha256_hex);
    std::copy(bytes.begin(), bytes.end(), entry.sha256.begin());
  }
  return entry;
}

absl::StatusOr<std::vector<TokenEntry>> ParseEntriesOrThrow(
    std::string_view yaml, std::string_view source) {
  const YAML::Node root = YAML::Load(std::string(yaml));
  if (!root.IsMap() || !root["tokens"] || !root["tokens"].IsSequence()) {
    return absl::InvalidArgumentError(absl::StrCat(
        std::string(source),
        ": expected a mapping with a 'tokens:' list of {name, role, "
        "token} entries"));
  }
  for (const auto& field : root) {
    if (field.first.Scalar() != "tokens") {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s:%d: unknown key '%s' (expected only 'tokens')",
          std::string(source), LineOf(field.first), field.first.Scalar()));
    }
  }
  const YAML::Node list = root["tokens"];
  if (list.size() == 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(std::string(source),
                     ": 'tokens' is empty; every call would be refused"));
  }
  std::vector<TokenEntry> entries;
  std::set<std::string> names;
  for (size_t i = 0; i < list.size(); ++i) {
    absl::StatusOr<TokenEntry> entry = ParseEntry(source, i, list[i]);
    if (!entry.ok()) return entry.status();
    if (!names.insert(entry->name).second) {
      return EntryError(source, i, list[i],
                        absl::StrCat("name '", entry->name, "' is used twice"));
    }
    for (const TokenEntry& other : entries) {
      if (other.sha256 == entry->sha256) {
        return EntryError(source, i, list[i],
                          absl::StrCat("same token as '", other.name,
                                       "' (a token must map to one role)"));
      }
    }
    entries.push_back(*std::move(entry));
  }
  return entries;
}

}  // namespace

std::string_view RoleName(Role role) {
  switch (role) {
    case Role::kPublic:
      return "public";
    case Role::kRead:
      return "read";
    case Role::kWrite:
      return "write";
    case Role::kAdmin:
      return "admin";
  }
  return "unknown";
}

std::optional<Role> RequiredRole(std::string_view method) {
  for (const MethodRole& entry : kMethodRoles) {
    if (entry.method == method) return entry.role;
  }
  return std::nullopt;
}

absl::StatusOr<std::unique_ptr<TokenAuthenticator>> TokenAuthenticator::Parse(
    std::string_view yaml, std::string_view source) {
  absl::StatusOr<std::vector<TokenEntry>> entries;
  try {
    entries = ParseEntriesOrThrow(yaml, source);
  } catch (const YAML::Exception& e) {
    // yaml-cpp's messages describe the syntax, not the scalar values.
    return absl::InvalidArgumentError(
        absl::StrFormat("%s:%d: invalid YAML: %s", std::string(source),
                        e.mark.is_null() ? 0 : e.mark.line + 1, e.msg));
  }
  if (!entries.ok()) return entries.status();
  return std::unique_ptr<TokenAuthenticator>(
      new TokenAuthenticator(*std::move(entries)));
}

absl::StatusOr<std::unique_ptr<TokenAuthenticator>>
TokenAuthenticator::LoadFile(const std::string& path) {
  absl::StatusOr<std::string> text = ReadFileToString(path);
  if (!text.ok()) {
    return absl::Status(
        text.status().code(),
        absl::StrCat("--auth_tokens: ", text.status().message()));
  }
  struct stat info;
  if (stat(path.c_str(), &info) == 0 && (info.st_mode & S_IROTH) != 0) {
    spdlog::warn(
        "--auth_tokens file {} is readable by every user (mode {:o}); "
        "chmod o-r it",
        path, info.st_mode & 0777);
  }
  return Parse(*text, path);
}

absl::StatusOr<const TokenEntry*> TokenAuthenticator::Authenticate(
    const grpc::ServerContextBase& context) const {
  const auto& metadata = context.client_metadata();
  const auto [first, last] = metadata.equal_range(kAuthorizationKey);
  if (first == last) {
    return absl::UnauthenticatedError(
        "missing 'authorization: Bearer <token>' metadata (this pathd runs "
        "with --auth_tokens)");
  }
  if (std::next(first) != last) {
    return absl::UnauthenticatedError(
        "more than one 'authorization' metadata entry");
  }
  std::string_view value(first->second.data(), first->second.size());
  if (value.size() < sizeof(kBearerPrefix) - 1 ||
      !absl::EqualsIgnoreCase(
          std::string(value.substr(0, sizeof(kBearerPrefix) - 1)),
          kBearerPrefix)) {
    return absl::UnauthenticatedError(
        "'authorization' metadata is not 'Bearer <token>'");
  }
  value.remove_prefix(sizeof(kBearerPrefix) - 1);
  // Hashing first makes every comparison the same 32 bytes whatever the
  // presented length; every entry is compared so the match position does not
  // show in the time either.
  const std::array<uint8_t, 32> digest = Sha256(value);
  const TokenEntry* match = nullptr;
  for (const TokenEntry& entry : entries_) {
    const bool equal =
        CRYPTO_memcmp(digest.data(), entry.sha256.data(), digest.size()) == 0;
    if (equal) match = &entry;
  }
  if (match == nullptr) return absl::UnauthenticatedError("unknown token");
  return match;
}

absl::Status TokenAuthenticator::Authorize(
    const grpc::ServerContextBase& context, std::string_view method) const {
  const std::optional<Role> needed = RequiredRole(method);
  if (!needed.has_value()) {
    // Fail closed: a method nobody gave a role is callable by nobody.
    return absl::PermissionDeniedError(absl::StrCat(
        std::string(method), " has no role in pathd's method table"));
  }
  if (*needed == Role::kPublic) return absl::OkStatus();
  absl::StatusOr<const TokenEntry*> entry = Authenticate(context);
  if (!entry.ok()) return entry.status();
  if ((*entry)->role < *needed) {
    return absl::PermissionDeniedError(absl::StrCat(
        "token '", (*entry)->name, "' has role ",
        std::string(RoleName((*entry)->role)), "; ", std::string(method),
        " needs role ", std::string(RoleName(*needed))));
  }
  return absl::OkStatus();
}

absl::Status Authorize(const TokenAuthenticator* auth,
                       const grpc::ServerContextBase& context,
                       std::string_view method) {
  if (auth == nullptr) return absl::OkStatus();
  return auth->Authorize(context, method);
}

namespace internal {

void LogRefusal(const TokenAuthenticator& auth, std::string_view method,
                const grpc::ServerContextBase& context, const absl::Status& status) {
  const size_t slash = method.rfind('/');
  const std::string_view rpc =
      slash == std::string_view::npos ? method : method.substr(slash + 1);
  // Refusals are logged at info level, unlike answered requests (debug):
  // someone presenting bad tokens is worth seeing at the default level. But
  // any caller can cause them at will, so at most one line per second per
  // reason (code and message: a bounded set, never the peer) is written,
  // carrying the count of those held back since the previous one.
  const std::string code = absl::StatusCodeToString(status.code());
  const std::string reason =
      absl::StrCat(absl::string_view(rpc.data(), rpc.size()), " ", code, " ",
                   status.message());
  int64_t suppressed = 0;
  if (auth.refusal_log().ShouldLog(reason, absl::Now(), &suppressed)) {
    spdlog::info("refused {} from {}: {} {}{}", rpc, context.peer(), code,
                 std::string(status.message()),
                 suppressed == 0
                     ? std::string()
                     : absl::StrCat(" (and ", suppressed,
                                    " more refusals like it not logged)"));
  }
  // Still counted in the metrics; the request line itself is debug level.
  LogRequest(rpc, "-", "", status, absl::Now());
}

}  // namespace internal

}  // namespace pathd::server
