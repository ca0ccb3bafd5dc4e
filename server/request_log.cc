// Request log line.
#include "server/request_log.h"

#include <string>

#include "spdlog/spdlog.h"

namespace pathd::server {

void LogRequest(std::string_view rpc, std::string_view map, std::string_view detail,
                const absl::Status& status, absl::Time received) {
  if (!spdlog::should_log(spdlog::level::debug)) return;
  const int64_t us = absl::ToInt64Microseconds(absl::Now() - received);
  const std::string code = absl::StatusCodeToString(status.code());
  if (status.ok()) {
    spdlog::debug("rpc={} map={} {}{}status={} us={}", rpc, map, detail,
                  detail.empty() ? "" : " ", code, us);
  } else {
    spdlog::debug("rpc={} map={} {}{}status={} us={} error=\"{}\"", rpc, map,
                  detail, detail.empty() ? "" : " ", code, us,
                  std::string(status.message()));
  }
}

}  // namespace pathd::server
