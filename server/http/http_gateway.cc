#include "server/http/http_gateway.h"

#include <civetweb.h>
#include <grpcpp/client_context.h>
#include <grpcpp/support/sync_stream.h>

#include <atomic>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "absl/base/thread_annotations.h"
#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/synchronization/mutex.h"
#include "absl/synchronization/notification.h"
#include "absl/time/clock.h"
#include "google/protobuf/struct.pb.h"
#include "google/protobuf/util/json_util.h"
#include "grpc/health/v1/health.grpc.pb.h"
#include "pathd/v1/map_service.grpc.pb.h"
#include "pathd/v1/planner_service.grpc.pb.h"
#include "proto/geojson.h"
#include "proto/planner_names.h"
#include "server/grpc_status.h"
#include "server/http/exchange.h"
#include "server/http/web_assets.h"

namespace pathd::server {
namespace {

using google::protobuf::Message;

// The metadata key that carries the HTTP client's address to the service
// (MemoryBudget::CallerOf, the request log), trusted only on in-process calls.
constexpr char kHttpPeerKey[] = "x-pathd-http-peer";

// How a route answers on success.
enum class Format { kJson, kGeoJson };

// The path after "/v1/maps/NAME": NAME and what follows (":verb" or
// "/sessions"). Map names are A-Z a-z 0-9 . _ - (map_name.h), so the first
// ':' or '/' ends one.
struct MapPath {
  std::string name;
  std::string rest;
};

MapPath SplitMapPath(std::string_view tail) {
  const size_t end = tail.find_first_of(":/");
  if (end == std::string_view::npos) return {std::string(tail), ""};
  return {std::string(tail.substr(0, end)), std::string(tail.substr(end))};
}

// Sets the request's map field ("map" on the planner's requests, "name" on
// the map service's) to the URL's name; a body naming another map is an
// error rather than silently overridden.
absl::Status SetMapName(Message& request, const std::string& map) {
  const auto* descriptor = request.GetDescriptor();
  const auto* field = descriptor->FindFieldByName("map");
  if (field == nullptr) field = descriptor->FindFieldByName("name");
  if (field == nullptr || field->type() != google::protobuf::FieldDescriptor::TYPE_STRING ||
      field->is_repeated()) {
    return absl::OkStatus();
  }
  const auto* reflection = request.GetReflection();
  const std::string given = reflection->GetString(request, field);
  if (!given.empty() && given != map) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "the body's %s \"%s\" differs from the URL's map \"%s\"", field->name(), given, map));
  }
  reflection->SetString(&request, field, map);
  return absl::OkStatus();
}

// A GET's or DELETE's query as the request: each parameter is a field of the
// request by its proto name ("include_cells=true", "from_version=3").
absl::Status RequestFromQuery(const std::map<std::string, std::string>& query,
                              Message& request) {
  if (query.empty()) return absl::OkStatus();
  google::protobuf::Struct fields;
  for (const auto& [name, value] : query) {
    auto& field = (*fields.mutable_fields())[name];
    if (value == "true" || value == "false") {
      field.set_bool_value(value == "true");
    } else {
      // Protobuf's JSON parser takes numbers and enum names as strings.
      field.set_string_value(value);
    }
  }
  std::string json;
  if (!google::protobuf::util::MessageToJsonString(fields, &json).ok()) {
    return absl::InternalError("cannot convert the query to JSON");
  }
  absl::Status parsed = FromJson(json, request);
  if (!parsed.ok()) {
    return absl::InvalidArgumentError(
        absl::StrCat("bad query parameter: ", std::string(parsed.message())));
  }
  return absl::OkStatus();
}

bool PrintableAscii(std::string_view text) {
  for (char c : text) {
    if (c < 0x20 || c > 0x7e) return false;
  }
  return true;
}

}  // namespace

class HttpGateway::Impl {
 public:
  Impl(HttpGatewayOptions options, std::shared_ptr<grpc::Channel> channel)
      : options_(std::move(options)),
        maps_(v1::MapService::NewStub(channel)),
        planner_(v1::PlannerService::NewStub(channel)),
        health_(grpc::health::v1::Health::NewStub(channel)) {}

  ~Impl() { Stop(); }

  absl::Status Listen() {
    const std::string threads = absl::StrCat(options_.max_streams + kUnaryThreads);
    const std::string ports = options_.address;
    // request_timeout_ms bounds each read and write on a socket: a client
    // that stops reading its event stream is dropped after it.
    const char* config[] = {"listening_ports", ports.c_str(),
                            "num_threads", threads.c_str(),
                            "request_timeout_ms", "30000",
                            "enable_keep_alive", "yes",
                            "keep_alive_timeout_ms", "5000",
                            nullptr};
    mg_callbacks callbacks;
    std::memset(&callbacks, 0, sizeof(callbacks));
    callbacks.log_message = [](const mg_connection*, const char* message) {
      spdlog::warn("http: {}", message);
      return 1;
    };
    mg_init_data init{&callbacks, this, config};
    char error_text[256] = {0};
    unsigned error_code = 0;
    mg_error_data error{&error_code, error_text, sizeof(error_text)};
    mg_init_library(0);
    library_initialised_ = true;
    context_ = mg_start2(&init, &error);
    if (context_ == nullptr) {
      return absl::UnavailableError(absl::StrFormat(
          "cannot listen for HTTP on %s (--http_address): %s", options_.address,
          error_text[0] != '\0' ? error_text : "the address is in use or not host:port"));
    }
    mg_server_port bound[4];
    const int n = mg_get_server_ports(context_, 4, bound);
    port_ = n > 0 ? bound[0].port : 0;
    mg_set_request_handler(context_, "/", &Impl::Handle, this);
    keepalive_ = std::thread([this] { KeepaliveLoop(); });
    return absl::OkStatus();
  }

  int port() const { return port_; }

  void BeginShutdown() {
    absl::MutexLock lock(&mu_);
    if (stopping_) return;
    stopping_ = true;
    for (OpenStream* stream : streams_) stream->context->TryCancel();
  }

  void Stop() {
    BeginShutdown();
    if (keepalive_.joinable()) {
      stop_keepalive_.Notify();
      keepalive_.join();
    }
    if (context_ != nullptr) {
      mg_stop(context_);
      context_ = nullptr;
    }
    if (library_initialised_) {
      mg_exit_library();
      library_initialised_ = false;
    }
  }

 private:
  // A Server-Sent Event stream in progress: the keepalive thread writes to
  // it and shutdown cancels it.
  struct OpenStream {
    HttpExchange* exchange;
    grpc::ClientContext* context;
  };

  // A Navigate call opened over HTTP: its events go to the opener's stream,
  // its further messages come through POST /v1/sessions/ID:send.
  struct Navigation {
    absl::Mutex mu;
    grpc::ClientReaderWriter<v1::NavigateRequest, v1::NavigateResponse>* stream
        ABSL_GUARDED_BY(mu) = nullptr;
    bool closed ABSL_GUARDED_BY(mu) = false;
    bool writes_done ABSL_GUARDED_BY(mu) = false;
    // The opener's Authorization header: only it may send to the session.
    std::string authorization;
  };

  static int Handle(mg_connection* conn, void* data) {
    auto* self = static_cast<Impl*>(data);
    HttpExchange exchange(conn, self->options_.max_body_bytes);
    if (!self->options_.replica_name.empty()) {
      exchange.AddHeader("X-Pathd-Replica", self->options_.replica_name);
    }
    {
      absl::MutexLock lock(&self->mu_);
      if (self->stopping_) {
        return exchange.SendError(grpc::StatusCode::UNAVAILABLE, "pathd is shutting down");
      }
    }
    return self->Dispatch(exchange);
  }

  int Dispatch(HttpExchange& x) {
    const std::string& path = x.path();
    const std::string& method = x.method();
    if (path == "/healthz") return Health(x);
    if (absl::StartsWith(path, "/v1/")) return DispatchApi(x);
    if (method == "GET" || method == "HEAD") {
      if (const WebAsset* asset = FindWebAsset(path == "/" ? "/index.html" : path)) {
        return x.Send(200, asset->content_type, asset->body);
      }
    }
    return NoRoute(x);
  }

  int NoRoute(HttpExchange& x) {
    return x.SendError(grpc::StatusCode::NOT_FOUND,
                       absl::StrFormat("no route for %s %s (docs/http.md lists the routes)",
                                       x.method(), x.path()));
  }

  int WrongMethod(HttpExchange& x, std::vector<std::string> allowed) {
    x.AddHeader("Allow", absl::StrJoin(allowed, ", "));
    return x.Send(405, "application/json",
                  StatusJson(grpc::StatusCode::UNIMPLEMENTED,
                             absl::StrFormat("%s %s: the route takes %s", x.method(), x.path(),
                                             absl::StrJoin(allowed, " or "))));
  }

  int DispatchApi(HttpExchange& x) {
    const std::string& path = x.path();
    const std::string& method = x.method();
    if (path == "/v1/maps") {
      if (method == "GET") return Unary(x, "", *maps_, &v1::MapService::Stub::ListMaps);
      if (method == "POST") return Unary(x, "", *maps_, &v1::MapService::Stub::CreateMap);
      return WrongMethod(x, {"GET", "POST"});
    }
    if (path == "/v1/cacheStats") {
      if (method != "GET") return WrongMethod(x, {"GET"});
      return Unary(x, "", *planner_, &v1::PlannerService::Stub::GetCacheStats);
    }
    if (path == "/v1/planners") {
      if (method != "GET") return WrongMethod(x, {"GET"});
      return Planners(x);
    }
    if (path == "/v1/sessions") {
      if (method != "GET") return WrongMethod(x, {"GET"});
      return Unary(x, "", *planner_, &v1::PlannerService::Stub::ListSessions);
    }
    if (absl::StartsWith(path, "/v1/sessions/")) return SessionRoute(x);
    if (!absl::StartsWith(path, "/v1/maps/")) return NoRoute(x);
    const MapPath map = SplitMapPath(std::string_view(path).substr(std::strlen("/v1/maps/")));
    if (map.name.empty()) return NoRoute(x);
    if (map.rest.empty()) {
      if (method == "GET") return Unary(x, map.name, *maps_, &v1::MapService::Stub::GetMap);
      if (method == "DELETE") return Unary(x, map.name, *maps_, &v1::MapService::Stub::DeleteMap);
      if (method == "PUT") return Unary(x, map.name, *maps_, &v1::MapService::Stub::CreateMap);
      return WrongMethod(x, {"GET", "PUT", "DELETE"});
    }
    if (map.rest == "/sessions") {
      if (method != "GET") return WrongMethod(x, {"GET"});
      return Unary(x, map.name, *planner_, &v1::PlannerService::Stub::ListSessions);
    }
    if (map.rest == ":watch") {
      if (method != "GET") return WrongMethod(x, {"GET"});
      v1::WatchMapRequest request;
      // An EventSource that reconnects sends the last version it saw.
      std::optional<std::string> last = x.Header("Last-Event-ID");
      uint64_t last_version = 0;
      if (last.has_value() && absl::SimpleAtoi(*last, &last_version) &&
          x.query().count("from_version") == 0) {
        request.set_from_version(last_version + 1);
      }
      return ServerStream(x, map.name, request, *maps_, &v1::MapService::Stub::WatchMap,
                          [](const v1::MapEvent& e) { return absl::StrCat(e.version()); });
    }
    if (method != "POST") return WrongMethod(x, {"POST"});
    using P = v1::PlannerService::Stub;
    const std::string& verb = map.rest;
    if (verb == ":update") return Unary(x, map.name, *maps_, &v1::MapService::Stub::UpdateMap);
    if (verb == ":plan") return Unary(x, map.name, *planner_, &P::Plan, &PlanGeoJson);
    if (verb == ":costToGo") return Unary(x, map.name, *planner_, &P::CostToGo);
    if (verb == ":isPathValid") return Unary(x, map.name, *planner_, &P::IsPathValid);
    if (verb == ":table") return Unary(x, map.name, *planner_, &P::Table);
    if (verb == ":nearest") return Unary(x, map.name, *planner_, &P::Nearest);
    if (verb == ":trip") return Unary(x, map.name, *planner_, &P::Trip);
    if (verb == ":isochrone") return Unary(x, map.name, *planner_, &P::Isochrone, &IsochroneGeoJson);
    if (verb == ":planFleet") return Unary(x, map.name, *planner_, &P::PlanFleet);
    if (verb == ":planBatch") return PlanBatch(x, map.name);
    if (verb == ":navigate") return Navigate(x, map.name);
    if (verb == ":planStream") {
      v1::PlanRequest request;
      return ServerStream(x, map.name, request, *planner_, &P::PlanStream,
                          [](const v1::PlanStreamEvent&) { return std::string(); });
    }
    return NoRoute(x);
  }

  // The request of a route: the JSON body (POST, PUT) or the query (GET,
  // DELETE), with the URL's map name. The gateway's own parameters (pretty,
  // format) are taken out first.
  absl::Status ReadRequest(HttpExchange& x, const std::string& map, Message& request) {
    if (x.method() == "GET" || x.method() == "DELETE" || x.method() == "HEAD") {
      if (absl::Status s = RequestFromQuery(x.query(), request); !s.ok()) return s;
    } else {
      if (!x.query().empty()) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "unknown query parameter \"%s\": %s takes its request as the JSON body",
            x.query().begin()->first, x.method()));
      }
      absl::StatusOr<std::string> body = x.ReadBody();
      if (!body.ok()) return body.status();
      if (absl::Status s = FromJson(*body, request); !s.ok()) return s;
    }
    if (!map.empty()) return SetMapName(request, map);
    return absl::OkStatus();
  }

  // The call's metadata and deadline from the HTTP headers.
  absl::Status PrepareContext(HttpExchange& x, grpc::ClientContext& context) {
    if (std::optional<std::string> auth = x.Header("Authorization")) {
      if (!PrintableAscii(*auth)) {
        return absl::UnauthenticatedError(
            "the Authorization header has characters no token has (printable ASCII only)");
      }
      context.AddMetadata("authorization", *auth);
    }
    context.AddMetadata(kHttpPeerKey, x.remote_address());
    if (std::optional<std::string> timeout = x.Header("Grpc-Timeout")) {
      absl::StatusOr<absl::Duration> d = ParseGrpcTimeout(*timeout);
      if (!d.ok()) return d.status();
      context.set_deadline(absl::ToChronoTime(absl::Now() + *d));
    }
    return absl::OkStatus();
  }

  // Takes the gateway's own query parameters: ?pretty and ?format.
  absl::StatusOr<std::pair<bool, Format>> TakeOutputOptions(HttpExchange& x, bool geojson) {
    bool pretty = false;
    if (std::optional<std::string> p = x.TakeQuery("pretty")) pretty = *p != "false";
    Format format = Format::kJson;
    if (std::optional<std::string> f = x.TakeQuery("format")) {
      if (*f == "geojson" && geojson) {
        format = Format::kGeoJson;
      } else if (*f != "json") {
        return absl::InvalidArgumentError(absl::StrFormat(
            "format=%s: this route answers %s", *f, geojson ? "json or geojson" : "json"));
      }
    }
    return std::make_pair(pretty, format);
  }

  template <typename Stub, typename Request, typename Response>
  int Unary(HttpExchange& x, const std::string& map, Stub& stub,
            grpc::Status (Stub::*method)(grpc::ClientContext*, const Request&, Response*),
            std::string (*geojson)(const Response&, std::string_view) = nullptr) {
    absl::StatusOr<std::pair<bool, Format>> output = TakeOutputOptions(x, geojson != nullptr);
    if (!output.ok()) return x.SendError(ToGrpcStatus(output.status()));
    Request request;
    if (absl::Status s = ReadRequest(x, map, request); !s.ok()) return RefuseRequest(x, s);
    grpc::ClientContext context;
    if (absl::Status s = PrepareContext(x, context); !s.ok()) return x.SendError(ToGrpcStatus(s));
    Response response;
    const grpc::Status status = (stub.*method)(&context, request, &response);
    if (!status.ok()) return x.SendError(status);
    if (output->second == Format::kGeoJson) {
      return x.Send(200, "application/geo+json", geojson(response, map));
    }
    absl::StatusOr<std::string> json = ToJson(response, output->first);
    if (!json.ok()) return x.SendError(ToGrpcStatus(json.status()));
    return x.SendJson(*json);
  }

  // A request the gateway refuses before any call. An oversized body gets 413
  // at once; civetweb then reads the rest of it into a fixed buffer and drops
  // it, so the client, still sending, gets to read the answer (closing the
  // connection instead would reset it mid-send).
  int RefuseRequest(HttpExchange& x, const absl::Status& status) {
    if (status.code() == absl::StatusCode::kResourceExhausted) {
      return x.Send(413, "application/json",
                    StatusJson(grpc::StatusCode::RESOURCE_EXHAUSTED, std::string(status.message())));
    }
    return x.SendError(ToGrpcStatus(status));
  }

  // Admits one more event stream (--http_max_streams) and registers it.
  absl::Status OpenEventStream(OpenStream& stream) {
    absl::MutexLock lock(&mu_);
    if (stopping_) return absl::UnavailableError("pathd is shutting down");
    if (static_cast<int>(streams_.size()) >= options_.max_streams) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "%d HTTP event streams are open, the most pathd serves at once "
          "(--http_max_streams); close one or use gRPC",
          options_.max_streams));
    }
    streams_.insert(&stream);
    return absl::OkStatus();
  }

  void CloseEventStream(OpenStream& stream) {
    absl::MutexLock lock(&mu_);
    streams_.erase(&stream);
  }

  // The end of an event stream: an error before any event is a plain HTTP
  // error; otherwise an "end" event carries the call's status.
  int FinishEvents(HttpExchange& x, const grpc::Status& status) {
    if (!x.events_started() && !status.ok()) return x.SendError(status);
    x.SendEvent("end", StatusJson(status.error_code(), status.error_message()));
    x.EndEvents();
    return 200;
  }

  // `id_of(event)`: the event's SSE id ("" = none).
  template <typename Stub, typename Request, typename Event, typename IdOf>
  int ServerStream(HttpExchange& x, const std::string& map, Request& request, Stub& stub,
                   std::unique_ptr<grpc::ClientReader<Event>> (Stub::*method)(
                       grpc::ClientContext*, const Request&),
                   IdOf id_of) {
    if (absl::Status s = ReadRequest(x, map, request); !s.ok()) return RefuseRequest(x, s);
    grpc::ClientContext context;
    if (absl::Status s = PrepareContext(x, context); !s.ok()) return x.SendError(ToGrpcStatus(s));
    OpenStream open{&x, &context};
    if (absl::Status s = OpenEventStream(open); !s.ok()) return x.SendError(ToGrpcStatus(s));
    std::unique_ptr<grpc::ClientReader<Event>> reader = (stub.*method)(&context, request);
    Event event;
    while (reader->Read(&event)) {
      absl::StatusOr<std::string> json = ToJson(event, /*pretty=*/false);
      if (!json.ok() || !x.SendEvent("", *json, id_of(event))) {
        context.TryCancel();
        break;
      }
    }
    const grpc::Status status = reader->Finish();
    CloseEventStream(open);
    return FinishEvents(x, status);
  }

  // PlanBatch: {"requests": [PlanBatchRequest...]} in, {"responses":
  // [PlanBatchResponse...]} out, in the order the server answers (match
  // them by request_id). Each request's map defaults to the URL's.
  int PlanBatch(HttpExchange& x, const std::string& map) {
    absl::StatusOr<std::pair<bool, Format>> output = TakeOutputOptions(x, false);
    if (!output.ok()) return x.SendError(ToGrpcStatus(output.status()));
    if (!x.query().empty()) {
      return x.SendError(grpc::StatusCode::INVALID_ARGUMENT,
                         absl::StrFormat("unknown query parameter \"%s\"", x.query().begin()->first));
    }
    absl::StatusOr<std::string> body = x.ReadBody();
    if (!body.ok()) return RefuseRequest(x, body.status());
    google::protobuf::Struct parsed;
    if (absl::Status s = FromJson(*body, parsed); !s.ok()) return x.SendError(ToGrpcStatus(s));
    const auto& fields = parsed.fields();
    auto requests_field = fields.find("requests");
    if (fields.size() != 1 || requests_field == fields.end() ||
        !requests_field->second.has_list_value()) {
      return x.SendError(grpc::StatusCode::INVALID_ARGUMENT,
                         "the body must be {\"requests\": [PlanBatchRequest, ...]}");
    }
    std::vector<v1::PlanBatchRequest> requests;
    for (int i = 0; i < requests_field->second.list_value().values_size(); ++i) {
      std::string item;
      if (!google::protobuf::util::MessageToJsonString(
               requests_field->second.list_value().values(i), &item).ok()) {
        return x.SendError(grpc::StatusCode::INTERNAL, "cannot re-read the body");
      }
      v1::PlanBatchRequest request;
      if (absl::Status s = FromJson(item, request); !s.ok()) {
        return x.SendError(grpc::StatusCode::INVALID_ARGUMENT,
                           absl::StrFormat("requests[%d]: %s", i, s.message()));
      }
      if (absl::Status s = SetMapName(*request.mutable_request(), map); !s.ok()) {
        return x.SendError(grpc::StatusCode::INVALID_ARGUMENT,
                           absl::StrFormat("requests[%d]: %s", i, s.message()));
      }
      requests.push_back(std::move(request));
    }
    grpc::ClientContext context;
    if (absl::Status s = PrepareContext(x, context); !s.ok()) return x.SendError(ToGrpcStatus(s));
    auto stream = planner_->PlanBatch(&context);
    // The writer runs beside the reader: the server answers while requests
    // are still arriving, and its flow control would stall one thread doing
    // both.
    std::thread writer([&] {
      for (const v1::PlanBatchRequest& request : requests) {
        if (!stream->Write(request)) break;
      }
      stream->WritesDone();
    });
    std::vector<std::string> answers;
    v1::PlanBatchResponse response;
    bool print_failed = false;
    while (stream->Read(&response)) {
      absl::StatusOr<std::string> json = ToJson(response, output->first);
      if (!json.ok()) print_failed = true;
      else answers.push_back(*std::move(json));
    }
    writer.join();
    const grpc::Status status = stream->Finish();
    if (!status.ok()) return x.SendError(status);
    if (print_failed) return x.SendError(grpc::StatusCode::INTERNAL, "cannot print an answer");
    return x.SendJson(absl::StrCat("{\"responses\": [", absl::StrJoin(answers, ", "), "]}"));
  }

  // Navigate: the body is the first NavigateRequest (open); the answers and
  // pushes come back as events, the first carrying the session_id that
  // POST /v1/sessions/ID:send and DELETE /v1/sessions/ID take.
  int Navigate(HttpExchange& x, const std::string& map) {
    v1::NavigateRequest first;
    if (absl::Status s = ReadRequest(x, "", first); !s.ok()) return RefuseRequest(x, s);
    if (!first.has_open()) {
      return x.SendError(grpc::StatusCode::INVALID_ARGUMENT,
                         "the body must be a NavigateRequest with \"open\"");
    }
    if (absl::Status s = SetMapName(*first.mutable_open(), map); !s.ok()) {
      return x.SendError(ToGrpcStatus(s));
    }
    grpc::ClientContext context;
    if (absl::Status s = PrepareContext(x, context); !s.ok()) return x.SendError(ToGrpcStatus(s));
    OpenStream open{&x, &context};
    if (absl::Status s = OpenEventStream(open); !s.ok()) return x.SendError(ToGrpcStatus(s));
    auto navigation = std::make_shared<Navigation>();
    navigation->authorization = x.Header("Authorization").value_or("");
    auto stream = planner_->Navigate(&context);
    {
      absl::MutexLock lock(&navigation->mu);
      navigation->stream = stream.get();
      stream->Write(first);
    }
    uint64_t session_id = 0;
    v1::NavigateResponse response;
    while (stream->Read(&response)) {
      if (session_id == 0 && response.session_id() != 0) {
        session_id = response.session_id();
        absl::MutexLock lock(&mu_);
        navigations_[session_id] = navigation;
      }
      absl::StatusOr<std::string> json = ToJson(response, /*pretty=*/false);
      if (!json.ok() || !x.SendEvent("", *json)) {
        context.TryCancel();
        break;
      }
    }
    {
      absl::MutexLock lock(&navigation->mu);
      navigation->closed = true;
      navigation->stream = nullptr;
    }
    if (session_id != 0) {
      absl::MutexLock lock(&mu_);
      navigations_.erase(session_id);
    }
    const grpc::Status status = stream->Finish();
    CloseEventStream(open);
    return FinishEvents(x, status);
  }

  // POST /v1/sessions/ID:send (a NavigateRequest) and DELETE /v1/sessions/ID
  // (the client's end of the session: the server finishes it with OK).
  int SessionRoute(HttpExchange& x) {
    const std::string_view tail = std::string_view(x.path()).substr(std::strlen("/v1/sessions/"));
    const size_t colon = tail.find(':');
    const std::string_view id_text = tail.substr(0, colon);
    const std::string_view verb =
        colon == std::string_view::npos ? std::string_view() : tail.substr(colon);
    uint64_t id = 0;
    if (!absl::SimpleAtoi(absl::string_view(id_text.data(), id_text.size()), &id) || (!verb.empty() && verb != ":send")) return NoRoute(x);
    if (verb.empty() && x.method() != "DELETE") return WrongMethod(x, {"DELETE"});
    if (!verb.empty() && x.method() != "POST") return WrongMethod(x, {"POST"});
    v1::NavigateRequest message;
    if (!verb.empty()) {
      if (absl::Status s = ReadRequest(x, "", message); !s.ok()) return RefuseRequest(x, s);
      if (message.has_open()) {
        return x.SendError(grpc::StatusCode::INVALID_ARGUMENT,
                           "the session is open already: send pose or observe");
      }
    }
    std::shared_ptr<Navigation> navigation;
    {
      absl::MutexLock lock(&mu_);
      auto it = navigations_.find(id);
      if (it != navigations_.end()) navigation = it->second;
    }
    const std::string not_found = absl::StrFormat(
        "no session %d opened over this HTTP address (it ended, or was opened over gRPC)", id);
    if (navigation == nullptr) return x.SendError(grpc::StatusCode::NOT_FOUND, not_found);
    if (x.Header("Authorization").value_or("") != navigation->authorization) {
      return x.SendError(grpc::StatusCode::PERMISSION_DENIED,
                         "only the session's opener (its Authorization header) may send to it");
    }
    absl::MutexLock lock(&navigation->mu);
    if (navigation->closed) return x.SendError(grpc::StatusCode::NOT_FOUND, not_found);
    if (navigation->writes_done) {
      return x.SendError(grpc::StatusCode::FAILED_PRECONDITION,
                         absl::StrFormat("session %d is closing", id));
    }
    if (verb.empty()) {
      navigation->writes_done = true;
      navigation->stream->WritesDone();
      return x.SendJson("{}");
    }
    if (!navigation->stream->Write(message)) {
      return x.SendError(grpc::StatusCode::NOT_FOUND, not_found);
    }
    // The answer comes on the session's event stream.
    return x.SendJson("{}");
  }

  // The Planner enum's values and their registry names (planner_names.h):
  // what the viewer offers, with no list of its own to fall behind.
  int Planners(HttpExchange& x) {
    std::vector<std::string> entries;
    for (const WirePlanner& planner : WirePlanners()) {
      entries.push_back(absl::StrFormat("{\"value\": \"%s\", \"name\": \"%s\"}",
                                        v1::Planner_Name(planner.wire), planner.name));
    }
    return x.SendJson(absl::StrCat("{\"planners\": [", absl::StrJoin(entries, ", "), "]}"));
  }

  int Health(HttpExchange& x) {
    grpc::ClientContext context;
    context.set_deadline(absl::ToChronoTime(absl::Now() + absl::Seconds(5)));
    grpc::health::v1::HealthCheckRequest request;
    grpc::health::v1::HealthCheckResponse response;
    const grpc::Status status = health_->Check(&context, request, &response);
    if (!status.ok()) return x.SendError(status);
    if (response.status() != grpc::health::v1::HealthCheckResponse::SERVING) {
      return x.SendError(grpc::StatusCode::UNAVAILABLE, "not serving");
    }
    return x.SendJson("{\"status\": \"SERVING\"}");
  }

  void KeepaliveLoop() {
    while (!stop_keepalive_.WaitForNotificationWithTimeout(options_.keepalive)) {
      absl::MutexLock lock(&mu_);
      for (OpenStream* stream : streams_) {
        if (!stream->exchange->SendKeepalive()) stream->context->TryCancel();
      }
    }
  }

  const HttpGatewayOptions options_;
  std::unique_ptr<v1::MapService::Stub> maps_;
  std::unique_ptr<v1::PlannerService::Stub> planner_;
  std::unique_ptr<grpc::health::v1::Health::Stub> health_;
  mg_context* context_ = nullptr;
  bool library_initialised_ = false;
  int port_ = 0;
  std::thread keepalive_;
  absl::Notification stop_keepalive_;

  absl::Mutex mu_;
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  std::set<OpenStream*> streams_ ABSL_GUARDED_BY(mu_);
  std::map<uint64_t, std::shared_ptr<Navigation>> navigations_ ABSL_GUARDED_BY(mu_);
};

absl::StatusOr<std::unique_ptr<HttpGateway>> HttpGateway::Start(
    HttpGatewayOptions options, std::shared_ptr<grpc::Channel> channel) {
  if (options.max_streams < 1) {
    return absl::InvalidArgumentError("--http_max_streams must be at least 1");
  }
  auto impl = std::make_unique<Impl>(std::move(options), std::move(channel));
  if (absl::Status s = impl->Listen(); !s.ok()) return s;
  return std::unique_ptr<HttpGateway>(new HttpGateway(std::move(impl)));
}

HttpGateway::HttpGateway(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
HttpGateway::~HttpGateway() = default;
int HttpGateway::port() const { return impl_->port(); }
void HttpGateway::BeginShutdown() { impl_->BeginShutdown(); }
void HttpGateway::Stop() { impl_->Stop(); }

}  // namespace pathd::server
