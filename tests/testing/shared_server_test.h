// A gtest base for suites whose tests share one InProcessServer
// (in_process_server.h): started before the suite's first test with the
// options the suite names, shut down after its last.
#ifndef PATHD_TESTS_TESTING_SHARED_SERVER_TEST_H_
#define PATHD_TESTS_TESTING_SHARED_SERVER_TEST_H_

#include "absl/status/status.h"
#include "gtest/gtest.h"
#include "server/server.h"
#include "tests/testing/in_process_server.h"

namespace pathd::testing {

// `Suite` derives from SharedServerTest<Suite> and defines
// `static server::ServerOptions SuiteOptions()`. A suite's own
// SetUpTestSuite calls this one first and returns on a fatal failure.
template <typename Suite>
class SharedServerTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    server_ = new InProcessServer(Suite::SuiteOptions());
    const absl::Status started = server_->Start();
    ASSERT_TRUE(started.ok()) << started;
  }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }

  static InProcessServer* server_;
};

template <typename Suite>
InProcessServer* SharedServerTest<Suite>::server_ = nullptr;

}  // namespace pathd::testing

#endif  // PATHD_TESTS_TESTING_SHARED_SERVER_TEST_H_
