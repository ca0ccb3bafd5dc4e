// pathctl's tables that scripts and shells depend on: the status-to-exit-code
// map, and the completion spec against the documented synopsis.
#include "proto/planner_names.h"
#include "client/pathctl/pathctl.h"

#include <algorithm>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "gtest/gtest.h"

namespace pathd::pathctl {
namespace {

TEST(ExitCodeForStatusTest, DistinctCodesForWhatScriptsReactTo) {
  EXPECT_EQ(ExitCodeForStatus(absl::StatusCode::kOk), 0);
  EXPECT_EQ(ExitCodeForStatus(absl::StatusCode::kUnavailable), 5);
  EXPECT_EQ(ExitCodeForStatus(absl::StatusCode::kDeadlineExceeded), 6);
  EXPECT_EQ(ExitCodeForStatus(absl::StatusCode::kNotFound), 7);
  EXPECT_EQ(ExitCodeForStatus(absl::StatusCode::kUnauthenticated), 8);
  EXPECT_EQ(ExitCodeForStatus(absl::StatusCode::kPermissionDenied), 8);
  for (absl::StatusCode code :
       {absl::StatusCode::kInvalidArgument, absl::StatusCode::kAlreadyExists,
        absl::StatusCode::kAborted, absl::StatusCode::kFailedPrecondition,
        absl::StatusCode::kResourceExhausted, absl::StatusCode::kInternal,
        absl::StatusCode::kUnknown, absl::StatusCode::kCancelled}) {
    EXPECT_EQ(ExitCodeForStatus(code), kExitError)
        << absl::StatusCodeToString(code);
  }
}

TEST(ExitCodeForStatusTest, HelpDocumentsEveryExitCode) {
  const std::string usage = UsageText();
  for (int code = 0; code <= kExitDenied; ++code) {
    EXPECT_NE(usage.find(absl::StrCat("\n  ", code, "  ")), std::string::npos)
        << "exit code " << code << " is not in --help";
  }
}

bool Contains(const std::vector<std::string>& words, const std::string& word) {
  return std::find(words.begin(), words.end(), word) != words.end();
}

// Every "pathctl [flags] COMMAND [SUB]" line of the synopsis is completed:
// a command added to the synopsis but not to PathctlCompletionSpec fails here.
TEST(CompletionSpecTest, CompletesEveryCommandOfTheSynopsis) {
  const CompletionSpec spec = PathctlCompletionSpec();
  int commands_seen = 0;
  for (absl::string_view line : absl::StrSplit(SynopsisText(), '\n')) {
    line = absl::StripLeadingAsciiWhitespace(line);
    if (!absl::ConsumePrefix(&line, "pathctl ")) continue;
    absl::ConsumePrefix(&line, "[flags] ");
    const std::vector<std::string> words =
        absl::StrSplit(line, ' ', absl::SkipEmpty());
    if (words.empty() || words[0].front() == '-') continue;  // --help
    ++commands_seen;
    EXPECT_TRUE(Contains(spec.commands, words[0])) << line;
    const auto subs = spec.subcommands.find(words[0]);
    if (subs != spec.subcommands.end() && words.size() > 1) {
      EXPECT_TRUE(Contains(subs->second, words[1])) << line;
    }
  }
  EXPECT_GE(commands_seen, 15);
}

TEST(CompletionSpecTest, CompletesPlannerNamesAndFormats) {
  const CompletionSpec spec = PathctlCompletionSpec();
  const std::vector<std::string>& planners = spec.flag_values.at("planner");
  EXPECT_EQ(planners.size(), pathd::WirePlanners().size());
  EXPECT_TRUE(Contains(planners, "dstar_lite"));
  EXPECT_EQ(spec.flag_values.at("output"),
            (std::vector<std::string>{"table", "json", "csv"}));
}

}  // namespace
}  // namespace pathd::pathctl
