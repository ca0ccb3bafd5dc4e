// A fresh directory for one test or suite under the system's temporary
// folder, removed with everything in it when the TempDir goes away.
#ifndef PATHD_TESTS_TESTING_TEMP_DIR_H_
#define PATHD_TESTS_TESTING_TEMP_DIR_H_

#include <stdlib.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <string>
#include <system_error>

namespace pathd::testing {

class TempDir {
 public:
  // <temp folder>/<prefix>_XXXXXX by mkdtemp; path() is empty when that
  // failed, error() saying why.
  explicit TempDir(const std::string& prefix) {
    std::string name =
        (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
    if (mkdtemp(name.data()) == nullptr) {
      error_ = "mkdtemp " + name + ": " + strerror(errno);
    } else {
      path_ = name;
    }
  }
  ~TempDir() {
    std::error_code ignored;
    if (!path_.empty()) std::filesystem::remove_all(path_, ignored);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  const std::string& error() const { return error_; }

 private:
  std::filesystem::path path_;
  std::string error_;
};

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_TEMP_DIR_H_
