// The rule of mapf.h, re-derived with standard containers only.
#include "tests/testing/fleet_checker.h"

#include <algorithm>
#include <cstdlib>
#include <map>
#include <set>
#include <utility>

namespace pathd::testing {
namespace {

bool Usable(const Grid& g, int32_t x, int32_t y, bool unknown_is_free) {
  if (x < 0 || y < 0 || x >= g.width() || y >= g.height()) return false;
  const uint8_t c = g.cost(x, y);
  return c <= 252 || (unknown_is_free && c == 255);
}

std::string At(size_t robot, size_t t, Cell c) {
  return "robot " + std::to_string(robot) + " at t=" + std::to_string(t) +
         " cell (" + std::to_string(c.x) + ", " + std::to_string(c.y) + ")";
}

}  // namespace

FleetCheckResult CheckFleetPlan(const std::vector<FleetCheckRobot>& robots,
                                bool eight_connected, bool unknown_is_free,
                                const std::vector<std::vector<Cell>>& paths) {
  FleetCheckResult r;
  if (paths.size() != robots.size()) {
    r.error = "paths for " + std::to_string(paths.size()) +
              " robots, expected " + std::to_string(robots.size());
    return r;
  }
  size_t longest = 0;
  for (size_t i = 0; i < robots.size(); ++i) {
    const std::vector<Cell>& p = paths[i];
    const Grid& g = *robots[i].grid;
    if (p.empty()) {
      r.error = "robot " + std::to_string(i) + ": empty path";
      return r;
    }
    if (!(p.front() == robots[i].start)) {
      r.error = At(i, 0, p.front()) + ": not its start";
      return r;
    }
    if (!(p.back() == robots[i].goal)) {
      r.error = At(i, p.size() - 1, p.back()) + ": path ends off its goal";
      return r;
    }
    for (size_t t = 0; t < p.size(); ++t) {
      if (!Usable(g, p[t].x, p[t].y, unknown_is_free)) {
        r.error = At(i, t, p[t]) + ": not traversable";
        return r;
      }
      if (t == 0) continue;
      const int dx = p[t].x - p[t - 1].x;
      const int dy = p[t].y - p[t - 1].y;
      if (std::abs(dx) > 1 || std::abs(dy) > 1) {
        r.error = At(i, t, p[t]) + ": a jump";
        return r;
      }
      if (dx != 0 && dy != 0) {
        if (!eight_connected) {
          r.error = At(i, t, p[t]) + ": diagonal on a 4-connected grid";
          return r;
        }
        if (!Usable(g, p[t].x, p[t - 1].y, unknown_is_free) ||
            !Usable(g, p[t - 1].x, p[t].y, unknown_is_free)) {
          r.error = At(i, t, p[t]) + ": cuts a corner";
          return r;
        }
      }
    }
    int64_t cost = static_cast<int64_t>(p.size()) - 1;
    while (cost > 0 && p[cost - 1] == p.back()) --cost;
    r.costs.push_back(cost);
    r.sum_of_costs += cost;
    r.makespan = std::max(r.makespan, cost);
    longest = std::max(longest, p.size());
  }
  // Every step until the last robot's path ends (after that all are parked
  // on distinct goals, which the t = longest - 1 step already covers).
  for (size_t t = 0; t + 1 < std::max<size_t>(longest, 2); ++t) {
    std::map<std::pair<int32_t, int32_t>, size_t> owner;
    for (size_t i = 0; i < paths.size(); ++i) {
      const std::vector<Cell>& p = paths[i];
      const Cell a = p[std::min(t, p.size() - 1)];
      const Cell b = p[std::min(t + 1, p.size() - 1)];
      std::set<std::pair<int32_t, int32_t>> swept{{a.x, a.y}, {b.x, b.y}};
      if (a.x != b.x && a.y != b.y) {
        swept.insert({b.x, a.y});
        swept.insert({a.x, b.y});
      }
      for (const auto& c : swept) {
        const auto [it, fresh] = owner.emplace(c, i);
        if (!fresh) {
          r.error = "robots " + std::to_string(it->second) + " and " +
                    std::to_string(i) + " both sweep cell (" +
                    std::to_string(c.first) + ", " + std::to_string(c.second) +
                    ") during step " + std::to_string(t) + " -> " +
                    std::to_string(t + 1);
          return r;
        }
      }
    }
  }
  r.ok = true;
  return r;
}

}  // namespace pathd::testing
