// FleetSchedule: the plan's order of passage per cell, and releases from it.
#include "core/fleet/execution.h"

#include <cstdlib>
#include <utility>

namespace pathd {

FleetSchedule::FleetSchedule(std::vector<std::vector<Cell>> paths,
                             int32_t width)
    : paths_(std::move(paths)),
      width_(width),
      progress_(paths_.size(), 0),
      removed_(paths_.size(), false) {
  for (int r = 0; r < robots(); ++r) {
    // The visit of robot r to each cell that is still open (its last step
    // is the previous one), as an index into visits_[cell].
    absl::flat_hash_map<uint32_t, size_t> open;
    const int64_t last_index = static_cast<int64_t>(paths_[r].size()) - 1;
    for (int64_t s = 0; s <= last_index; ++s) {
      uint32_t cells[4];
      const int n = SweepOf(r, s, cells);
      for (int k = 0; k < n; ++k) {
        std::vector<Visit>& list = visits_[cells[k]];
        auto it = open.find(cells[k]);
        if (it != open.end() && list[it->second].last == s - 1) {
          list[it->second].last = s;
        } else {
          open[cells[k]] = list.size();
          list.push_back(Visit{r, s, s});
        }
      }
    }
    // Parked at the goal after the last index, for ever.
    const Cell goal = paths_[r].back();
    const uint32_t g =
        static_cast<uint32_t>(goal.y) * static_cast<uint32_t>(width_) +
        static_cast<uint32_t>(goal.x);
    visits_[g][open.at(g)].last = kForever;
  }
}

int FleetSchedule::SweepOf(int robot, int64_t s, uint32_t out[4]) const {
  const std::vector<Cell>& path = paths_[robot];
  const auto index = [this](int32_t x, int32_t y) {
    return static_cast<uint32_t>(y) * static_cast<uint32_t>(width_) +
           static_cast<uint32_t>(x);
  };
  const int64_t last_index = static_cast<int64_t>(path.size()) - 1;
  if (s >= last_index) {
    out[0] = index(path.back().x, path.back().y);
    return 1;
  }
  const Cell a = path[s];
  const Cell b = path[s + 1];
  out[0] = index(a.x, a.y);
  if (a == b) return 1;
  out[1] = index(b.x, b.y);
  if (a.x == b.x || a.y == b.y) return 2;
  out[2] = index(a.x, b.y);
  out[3] = index(b.x, a.y);
  return 4;
}

bool FleetSchedule::Free(int robot, int64_t s, uint32_t cell) const {
  auto it = visits_.find(cell);
  if (it == visits_.end()) return true;
  for (const Visit& v : it->second) {
    if (v.robot == robot || removed_[v.robot] || v.first >= s) continue;
    // Planned earlier: robot v.robot must be past the visit's last step.
    if (v.last == kForever || progress_[v.robot] < v.last + 1) return false;
  }
  return true;
}

int64_t FleetSchedule::Release(int robot) const {
  const int64_t last_index = static_cast<int64_t>(paths_[robot].size()) - 1;
  int64_t release = progress_[robot];
  for (int64_t s = progress_[robot]; s < last_index; ++s) {
    uint32_t cells[4];
    const int n = SweepOf(robot, s, cells);
    for (int k = 0; k < n; ++k) {
      if (!Free(robot, s, cells[k])) return release;
    }
    release = s + 1;
  }
  return release;
}

bool FleetSchedule::Report(int robot, Cell cell) {
  const std::vector<Cell>& path = paths_[robot];
  const int64_t release = Release(robot);
  int64_t k = progress_[robot];
  while (k <= release && path[k] != cell) ++k;
  if (k > release) return false;
  while (k + 1 <= release && path[k + 1] == cell) ++k;
  progress_[robot] = k;
  return true;
}

void FleetSchedule::Remove(int robot) { removed_[robot] = true; }

}  // namespace pathd
