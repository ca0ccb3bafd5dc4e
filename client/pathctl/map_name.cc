// The map name rule (copied from server/map_store.cc MapStore::ValidateName).
#include "client/pathctl/map_name.h"

#include "absl/strings/escaping.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"

namespace pathd::pathctl {
namespace {

bool IsNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
         (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
}

}  // namespace

absl::Status ValidateMapName(absl::string_view name) {
  if (name.empty()) return absl::InvalidArgumentError("map name is empty");
  if (name.size() > kMaxMapNameLength) {
    return absl::InvalidArgumentError(
        absl::StrFormat("map name is %d characters long; the limit is %d",
                        name.size(), kMaxMapNameLength));
  }
  const absl::string_view text = name;
  if (name.front() == '.') {
    return absl::InvalidArgumentError(absl::StrFormat(
        "map name '%s' must not start with '.'", absl::CHexEscape(text)));
  }
  for (size_t i = 0; i < name.size(); ++i) {
    if (!IsNameChar(name[i])) {
      // Quote the byte as a number: it may be a control or non-UTF-8 byte.
      return absl::InvalidArgumentError(absl::StrFormat(
          "map name '%s' has character 0x%02x at position %d; allowed are "
          "A-Z a-z 0-9 . _ -",
          absl::CHexEscape(text), static_cast<unsigned char>(name[i]), i));
    }
  }
  return absl::OkStatus();
}

}  // namespace pathd::pathctl
