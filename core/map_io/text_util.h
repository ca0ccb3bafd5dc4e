// Small text helpers the map readers share (internal to core).
#ifndef PATHD_CORE_MAP_IO_TEXT_UTIL_H_
#define PATHD_CORE_MAP_IO_TEXT_UTIL_H_

#include <string>
#include <string_view>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"

namespace pathd::internal {

// Abseil here is built with its own string_view
// (ABSL_OPTION_USE_STD_STRING_VIEW is 0), so the std::string_view of the public
// API is converted once at entry.
inline absl::string_view ToAbsl(std::string_view s) {
  return absl::string_view(s.data(), s.size());
}

// Quotes untrusted text for an error message: escaped, and cut short so a
// binary file fed to a parser cannot produce a megabyte-long message.
inline std::string Quote(absl::string_view text) {
  constexpr size_t kMaxQuoted = 40;
  if (text.size() <= kMaxQuoted) return absl::StrCat("'", absl::CHexEscape(text), "'");
  return absl::StrCat("'", absl::CHexEscape(text.substr(0, kMaxQuoted)), "...'");
}

}  // namespace pathd::internal

#endif  // PATHD_CORE_MAP_IO_TEXT_UTIL_H_
