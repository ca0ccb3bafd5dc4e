#include "server/http/exchange.h"

#include <civetweb.h>

#include <cctype>
#include <utility>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "google/protobuf/struct.pb.h"
#include "google/protobuf/util/json_util.h"

namespace pathd::server {
namespace {

std::string UrlDecode(std::string_view text) {
  // Decoding never lengthens the text; +1 for the terminator civetweb writes.
  std::string out(text.size() + 1, '\0');
  const int n = mg_url_decode(text.data(), static_cast<int>(text.size()), out.data(),
                              static_cast<int>(out.size()), /*is_form_url_encoded=*/1);
  out.resize(n < 0 ? 0 : static_cast<size_t>(n));
  return out;
}

}  // namespace

int HttpStatusOf(grpc::StatusCode code) {
  switch (code) {
    case grpc::StatusCode::OK: return 200;
    case grpc::StatusCode::CANCELLED: return 499;
    case grpc::StatusCode::UNKNOWN: return 500;
    case grpc::StatusCode::INVALID_ARGUMENT: return 400;
    case grpc::StatusCode::DEADLINE_EXCEEDED: return 504;
    case grpc::StatusCode::NOT_FOUND: return 404;
    case grpc::StatusCode::ALREADY_EXISTS: return 409;
    case grpc::StatusCode::PERMISSION_DENIED: return 403;
    case grpc::StatusCode::UNAUTHENTICATED: return 401;
    case grpc::StatusCode::RESOURCE_EXHAUSTED: return 429;
    case grpc::StatusCode::FAILED_PRECONDITION: return 400;
    case grpc::StatusCode::ABORTED: return 409;
    case grpc::StatusCode::OUT_OF_RANGE: return 400;
    case grpc::StatusCode::UNIMPLEMENTED: return 501;
    case grpc::StatusCode::INTERNAL: return 500;
    case grpc::StatusCode::UNAVAILABLE: return 503;
    case grpc::StatusCode::DATA_LOSS: return 500;
    default: return 500;
  }
}

std::string StatusJson(grpc::StatusCode code, std::string_view message) {
  // The message through protobuf's JSON printer, which escapes it.
  google::protobuf::Value text;
  text.set_string_value(std::string(message));
  std::string quoted;
  if (!google::protobuf::util::MessageToJsonString(text, &quoted).ok()) quoted = "\"\"";
  return absl::StrFormat("{\"code\":%d,\"message\":%s,\"details\":[]}",
                         static_cast<int>(code), quoted);
}

absl::StatusOr<absl::Duration> ParseGrpcTimeout(std::string_view text) {
  const auto bad = [&] {
    return absl::InvalidArgumentError(absl::StrCat(
        "Grpc-Timeout \"", std::string(text),
        "\" is not 1-8 digits and a unit (H, M, S, m, u or n), e.g. 500m or 2S"));
  };
  if (text.size() < 2 || text.size() > 9) return bad();
  int64_t value = 0;
  if (!absl::SimpleAtoi(absl::string_view(text.data(), text.size() - 1), &value) || value < 0 ||
      !std::isdigit(static_cast<unsigned char>(text[0]))) {
    return bad();
  }
  switch (text.back()) {
    case 'H': return absl::Hours(value);
    case 'M': return absl::Minutes(value);
    case 'S': return absl::Seconds(value);
    case 'm': return absl::Milliseconds(value);
    case 'u': return absl::Microseconds(value);
    case 'n': return absl::Nanoseconds(value);
    default: return bad();
  }
}

absl::StatusOr<std::string> ToJson(const google::protobuf::Message& message, bool pretty) {
  google::protobuf::util::JsonPrintOptions options;
  options.add_whitespace = pretty;
  options.always_print_primitive_fields = true;
  std::string json;
  if (const auto status = google::protobuf::util::MessageToJsonString(message, &json, options);
      !status.ok()) {
    return absl::InternalError(absl::StrCat("cannot print ", message.GetTypeName(),
                                            " as JSON: ", status.ToString()));
  }
  return json;
}

absl::Status FromJson(std::string_view json, google::protobuf::Message& message) {
  if (absl::StripAsciiWhitespace(absl::string_view(json.data(), json.size())).empty()) {
    return absl::OkStatus();
  }
  google::protobuf::util::JsonParseOptions options;
  options.ignore_unknown_fields = false;
  const auto status = google::protobuf::util::JsonStringToMessage(
      google::protobuf::StringPiece(json.data(), json.size()), &message, options);
  if (!status.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("the body is not a JSON ", message.GetDescriptor()->name(), ": ",
                     std::string(status.message())));
  }
  return absl::OkStatus();
}

HttpExchange::HttpExchange(mg_connection* conn, int64_t max_body_bytes)
    : conn_(conn), max_body_bytes_(max_body_bytes) {
  const mg_request_info* info = mg_get_request_info(conn);
  method_ = info->request_method != nullptr ? info->request_method : "";
  path_ = info->local_uri != nullptr ? info->local_uri : "";
  remote_address_ = info->remote_addr;
  if (info->query_string != nullptr) {
    for (absl::string_view pair : absl::StrSplit(info->query_string, '&', absl::SkipEmpty())) {
      std::pair<absl::string_view, absl::string_view> kv =
          absl::StrSplit(pair, absl::MaxSplits('=', 1));
      query_[UrlDecode(std::string_view(kv.first.data(), kv.first.size()))] =
          UrlDecode(std::string_view(kv.second.data(), kv.second.size()));
    }
  }
}

std::optional<std::string> HttpExchange::Header(const char* name) const {
  const char* value = mg_get_header(conn_, name);
  if (value == nullptr) return std::nullopt;
  return std::string(value);
}

std::optional<std::string> HttpExchange::TakeQuery(const std::string& name) {
  auto it = query_.find(name);
  if (it == query_.end()) return std::nullopt;
  std::string value = std::move(it->second);
  query_.erase(it);
  return value;
}

absl::StatusOr<std::string> HttpExchange::ReadBody() {
  const mg_request_info* info = mg_get_request_info(conn_);
  const auto too_large = [&] {
    return absl::ResourceExhaustedError(absl::StrFormat(
        "the request body is over the %d-byte limit (pathd --max_message_bytes)",
        max_body_bytes_));
  };
  if (info->content_length > max_body_bytes_) return too_large();
  std::string body;
  if (info->content_length > 0) body.reserve(static_cast<size_t>(info->content_length));
  char buffer[16384];
  while (true) {
    const int n = mg_read(conn_, buffer, sizeof(buffer));
    if (n < 0) return absl::UnavailableError("the client closed the connection mid-body");
    if (n == 0) break;
    if (static_cast<int64_t>(body.size()) + n > max_body_bytes_) return too_large();
    body.append(buffer, static_cast<size_t>(n));
  }
  return body;
}

void HttpExchange::AddHeader(std::string name, std::string value) {
  extra_headers_.emplace_back(std::move(name), std::move(value));
}

int HttpExchange::Send(int status, std::string_view content_type, std::string_view body) {
  mg_response_header_start(conn_, status);
  mg_response_header_add(conn_, "Content-Type", content_type.data(),
                         static_cast<int>(content_type.size()));
  const std::string length = absl::StrCat(body.size());
  mg_response_header_add(conn_, "Content-Length", length.c_str(), -1);
  mg_response_header_add(conn_, "Cache-Control", "no-store", -1);
  for (const auto& [name, value] : extra_headers_) {
    mg_response_header_add(conn_, name.c_str(), value.c_str(), -1);
  }
  mg_response_header_send(conn_);
  if (method_ != "HEAD" && !body.empty()) mg_write(conn_, body.data(), body.size());
  return status;
}

int HttpExchange::SendError(const grpc::Status& status) {
  return Send(HttpStatusOf(status.error_code()), "application/json",
              StatusJson(status.error_code(), status.error_message()));
}

bool HttpExchange::WriteChunkLocked(std::string_view text) {
  if (broken_) return false;
  if (!events_started_) {
    events_started_ = true;
    mg_response_header_start(conn_, 200);
    mg_response_header_add(conn_, "Content-Type", "text/event-stream", -1);
    mg_response_header_add(conn_, "Cache-Control", "no-store", -1);
    mg_response_header_add(conn_, "Transfer-Encoding", "chunked", -1);
    // nginx and similar proxies pass events on at once instead of buffering.
    mg_response_header_add(conn_, "X-Accel-Buffering", "no", -1);
    for (const auto& [name, value] : extra_headers_) {
      mg_response_header_add(conn_, name.c_str(), value.c_str(), -1);
    }
    if (mg_response_header_send(conn_) < 0) broken_ = true;
  }
  if (!broken_ && mg_send_chunk(conn_, text.data(), static_cast<unsigned>(text.size())) < 0) {
    broken_ = true;
  }
  return !broken_;
}

bool HttpExchange::SendEvent(std::string_view event, std::string_view data,
                             std::string_view id) {
  std::string text;
  if (!event.empty()) absl::StrAppend(&text, "event: ", std::string(event), "\n");
  if (!id.empty()) absl::StrAppend(&text, "id: ", std::string(id), "\n");
  // A data line per line of the payload (JSON here is one line).
  for (absl::string_view line : absl::StrSplit(absl::string_view(data.data(), data.size()), '\n')) {
    absl::StrAppend(&text, "data: ", line, "\n");
  }
  text.push_back('\n');
  absl::MutexLock lock(&write_mu_);
  return WriteChunkLocked(text);
}

bool HttpExchange::SendKeepalive() {
  // A handler writing an event right now shows the client is being served;
  // waiting for it could hold the keepalive pass behind a slow socket.
  if (!write_mu_.TryLock()) return true;
  const bool ok = !events_started_ ? !broken_ : WriteChunkLocked(": keepalive\n\n");
  write_mu_.Unlock();
  return ok;
}

void HttpExchange::EndEvents() {
  absl::MutexLock lock(&write_mu_);
  if (events_started_ && !broken_) mg_send_chunk(conn_, "", 0);
  broken_ = true;
}

bool HttpExchange::events_started() const {
  absl::MutexLock lock(&write_mu_);
  return events_started_;
}

}  // namespace pathd::server
