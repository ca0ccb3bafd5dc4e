// The robots of control sessions, per map (robot_registry.h).
#include "server/rpc/robot_registry.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace pathd::server {
namespace {

double AgeSeconds(const RobotReport& report, SteadyTime now) {
  // A report stamped after `now` (taken before the lock) is fresh, not
  // negative.
  return std::max(0.0, std::chrono::duration<double>(now - report.received).count());
}

bool Forgotten(const RobotReport& report, SteadyTime now) {
  return AgeSeconds(report, now) >= report.forget_after.count();
}

}  // namespace

void RobotRegistry::Publish(const std::string& map, uint64_t id,
                            const RobotReport& report) {
  absl::MutexLock lock(&mu_);
  std::vector<Robot>& robots = maps_[map];
  // Forgotten robots leave here, so the scan of Near stays proportional to
  // the robots that still count.
  robots.erase(std::remove_if(robots.begin(), robots.end(),
                              [&](const Robot& r) {
                                return r.id != id && Forgotten(r.report, report.received);
                              }),
               robots.end());
  for (Robot& robot : robots) {
    if (robot.id == id) {
      robot.report = report;
      return;
    }
  }
  robots.push_back(Robot{id, report});
}

void RobotRegistry::Remove(const std::string& map, uint64_t id) {
  absl::MutexLock lock(&mu_);
  auto it = maps_.find(map);
  if (it == maps_.end()) return;
  std::vector<Robot>& robots = it->second;
  robots.erase(std::remove_if(robots.begin(), robots.end(),
                              [id](const Robot& r) { return r.id == id; }),
               robots.end());
  if (robots.empty()) maps_.erase(it);
}

std::vector<MovingObstacle> RobotRegistry::Near(const std::string& map, uint64_t self,
                                                CellPoint center, double range,
                                                SteadyTime now,
                                                std::optional<double> clock) const {
  std::vector<MovingObstacle> out;
  absl::MutexLock lock(&mu_);
  auto it = maps_.find(map);
  if (it == maps_.end()) return out;
  for (const Robot& robot : it->second) {
    if (robot.id == self) continue;
    const RobotReport& r = robot.report;
    const double age = AgeSeconds(r, now);
    if (age >= r.forget_after.count()) continue;
    MovingObstacle obstacle;
    obstacle.radius = r.radius;
    if (age < r.stale_after.count()) {
      // Constant velocity since its last state: where it is now if it kept
      // its command, which it does for about one control period.
      const double dt = clock.has_value() && r.shared_clock ? *clock - r.stamp : age;
      obstacle.position = CellPoint{r.position.x + r.velocity.x * dt,
                                    r.position.y + r.velocity.y * dt};
      obstacle.velocity = r.velocity;
      obstacle.reciprocal = true;
    } else {
      obstacle.position = r.position;
      obstacle.velocity = CellPoint{0.0, 0.0};
      obstacle.reciprocal = false;
    }
    const double distance = std::hypot(obstacle.position.x - center.x,
                                       obstacle.position.y - center.y);
    if (distance - obstacle.radius > range) continue;
    out.push_back(obstacle);
  }
  return out;
}

std::map<std::string, int64_t> RobotRegistry::Counts(SteadyTime now) const {
  std::map<std::string, int64_t> out;
  absl::MutexLock lock(&mu_);
  for (const auto& [map, robots] : maps_) {
    int64_t n = 0;
    for (const Robot& robot : robots) n += Forgotten(robot.report, now) ? 0 : 1;
    if (n > 0) out[map] = n;
  }
  return out;
}

}  // namespace pathd::server
