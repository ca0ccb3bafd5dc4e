// Files and child processes for the end-to-end tests: ReadFile/WriteFile,
// and the names the tests use for tests/testing/subprocess.h. pathd itself
// is started with tests/testing/pathd_process.h.
#ifndef PATHD_TESTS_E2E_PROCESS_H_
#define PATHD_TESTS_E2E_PROCESS_H_

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "gtest/gtest.h"
#include "tests/testing/pathd_process.h"
#include "tests/testing/subprocess.h"

namespace pathd::e2e {

using testing::kListeningPrefix;
using testing::PathdProcess;
using testing::PathdProcessOptions;
using testing::Spawn;
using testing::WaitForExit;

// A file's whole content, "" when it cannot be read (a log not written yet).
inline std::string ReadFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Writes `contents` to `path`, failing the test when it cannot.
inline void WriteFile(const std::filesystem::path& path,
                      const std::string& contents) {
  std::ofstream out(path, std::ios::binary);
  out << contents;
  ASSERT_TRUE(out.good()) << "cannot write " << path;
}

// pipe2 with O_CLOEXEC, failing the test when it cannot.
inline void MakePipe(int fds[2]) {
  ASSERT_TRUE(testing::MakePipe(fds)) << strerror(errno);
}

}  // namespace pathd::e2e

#endif  // PATHD_TESTS_E2E_PROCESS_H_
