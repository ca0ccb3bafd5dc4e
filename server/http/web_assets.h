// The viewer's files (server/http/web/), compiled into pathd by
// embed_web.cmake so the daemon serves its page with no files installed.
#ifndef PATHD_SERVER_HTTP_WEB_ASSETS_H_
#define PATHD_SERVER_HTTP_WEB_ASSETS_H_

#include <string_view>

namespace pathd::server {

struct WebAsset {
  std::string_view path;  // "/index.html"
  std::string_view content_type;
  std::string_view body;
};

// The file served at `path`; null when there is none.
const WebAsset* FindWebAsset(std::string_view path);

}  // namespace pathd::server

#endif  // PATHD_SERVER_HTTP_WEB_ASSETS_H_
