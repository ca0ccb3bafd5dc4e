// Which Moving AI maps the benchmark programs run over.
#ifndef PATHD_TESTS_BENCH_MOVINGAI_MAPS_H_
#define PATHD_TESTS_BENCH_MOVINGAI_MAPS_H_

#include <algorithm>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "absl/strings/str_split.h"

namespace pathd::bench {

// The maps named in `list` (comma-separated, relative to `root`), or, when it
// is empty, every "*.map" under `root`, sorted; empty when `root` is missing.
inline std::vector<std::string> MovingAiMaps(const std::filesystem::path& root,
                                             const std::string& list) {
  if (!list.empty()) return absl::StrSplit(list, ',', absl::SkipEmpty());
  std::vector<std::string> maps;
  std::error_code ec;
  for (const auto& e : std::filesystem::recursive_directory_iterator(root, ec)) {
    if (e.path().extension() == ".map") {
      maps.push_back(std::filesystem::relative(e.path(), root).string());
    }
  }
  std::sort(maps.begin(), maps.end());
  return maps;
}

}  // namespace pathd::bench

#endif  // PATHD_TESTS_BENCH_MOVINGAI_MAPS_H_
