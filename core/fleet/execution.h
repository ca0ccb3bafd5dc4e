// Executing a timed multi-robot plan (mapf.h) with robots that do not keep
// its clock. Real robots run late, stop for a person and start again, so
// following the plan's time steps would soon break its guarantees. Instead
// the plan fixes the order in which robots pass each cell, and a robot may
// make its next move only once every robot the plan sends through the
// cells of that move before it has gone through them: the plan's action
// dependency graph, executed as Hönig, Kiesel, Tinka, Durham & Ayanian
// describe in "Persistent and Robust Execution of MAPF Schedules in
// Warehouses" (IEEE RA-L, 2019). The dependencies point from later time
// steps to earlier ones, so they never wait in a cycle: every robot reaches
// its goal if every robot keeps moving when allowed, and no two robots ever
// sweep one cell at once, whatever their speeds.
//
// The model is mapf.h's: the step from index s to s + 1 of a path sweeps the
// cells at s and s + 1 and, for a diagonal move, the two side cells; after
// its last index a robot stays at its goal for ever. A robot's progress is
// the index of its path where it last reported standing; its release is the
// furthest index it may drive to now (each move in order, reporting as it
// arrives). Thread-compatible.
#ifndef PATHD_CORE_FLEET_EXECUTION_H_
#define PATHD_CORE_FLEET_EXECUTION_H_

#include <cstdint>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "core/map/grid.h"

namespace pathd {

class FleetSchedule {
 public:
  // `paths[i][t]`: robot i's cell at time step t, as PlanFleet returns them
  // (conflict-free, each at least one cell); `width`: the grid's width.
  // Every robot starts at progress 0.
  FleetSchedule(std::vector<std::vector<Cell>> paths, int32_t width);

  int robots() const { return static_cast<int>(paths_.size()); }
  const std::vector<Cell>& path(int robot) const { return paths_[robot]; }
  int64_t progress(int robot) const { return progress_[robot]; }
  bool removed(int robot) const { return removed_[robot]; }
  // True when the robot stands at the last index of its path.
  bool arrived(int robot) const {
    return progress_[robot] + 1 == static_cast<int64_t>(paths_[robot].size());
  }

  // The furthest index of its path `robot` may drive to now: every move up
  // to it is one that every robot planned through its cells earlier has
  // completed. At least progress(robot).
  int64_t Release(int robot) const;

  // `robot` reports standing in `cell`. Its progress moves to the first
  // index from its progress up to its release where the path is at `cell`,
  // and on through the waits there (indices repeating the cell) as far as
  // the release allows. False, and nothing changes, when `cell` is not on
  // that stretch of the path: the robot left its plan.
  bool Report(int robot, Cell cell);

  // `robot` left (its session ended): the cells it was planned through no
  // longer hold anyone back. The plan stays conflict-free for the others.
  void Remove(int robot);

 private:
  // One robot's consecutive steps [first, last] whose sweeps contain one
  // cell; last == kForever for the goal it stays at.
  struct Visit {
    int32_t robot;
    int64_t first;
    int64_t last;
  };
  static constexpr int64_t kForever = INT64_MAX;

  // The cells (row-major indices) the step from index s of `robot`'s path
  // sweeps; s at or past the last index: the goal alone.
  int SweepOf(int robot, int64_t s, uint32_t out[4]) const;
  // Every robot other than `robot` that the plan sends through `cell` in a
  // visit starting before step `s` has finished that visit.
  bool Free(int robot, int64_t s, uint32_t cell) const;

  std::vector<std::vector<Cell>> paths_;
  int32_t width_;
  std::vector<int64_t> progress_;
  std::vector<bool> removed_;
  // Per cell, every robot's visits, in robot then step order.
  absl::flat_hash_map<uint32_t, std::vector<Visit>> visits_;
};

}  // namespace pathd

#endif  // PATHD_CORE_FLEET_EXECUTION_H_
