// Helpers shared by the map reader tests (map_io_test.cc, ros_map_test.cc):
// test data paths, temporary files and status expectations.
#ifndef PATHD_TESTS_CORE_MAP_IO_MAP_IO_TEST_UTIL_H_
#define PATHD_TESTS_CORE_MAP_IO_MAP_IO_TEST_UTIL_H_

#include <fstream>
#include <initializer_list>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"

namespace pathd::testing_map_io {

inline constexpr char kTestData[] = "tests/testdata/map_io";
inline constexpr char kBenchmarks[] = "../shared/benchmarks/movingai";

// 4 wide, 3 high; one of each character class.
inline constexpr char kTinyMap[] =
    "type octile\n"
    "height 3\n"
    "width 4\n"
    "map\n"
    ".@..\n"
    ".T.G\n"
    "S..W\n";

inline std::string TestDataPath(std::string_view name) {
  return absl::StrCat(kTestData, "/", std::string(name));
}

// Writes a file under the test's temporary folder and returns its path.
inline std::string WriteTempFile(std::string_view name, std::string_view contents) {
  const std::string path =
      absl::StrCat(::testing::TempDir(), "/map_io_test_", std::string(name));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(contents.data(), static_cast<std::streamsize>(contents.size()));
  out.close();
  EXPECT_TRUE(out.good()) << path;
  return path;
}

// Expects INVALID_ARGUMENT whose message contains every fragment.
// A size limit: RESOURCE_EXHAUSTED, so the server can tell it from a syntax
// error and answer as its --max_map_cells contract says.
inline void ExpectTooBig(const absl::Status& status,
                  std::initializer_list<std::string_view> fragments) {
  EXPECT_EQ(status.code(), absl::StatusCode::kResourceExhausted) << status;
  for (std::string_view fragment : fragments) {
    EXPECT_NE(std::string(status.message()).find(fragment), std::string::npos)
        << "'" << fragment << "' not in: " << status;
  }
}

inline void ExpectInvalid(const absl::Status& status,
                   std::initializer_list<std::string_view> fragments) {
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << status;
  for (std::string_view fragment : fragments) {
    EXPECT_NE(std::string(status.message()).find(fragment), std::string::npos)
        << "'" << fragment << "' not in: " << status;
  }
}

}  // namespace pathd::testing_map_io

#endif  // PATHD_TESTS_CORE_MAP_IO_MAP_IO_TEST_UTIL_H_
