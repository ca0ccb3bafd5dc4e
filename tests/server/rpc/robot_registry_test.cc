// The robot registry with explicit times: fresh robots extrapolated and
// reciprocal, stale ones still and not, forgotten ones gone, the range and
// self filters, removal, counts; and many threads publishing and reading at
// once (for ThreadSanitizer).
#include "server/rpc/robot_registry.h"

#include <chrono>
#include <cmath>
#include <string>
#include <thread>
#include <vector>

#include "gtest/gtest.h"

namespace pathd::server {
namespace {

using std::chrono::milliseconds;

RobotReport Report(double x, double y, double vx, double vy, SteadyTime at) {
  RobotReport r;
  r.position = CellPoint{x, y};
  r.velocity = CellPoint{vx, vy};
  r.radius = 2.0;
  r.received = at;
  r.stale_after = std::chrono::duration<double>(1.0);
  r.forget_after = std::chrono::duration<double>(5.0);
  return r;
}

TEST(RobotRegistryTest, FreshStaleForgotten) {
  RobotRegistry registry;
  const SteadyTime t0 = std::chrono::steady_clock::now();
  registry.Publish("m", 1, Report(10, 10, 4, -2, t0));
  registry.Publish("m", 2, Report(0, 0, 0, 0, t0));

  // Robot 2 asks 0.5 s later: robot 1 moved on by its velocity.
  std::vector<MovingObstacle> near = registry.Near("m", 2, {0, 0}, 100, t0 + milliseconds(500));
  ASSERT_EQ(near.size(), 1u);
  EXPECT_DOUBLE_EQ(near[0].position.x, 12.0);
  EXPECT_DOUBLE_EQ(near[0].position.y, 9.0);
  EXPECT_DOUBLE_EQ(near[0].velocity.x, 4.0);
  EXPECT_TRUE(near[0].reciprocal);
  EXPECT_DOUBLE_EQ(near[0].radius, 2.0);

  // 2 s: stale, where it last was, still, not reacting.
  near = registry.Near("m", 2, {0, 0}, 100, t0 + milliseconds(2000));
  ASSERT_EQ(near.size(), 1u);
  EXPECT_DOUBLE_EQ(near[0].position.x, 10.0);
  EXPECT_DOUBLE_EQ(near[0].velocity.x, 0.0);
  EXPECT_FALSE(near[0].reciprocal);

  // 6 s: forgotten.
  EXPECT_TRUE(registry.Near("m", 2, {0, 0}, 100, t0 + milliseconds(6000)).empty());
  EXPECT_EQ(registry.Counts(t0 + milliseconds(6000)).count("m"), 0u);
}

// ControlOptions.shared_clock: a robot on the shared clock asking at its
// stamp sees another robot on it moved on by the difference of the stamps
// (forwards or backwards), whatever the server's clock says; a robot off the
// shared clock is still moved on by the server's.
TEST(RobotRegistryTest, SharedClockUsesStampDifferences) {
  RobotRegistry registry;
  const SteadyTime t0 = std::chrono::steady_clock::now();
  RobotReport shared = Report(10, 10, 4, -2, t0);
  shared.shared_clock = true;
  shared.stamp = 100.0;
  registry.Publish("m", 1, shared);
  RobotReport own = Report(-10, 0, 2, 0, t0);
  own.stamp = 7.0;  // its own clock: not comparable
  registry.Publish("m", 3, own);

  // Simulated time 0.1 s on; the server's clock only 1 ms.
  std::vector<MovingObstacle> near =
      registry.Near("m", 2, {0, 0}, 100, t0 + milliseconds(1), 100.1);
  ASSERT_EQ(near.size(), 2u);
  const MovingObstacle& a = near[0].velocity.x == 4 ? near[0] : near[1];
  const MovingObstacle& b = near[0].velocity.x == 4 ? near[1] : near[0];
  EXPECT_NEAR(a.position.x, 10.4, 1e-12);
  EXPECT_NEAR(a.position.y, 9.8, 1e-12);
  EXPECT_NEAR(b.position.x, -10.0 + 2 * 0.001, 1e-9);
  // A report from later than the asking robot's stamp is moved back.
  near = registry.Near("m", 2, {0, 0}, 100, t0 + milliseconds(1), 99.5);
  const MovingObstacle& back = near[0].velocity.x == 4 ? near[0] : near[1];
  EXPECT_NEAR(back.position.x, 8.0, 1e-12);
  // Without a clock of its own the server's is used for everyone.
  near = registry.Near("m", 2, {0, 0}, 100, t0 + milliseconds(500));
  const MovingObstacle& server = near[0].velocity.x == 4 ? near[0] : near[1];
  EXPECT_NEAR(server.position.x, 12.0, 1e-12);
}

TEST(RobotRegistryTest, RangeSelfMapsAndRemoval) {
  RobotRegistry registry;
  const SteadyTime t0 = std::chrono::steady_clock::now();
  registry.Publish("m", 1, Report(10, 0, 0, 0, t0));
  registry.Publish("m", 2, Report(0, 0, 0, 0, t0));
  registry.Publish("other", 3, Report(1, 0, 0, 0, t0));
  // Centre 10 away, radius 2: within a range of 8 (disc edge), not 7.9.
  EXPECT_EQ(registry.Near("m", 2, {0, 0}, 8.0, t0).size(), 1u);
  EXPECT_TRUE(registry.Near("m", 2, {0, 0}, 7.9, t0).empty());
  // Never itself; other maps never.
  EXPECT_TRUE(registry.Near("m", 1, {10, 0}, 5.0, t0).empty());
  EXPECT_EQ(registry.Counts(t0).at("m"), 2);
  EXPECT_EQ(registry.Counts(t0).at("other"), 1);
  registry.Remove("m", 1);
  EXPECT_TRUE(registry.Near("m", 2, {0, 0}, 100, t0).empty());
  registry.Remove("other", 3);
  EXPECT_EQ(registry.Counts(t0).count("other"), 0u);
}

TEST(RobotRegistryTest, ConcurrentPublishersAndReaders) {
  RobotRegistry registry;
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&registry, t] {
      for (int i = 0; i < 500; ++i) {
        const SteadyTime now = std::chrono::steady_clock::now();
        registry.Publish("m", static_cast<uint64_t>(t), Report(t, i, 1, 0, now));
        const auto near = registry.Near("m", static_cast<uint64_t>(t), {0, 0}, 1e6, now);
        EXPECT_LE(near.size(), 7u);
        if (i % 100 == 50) registry.Remove("m", static_cast<uint64_t>(t));
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(registry.Counts(std::chrono::steady_clock::now()).at("m"), 8);
}

}  // namespace
}  // namespace pathd::server
