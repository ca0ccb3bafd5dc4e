// Pieces the multi-agent solvers of mapf.h share: a robot's move graph on its
// grid (the cost model's moves, no corner cutting), the cells a step sweeps
// (the one conflict rule of mapf.h), per-robot distance tables (backward BFS
// in steps), a table of timed sweeps (reservations, conflict avoidance) and
// the space-time A* / focal search every planner's low level runs.
// Internal to core/fleet; thread-compatible.
#ifndef PATHD_CORE_FLEET_MAPF_INTERNAL_H_
#define PATHD_CORE_FLEET_MAPF_INTERNAL_H_

#include <cstdint>
#include <limits>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/container/flat_hash_set.h"
#include "core/fleet/mapf.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/stop_condition.h"

namespace pathd::mapf_internal {

inline constexpr uint32_t kNoCell = std::numeric_limits<uint32_t>::max();
inline constexpr int32_t kUnreachable = -1;

// A robot's steps to its goal from every cell, two bytes a cell (a 512 x 512
// map costs 0.5 MiB a robot): kFar where unreachable, capped at kFar - 1
// (min(d, cap) is still admissible and consistent).
using DistanceTable = std::vector<uint16_t>;
inline constexpr uint16_t kFar = 0xffff;
inline constexpr int32_t kNever = std::numeric_limits<int32_t>::max();

// The cells one step sweeps: its cell at t, at t+1 and, for a diagonal move,
// the two side cells. n = 1 for a wait, 2 for a straight move, 4 diagonal.
struct Sweep {
  uint32_t cells[4] = {kNoCell, kNoCell, kNoCell, kNoCell};
  int n = 0;
  bool Touches(uint32_t c) const {
    for (int k = 0; k < n; ++k) {
      if (cells[k] == c) return true;
    }
    return false;
  }
  bool Meets(const Sweep& other) const {
    for (int k = 0; k < n; ++k) {
      if (other.Touches(cells[k])) return true;
    }
    return false;
  }
};

// Buffers of DistancesTo, reused from one robot's table to the next.
struct BfsScratch {
  std::vector<int32_t> dist;
  std::vector<uint32_t> queue;
};

// The legal moves of one robot grid (cells by row-major index).
class MoveGraph {
 public:
  MoveGraph(const Grid& grid, Connectivity connectivity, bool unknown_is_free);

  int32_t width() const { return width_; }
  size_t cells() const { return open_.size(); }
  bool Open(uint32_t c) const { return open_[c] != 0; }
  bool Open(int32_t x, int32_t y) const {
    return x >= 0 && y >= 0 && x < width_ && y < height_ &&
           open_[static_cast<size_t>(y) * width_ + x] != 0;
  }
  uint32_t Index(Cell c) const {
    return static_cast<uint32_t>(c.y) * static_cast<uint32_t>(width_) +
           static_cast<uint32_t>(c.x);
  }
  Cell CellOf(uint32_t i) const {
    return Cell{static_cast<int32_t>(i % static_cast<uint32_t>(width_)),
                static_cast<int32_t>(i / static_cast<uint32_t>(width_))};
  }

  // Calls visit(to) for every legal move out of open cell `from` (not the
  // wait), straight moves first.
  template <typename Visit>
  void ForEachMove(uint32_t from, Visit&& visit) const {
    const Cell a = CellOf(from);
    bool open[4];
    for (int m = 0; m < 4; ++m) {
      open[m] = Open(a.x + kMoves[m].dx, a.y + kMoves[m].dy);
      if (open[m]) {
        visit(from + static_cast<uint32_t>(kMoves[m].dx) +
              static_cast<uint32_t>(kMoves[m].dy * width_));
      }
    }
    if (moves_ == 4) return;
    static constexpr int kSideX[4] = {0, 0, 1, 1};
    static constexpr int kSideY[4] = {2, 3, 2, 3};
    for (int d = 0; d < 4; ++d) {
      if (!open[kSideX[d]] || !open[kSideY[d]]) continue;  // corner cutting
      const Move& m = kMoves[4 + d];
      if (Open(a.x + m.dx, a.y + m.dy)) {
        visit(from + static_cast<uint32_t>(m.dx) +
              static_cast<uint32_t>(m.dy * width_));
      }
    }
  }

  // The cells the step from -> to sweeps (from == to: a wait).
  // Precondition: a legal move or a wait.
  Sweep SweepOf(uint32_t from, uint32_t to) const {
    Sweep s;
    s.cells[s.n++] = from;
    if (to == from) return s;
    s.cells[s.n++] = to;
    const Cell a = CellOf(from);
    const Cell b = CellOf(to);
    if (a.x != b.x && a.y != b.y) {
      s.cells[s.n++] = Index(Cell{b.x, a.y});
      s.cells[s.n++] = Index(Cell{a.x, b.y});
    }
    return s;
  }

  // Steps from every cell to `goal`: a BFS from the goal, whose moves are
  // the reverse moves (the rule is symmetric). `*from_distance` gets the
  // exact steps from `from` (kUnreachable when none).
  DistanceTable DistancesTo(uint32_t goal, uint32_t from,
                            int32_t* from_distance, BfsScratch* scratch) const;

 private:
  int32_t width_;
  int32_t height_;
  int moves_;
  std::vector<uint8_t> open_;
  std::vector<uint8_t> padded_open_;  // with a blocked border, for BFS
};

// A timed path by cell index; after its last entry the robot stays.
using IndexPath = std::vector<uint32_t>;

// The step t -> t+1 of a path (a wait at the goal past its end).
inline Sweep SweepAt(const MoveGraph& graph, const IndexPath& path, int64_t t) {
  const int64_t last = static_cast<int64_t>(path.size()) - 1;
  return graph.SweepOf(path[std::min(t, last)], path[std::min(t + 1, last)]);
}

// The cost of a path: the time it reaches its goal for the last time.
int32_t PathCost(const IndexPath& path);
// Drops trailing waits at the goal.
void TrimPath(IndexPath* path);

// Timed sweeps of a set of paths: counts per (cell, step) and, per cell, the
// time from which a robot parked on it (its goal) sweeps it at every step.
// As reservations (prioritized planning) its counts are hard; as a conflict
// avoidance table (CBS) they are tie-breakers.
class SweepTable {
 public:
  explicit SweepTable(size_t cells)
      : cells_(cells), parked_since_(cells, kNever), last_step_(cells, -1) {}

  void AddPath(const MoveGraph& graph, const IndexPath& path) {
    Update(graph, path, +1);
  }
  void RemovePath(const MoveGraph& graph, const IndexPath& path) {
    Update(graph, path, -1);
  }
  // One timed sweep of `cell` during step t (a robot known to be there).
  void AddTimed(uint32_t cell, int32_t t, int32_t delta);

  // How many of the sweeps of step t meet `s`.
  int Count(const Sweep& s, int32_t t) const {
    int n = 0;
    for (int k = 0; k < s.n; ++k) {
      if (parked_since_[s.cells[k]] <= t) ++n;
      if (!timed_.empty()) {
        const auto it = timed_.find(Key(s.cells[k], t));
        if (it != timed_.end()) n += it->second;
      }
    }
    return n;
  }
  // The last step with a timed sweep of `cell` (-1: none); lowered by
  // removals only when step 0's were the last (otherwise a conservative
  // bound).
  int32_t LastStep(uint32_t cell) const { return last_step_[cell]; }
  // One past the last step with any timed sweep: from then on the table does
  // not change with time.
  int32_t Horizon() const { return horizon_; }

 private:
  uint64_t Key(uint32_t cell, int32_t t) const {
    return static_cast<uint64_t>(t) * cells_ + cell;
  }
  void Update(const MoveGraph& graph, const IndexPath& path, int32_t delta);

  size_t cells_;
  absl::flat_hash_map<uint64_t, int32_t> timed_;
  std::vector<int32_t> parked_since_;
  std::vector<int32_t> last_step_;
  int32_t horizon_ = 0;
};

// CBS constraints of one robot: it may not sweep `cell` during step t.
class ConstraintSet {
 public:
  void Add(uint32_t cell, int32_t t, size_t cells) {
    set_.insert(static_cast<uint64_t>(t) * cells + cell);
    horizon_ = std::max(horizon_, t + 1);
    last_step_[cell] = std::max(last_step_[cell], t);
  }
  bool Blocks(const Sweep& s, int32_t t, size_t cells) const {
    if (set_.empty() || t >= horizon_) return false;
    for (int k = 0; k < s.n; ++k) {
      if (set_.contains(static_cast<uint64_t>(t) * cells + s.cells[k])) {
        return true;
      }
    }
    return false;
  }
  int32_t LastStep(uint32_t cell) const {
    const auto it = last_step_.find(cell);
    return it == last_step_.end() ? -1 : it->second;
  }
  int32_t Horizon() const { return horizon_; }

 private:
  absl::flat_hash_set<uint64_t> set_;
  absl::flat_hash_map<uint32_t, int32_t> last_step_;
  int32_t horizon_ = 0;
};

// One robot's space-time search: A* (w = 1) or focal search (w > 1, Barer
// et al. 2014: among open nodes with f <= w * f_min, fewest conflicts with
// `avoid`). Time is g; a state past every constraint's and table's horizon
// is keyed by its cell alone (nothing changes after it).
struct LowLevelQuery {
  const MoveGraph* graph = nullptr;
  const DistanceTable* h = nullptr;  // DistancesTo(goal)
  uint32_t start = 0;
  uint32_t goal = 0;
  const ConstraintSet* constraints = nullptr;  // hard, may be null
  const SweepTable* reserved = nullptr;        // hard, may be null
  const SweepTable* avoid = nullptr;           // soft, may be null
  int32_t max_steps = 0;
  double w = 1.0;
  // Expansions this search may spend (0: no limit besides `stop`).
  int64_t max_expansions = 0;
};

struct LowLevelResult {
  // kFound, kNoPath (no path within max_steps / the budget), or the stop
  // condition's outcome.
  PlanOutcome outcome = PlanOutcome::kNoPath;
  IndexPath path;
  int32_t cost = 0;
  // A lower bound on this robot's cost under the query's hard constraints.
  int32_t lower_bound = 0;
  // Conflicts of `path` with `avoid`.
  int32_t conflicts = 0;
};

// `expansions` is the caller's running total (polled with `stop`).
LowLevelResult SpaceTimeSearch(const LowLevelQuery& query,
                               const StopCondition& stop, int64_t* expansions);

// The shared context of one PlanFleet call.
struct Instance {
  std::vector<MoveGraph> graphs;        // one per FleetProblem::grids entry
  std::vector<int32_t> graph_of;        // robot -> graphs index
  std::vector<uint32_t> starts, goals;  // by cell index
  std::vector<DistanceTable> h;         // robot -> DistancesTo(goal)
  size_t cells = 0;
  int32_t max_steps = 0;
  // FleetOptions::max_steps was set (LaCAM's search is otherwise unbounded
  // in depth, which keeps it complete).
  bool max_steps_given = false;
  int64_t individual_sum = 0;  // sum of individual shortest paths
  const MoveGraph& graph(size_t robot) const { return graphs[graph_of[robot]]; }
  size_t robots() const { return starts.size(); }
};

// Fills plan->paths / makespan / sum_of_costs from index paths (trimmed).
void SetPaths(const Instance& inst, std::vector<IndexPath> paths,
              FleetPlan* plan);

FleetPlan SolvePrioritized(const Instance& inst, const FleetOptions& options,
                           const StopCondition& stop);
FleetPlan SolveCbs(const Instance& inst, const FleetOptions& options,
                   const StopCondition& stop);
FleetPlan SolveLacam(const Instance& inst, const FleetOptions& options,
                     const StopCondition& stop);
FleetPlan SolvePibt(const Instance& inst, const FleetOptions& options,
                    const StopCondition& stop);

}  // namespace pathd::mapf_internal

#endif  // PATHD_CORE_FLEET_MAPF_INTERNAL_H_
