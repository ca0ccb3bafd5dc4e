// Tests of the navigate script parser: every command, comments, and the
// file:line messages for bad lines; the shipped demo script parses.
#include "client/pathctl/navigate_script.h"

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/time/time.h"
#include "gtest/gtest.h"

namespace pathd::pathctl {
namespace {

using Kind = ScriptStep::Kind;

TEST(NavigateScriptTest, ParsesEveryCommand) {
  const absl::StatusOr<std::vector<ScriptStep>> steps = ParseNavigateScript(
      "# a robot run\n"
      "\n"
      "move 3 2   # first step\n"
      "follow 4\n"
      "block 2 2\n"
      "free 1 0\n"
      "cost 4 1 100\n"
      "cost 4 1 lethal\n"
      "rect 5 1 2 3 inscribed\n"
      "private block 0 3\n"
      "\tprivate rect 1 1 1 1 free\r\n"
      "wait 250\n"
      "expect-push\n"
      "expect-push 40\n",
      "run.nav");
  ASSERT_TRUE(steps.ok()) << steps.status();
  ASSERT_EQ(steps->size(), 12u);
  const std::vector<ScriptStep>& s = *steps;

  EXPECT_EQ(s[0].kind, Kind::kMove);
  EXPECT_EQ(s[0].cell.x(), 3);
  EXPECT_EQ(s[0].cell.y(), 2);
  EXPECT_EQ(s[0].where, "run.nav:3");
  EXPECT_EQ(s[0].text, "move 3 2");

  EXPECT_EQ(s[1].kind, Kind::kFollow);
  EXPECT_EQ(s[1].steps, 4);

  EXPECT_EQ(s[2].kind, Kind::kObserve);
  EXPECT_FALSE(s[2].observation.session_only());
  ASSERT_EQ(s[2].observation.changes_size(), 1);
  EXPECT_EQ(s[2].observation.changes(0).cell().x(), 2);
  EXPECT_EQ(s[2].observation.changes(0).cell().y(), 2);
  EXPECT_EQ(s[2].observation.changes(0).cost(), 254u);
  EXPECT_EQ(s[3].observation.changes(0).cost(), 0u);
  EXPECT_EQ(s[4].observation.changes(0).cost(), 100u);
  EXPECT_EQ(s[5].observation.changes(0).cost(), 254u);

  // Corners in any order name the same rectangle.
  const v1::CellChange& rect = s[6].observation.changes(0);
  ASSERT_TRUE(rect.has_rect());
  EXPECT_EQ(rect.rect().x_min(), 2);
  EXPECT_EQ(rect.rect().y_min(), 1);
  EXPECT_EQ(rect.rect().x_max(), 5);
  EXPECT_EQ(rect.rect().y_max(), 3);
  EXPECT_EQ(rect.cost(), 253u);

  EXPECT_TRUE(s[7].observation.session_only());
  EXPECT_EQ(s[7].observation.changes(0).cost(), 254u);
  EXPECT_TRUE(s[8].observation.session_only());
  EXPECT_TRUE(s[8].observation.changes(0).has_rect());
  EXPECT_EQ(s[8].where, "run.nav:11");

  EXPECT_EQ(s[9].kind, Kind::kWait);
  EXPECT_EQ(s[9].duration, absl::Milliseconds(250));
  EXPECT_EQ(s[10].kind, Kind::kExpectPush);
  EXPECT_EQ(s[10].duration, kDefaultExpectPushWait);
  EXPECT_EQ(s[11].duration, absl::Milliseconds(40));
}

TEST(NavigateScriptTest, PoseTakesFractionalCellsAndAHeading) {
  const auto steps = ParseNavigateScript("pose 3.25 2.5 -1.5708\n", "pose.nav");
  ASSERT_TRUE(steps.ok()) << steps.status();
  ASSERT_EQ(steps->size(), 1u);
  EXPECT_EQ((*steps)[0].kind, Kind::kPose);
  EXPECT_DOUBLE_EQ((*steps)[0].pose.x(), 3.25);
  EXPECT_DOUBLE_EQ((*steps)[0].pose.y(), 2.5);
  EXPECT_DOUBLE_EQ((*steps)[0].pose.yaw(), -1.5708);
}

TEST(NavigateScriptTest, EmptyScriptHasNoSteps) {
  const auto steps = ParseNavigateScript("# nothing\n\n   \n", "empty.nav");
  ASSERT_TRUE(steps.ok()) << steps.status();
  EXPECT_TRUE(steps->empty());
}

TEST(NavigateScriptTest, BadLinesNameFileLineAndProblem) {
  struct Case {
    std::string line;
    std::string says;
  };
  const std::vector<Case> cases = {
      {"jump 1 2", "unknown command 'jump'"},
      {"move 1", "move takes X Y, got 'move 1'"},
      {"move 1 2 3", "move takes X Y"},
      {"move one 2", "X: 'one' is not an integer"},
      {"pose 1 2", "pose takes X Y YAW"},
      {"pose 1 2 east", "YAW: 'east' is not a finite number"},
      {"pose nan 2 0", "X: 'nan' is not a finite number"},
      {"follow", "follow takes N"},
      {"follow 0", "follow needs N >= 1"},
      {"block 1", "block takes X Y"},
      {"cost 1 2", "cost takes X Y COST"},
      {"cost 1 2 300", "COST: '300'"},
      {"rect 0 0 1 1", "rect takes X0 Y0 X1 Y1 COST"},
      {"rect 0 0 1 y 5", "Y1: 'y' is not an integer"},
      {"private", "private must be followed by block, free, cost or rect"},
      {"private move 1 1", "private must be followed by"},
      {"wait", "wait takes MS"},
      {"wait -5", "MS: '-5'"},
      {"wait 1h", "MS: '1h'"},
      {"expect-push 10 20", "expect-push takes at most MS"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.line);
    const auto steps =
        ParseNavigateScript("# header\nmove 0 0\n" + c.line + "\n", "bad.nav");
    ASSERT_FALSE(steps.ok());
    EXPECT_EQ(steps.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(steps.status().message().substr(0, 10), "bad.nav:3:")
        << steps.status();
    EXPECT_NE(steps.status().message().find(c.says), std::string::npos)
        << steps.status();
  }
}

// The demo that ships with the project must stay valid.
TEST(NavigateScriptTest, ShippedDemoParses) {
  const std::string path = "examples/navigate/dstar_example.nav";
  std::ifstream file(path);
  ASSERT_TRUE(file) << "cannot read " << path << " (run from the source root)";
  std::stringstream text;
  text << file.rdbuf();
  const auto steps = ParseNavigateScript(text.str(), path);
  ASSERT_TRUE(steps.ok()) << steps.status();
  ASSERT_EQ(steps->size(), 3u);
  EXPECT_EQ((*steps)[0].kind, Kind::kMove);
  EXPECT_EQ((*steps)[1].kind, Kind::kObserve);
  EXPECT_EQ((*steps)[1].observation.changes(0).cell().x(), 2);
  EXPECT_EQ((*steps)[1].observation.changes(0).cell().y(), 2);
  EXPECT_EQ((*steps)[2].kind, Kind::kFollow);
}

}  // namespace
}  // namespace pathd::pathctl
