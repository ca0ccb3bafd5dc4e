// pathctl's progress bar, driven by a fake clock: when it draws (never when
// disabled, not before kShowAfter, at most every kRedrawInterval, at once
// after Clear), what a line looks like for each unit, and how it ends.
#include "client/pathctl/progress.h"

#include <sstream>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/time/time.h"
#include "gtest/gtest.h"

namespace pathd::pathctl {
namespace {

constexpr char kErase[] = "\x1b[K";

class FakeClock {
 public:
  absl::Time Now() const { return now_; }
  void Advance(absl::Duration d) { now_ += d; }
  ProgressBar::Clock AsClock() {
    return [this] { return now_; };
  }

 private:
  absl::Time now_ = absl::FromUnixSeconds(1000);
};

TEST(ProgressBarsWantedTest, OnlyForTwoTerminalsWithoutNoProgress) {
  EXPECT_TRUE(ProgressBarsWanted(true, true, false));
  EXPECT_FALSE(ProgressBarsWanted(false, true, false));  // stdout redirected
  EXPECT_FALSE(ProgressBarsWanted(true, false, false));  // stderr to a log
  EXPECT_FALSE(ProgressBarsWanted(true, true, true));    // --no_progress
}

TEST(ProgressBarTest, DisabledBarWritesNothing) {
  FakeClock clock;
  std::ostringstream err;
  {
    ProgressBar bar(err, "batch", 10, ProgressBar::Unit::kCount, false,
                    clock.AsClock());
    clock.Advance(absl::Seconds(5));
    bar.Update(5);
    bar.Clear();
    bar.Finish();
  }
  EXPECT_EQ(err.str(), "");
}

TEST(ProgressBarTest, WaitsForShowAfterThenRateLimits) {
  FakeClock clock;
  std::ostringstream err;
  ProgressBar bar(err, "batch", 1000, ProgressBar::Unit::kCount, true,
                  clock.AsClock());
  clock.Advance(ProgressBar::kShowAfter - absl::Milliseconds(1));
  bar.Update(10);
  EXPECT_EQ(err.str(), "") << "quick work shows no bar";

  clock.Advance(absl::Milliseconds(1));  // 0.5 s in
  bar.Update(250);
  EXPECT_EQ(
      err.str(),
      absl::StrCat("\rbatch [######..................]  25%  250/1000  500.0/s",
                   kErase));

  err.str("");
  clock.Advance(ProgressBar::kRedrawInterval - absl::Milliseconds(1));
  bar.Update(300);
  EXPECT_EQ(err.str(), "") << "redrawn too soon";
  clock.Advance(absl::Milliseconds(1));  // 0.6 s in
  bar.Update(420, "400 found, 20 no path, 0 errors");
  EXPECT_EQ(
      err.str(),
      absl::StrCat("\rbatch [##########..............]  42%  420/1000  700.0/s"
                   "  400 found, 20 no path, 0 errors",
                   kErase));
}

TEST(ProgressBarTest, ClearErasesAndTheNextUpdateRedrawsAtOnce) {
  FakeClock clock;
  std::ostringstream err;
  ProgressBar bar(err, "batch", 4, ProgressBar::Unit::kCount, true,
                  clock.AsClock());
  clock.Advance(absl::Seconds(1));
  bar.Update(1);
  err.str("");
  bar.Clear();
  EXPECT_EQ(err.str(), absl::StrCat("\r", kErase));
  err.str("");
  bar.Clear();
  EXPECT_EQ(err.str(), "") << "nothing to erase twice";
  bar.Update(2);  // no time passed: drawn anyway, under the caller's line
  EXPECT_EQ(err.str(),
            absl::StrCat("\rbatch [############............]  50%  2/4  2.0/s",
                         kErase));
}

TEST(ProgressBarTest, FinishDrawsTheLastStateAndEndsTheLineOnce) {
  FakeClock clock;
  std::ostringstream err;
  {
    ProgressBar bar(err, "batch", 4, ProgressBar::Unit::kCount, true,
                    clock.AsClock());
    clock.Advance(absl::Seconds(1));
    bar.Update(1);
    clock.Advance(absl::Milliseconds(10));
    bar.Update(4);  // rate-limited, but Finish shows it
    err.str("");
    clock.Advance(absl::Milliseconds(990));
    bar.Finish();
    EXPECT_EQ(
        err.str(),
        absl::StrCat("\rbatch [########################] 100%  4/4  2.0/s",
                     kErase, "\n"));
    err.str("");
    bar.Finish();
    bar.Update(5);
  }  // the destructor finishes too, but only once
  EXPECT_EQ(err.str(), "");
}

TEST(ProgressBarTest, FinishWithoutAShownBarPrintsNothing) {
  FakeClock clock;
  std::ostringstream err;
  ProgressBar bar(err, "batch", 4, ProgressBar::Unit::kCount, true,
                  clock.AsClock());
  bar.Update(4);
  bar.Finish();
  EXPECT_EQ(err.str(), "");
}

TEST(ProgressBarTest, RendersBytesSecondsAndUnknownTotals) {
  FakeClock clock;
  std::ostringstream err;
  const absl::Time start = clock.Now();
  clock.Advance(absl::Seconds(2));
  ProgressBar bytes(err, "reading", 3 * 1024 * 1024, ProgressBar::Unit::kBytes,
                    true, clock.AsClock(), start);
  bytes.Update(1.5 * 1024 * 1024);
  EXPECT_EQ(
      bytes.Render(clock.Now()),
      "reading [############............]  50%  1.5/3.0 MiB  768.0 KiB/s");

  ProgressBar seconds(err, "bench  ", 10, ProgressBar::Unit::kSeconds, true,
                      clock.AsClock(), start);
  seconds.Update(4.25, "1200 requests  600 req/s now  0 errors");
  EXPECT_EQ(
      seconds.Render(clock.Now()),
      "bench   [##########..............]  42%  4.2/10.0 s  1200 requests  "
      "600 req/s now  0 errors");

  ProgressBar open_ended(err, "sending room.map (0.1 MiB)", 0,
                         ProgressBar::Unit::kSeconds, true, clock.AsClock(),
                         start);
  open_ended.Update(2);
  EXPECT_EQ(open_ended.Render(clock.Now()),
            "sending room.map (0.1 MiB)  2.0 s");

  // Past the total (a count that overshoots) the bar stays full.
  ProgressBar over(err, "x", 10, ProgressBar::Unit::kCount, true,
                   clock.AsClock(), start);
  over.Update(12);
  EXPECT_EQ(over.Render(clock.Now()),
            "x [########################] 100%  12/10  6.0/s");
}

TEST(ProgressBarTest, AStartInThePastShowsAtOnce) {
  FakeClock clock;
  std::ostringstream err;
  ProgressBar bar(err, "bench  ", 10, ProgressBar::Unit::kSeconds, true,
                  clock.AsClock(), clock.Now() - absl::Seconds(1));
  bar.Update(1);
  EXPECT_EQ(
      err.str(),
      absl::StrCat("\rbench   [##......................]  10%  1.0/10.0 s",
                   kErase));
}

}  // namespace
}  // namespace pathd::pathctl
