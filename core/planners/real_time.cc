// Real-time heuristic search: RTAA* (Koenig & Likhachev 2006, "Real-Time
// Adaptive A*") and LRTA* with an A* look-ahead (Korf 1990; the Dijkstra-style
// update of Koenig & Sun 2009). The agent repeats episodes: an A* from its
// cell bounded to `lookahead` expansions, a heuristic update of the states
// that A* closed, then a move along the A* path to s', the open state of
// smallest f. The learned heuristic keeps every episode's work bounded and
// the agent from cycling; the result is the executed trajectory. The map is
// fully known, so an unreachable goal is reported (kNoPath) once a bounded
// side search proves it, instead of after the agent has explored everything.
// Each look-ahead is the best-first loop of core/search/best_first.h with the
// learned heuristic as its priority, a listener that collects CLOSED and a
// halt predicate for the expansion budget and "goal on top of OPEN".
#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "core/planners/planners.h"
#include "core/search/best_first.h"
#include "core/search/grid_planner.h"
#include "core/search/grid_view.h"
#include "core/search/heuristics.h"
#include "core/search/path_measure.h"

namespace pathd {
namespace {

constexpr int32_t kDefaultLookahead = 64;

// The trajectory may revisit cells many times while the heuristic fills a
// depression, but not without limit: past this many moves per map cell the
// query gives up with kExpansionLimit rather than hold hundreds of MB of
// trajectory. The default look-ahead stays far below it on the Moving AI
// maps; look-ahead 1 in one-cell-wide mazes can reach it.
constexpr size_t kMaxMovesPerCell = 16;
constexpr size_t kMinMaxMoves = size_t{1} << 20;

enum class Learning {
  // RTAA*: h(s) = f(s') - g(s) for every closed s; one pass over CLOSED.
  kRtaa,
  // LRTA*: h(s) = min over open o of (cost s -> o through CLOSED) + h(o), by a
  // Dijkstra search from OPEN backwards into CLOSED. Better informed than
  // RTAA*'s values, for a heap pass over CLOSED.
  kLrta,
};

// The look-ahead's open-list key: g plus the learned heuristic, the
// octile/Manhattan distance where nothing was learned.
struct LearnedPriority {
  const SearchScratch& scratch;
  internal::GridDistanceHeuristic h;
  double operator()(double g, uint32_t index, int32_t x, int32_t y) const {
    return g + scratch.LearnedOr(index, h(x, y));
  }
};

// The look-ahead's listener: appends each expanded cell to CLOSED and records
// it when the query asks. One variant with a pointer test rather than
// WithExpansionListener's two, so the flattened look-ahead holds one copy of
// the loop.
struct ClosedListener {
  std::vector<uint32_t>& closed;
  ExpansionRecorder* recorder;
  const internal::GridView& view;
  void OnExpand(uint32_t index) {
    closed.push_back(index);
    if (recorder != nullptr) recorder->Record(view.CellOf(index));
  }
};

// The look-ahead's halt: the episode's expansion budget is spent, or the goal
// is at the top of OPEN.
struct LookAheadHalt {
  int64_t budget_end;
  uint32_t goal;
  bool operator()(const internal::OpenList& open, int64_t expansions) const {
    return expansions >= budget_end || open.Top().index == goal;
  }
};

// One query's run; holds references only for its duration.
class RealTimeSearch {
 public:
  RealTimeSearch(const Grid& grid, const PlanRequest& request, const StopCondition& stop,
                 SearchScratch& scratch, Learning learning)
      : grid_(grid),
        request_(request),
        stop_(stop),
        scratch_(scratch),
        learning_(learning),
        view_(grid, request.cost),
        priority_{scratch, {request.goal, request.cost.connectivity}},
        goal_(view_.Index(request.goal.x, request.goal.y)),
        lookahead_(request.lookahead > 0 ? request.lookahead : kDefaultLookahead),
        max_moves_(std::max(kMinMaxMoves, kMaxMovesPerCell * grid.size())),
        flood_budget_(std::max(1, lookahead_ / 4)),
        flood_after_moves_(static_cast<size_t>(
            2.0 * GridDistance(request.start, request.goal, request.cost.connectivity))) {
  }

  PlanResult Run() {
    PlanResult result;
    result.outcome = Walk(result);
    if (result.found()) {
      const PathMeasure measure = MeasurePath(grid_, result.path, request_.cost);
      result.cost = measure.cost;
      result.length = measure.length;
    } else {
      result.path.clear();
    }
    result.expansions = expansions_;
    return result;
  }

 private:
  // The learned heuristic of cell `index`.
  double H(uint32_t index) const {
    const Cell c = view_.CellOf(index);
    return priority_(0.0, index, c.x, c.y);
  }

  // Runs episodes until the agent stands on the goal; appends its moves to
  // result.path and counts result.episodes.
  PlanOutcome Walk(PlanResult& result) {
    scratch_.BeginLearning(grid_.size());
    uint32_t current = view_.Index(request_.start.x, request_.start.y);
    result.path.push_back(request_.start);
    while (current != goal_) {
      ++result.episodes;
      if (const PlanOutcome why = LookAhead(current); why != PlanOutcome::kFound) {
        return why;
      }
      // OPEN ran dry: the agent's whole component was searched, and no goal.
      if (scratch_.open().empty()) return PlanOutcome::kNoPath;
      const SearchScratch::OpenEntry best = scratch_.open().front();  // s'
      if (result.path.size() - 1 > flood_after_moves_ &&
          CheckReachable(flood_budget_) == Reach::kUnreachable) {
        return PlanOutcome::kNoPath;
      }
      if (learning_ == Learning::kRtaa) {
        UpdateRtaa(best);
      } else {
        UpdateLrta();
      }
      Move(best.index, result.path);
      current = best.index;
      if (result.path.size() - 1 > max_moves_) return PlanOutcome::kExpansionLimit;
    }
    return PlanOutcome::kFound;
  }

  // A* from `from` on the learned heuristic until `lookahead_` expansions or
  // the goal is at the top of OPEN (or OPEN empties). Leaves OPEN in
  // scratch.open() and CLOSED in scratch.fifo(). Returns kFound to go on, or
  // why the stop condition fired.
  // Flattened (the open list inlined into the loop) and kept out of Walk():
  // an episode is short, and left to itself the compiler calls the open list
  // out of line here, which cost RTAA* 5% more instructions than the
  // hand-written loop this replaced (callgrind, docs/performance.md).
  [[gnu::noinline, gnu::flatten]] PlanOutcome LookAhead(uint32_t from) {
    scratch_.BeginSearch(grid_.size());
    internal::OpenList open(scratch_);
    const internal::GridExpansion expansion(view_);
    internal::PushRoot(scratch_, open, from, view_.CellOf(from), priority_);
    const LookAheadHalt halt{expansions_ + lookahead_, goal_};
    const PlanOutcome outcome = internal::BestFirstSearch(
        scratch_, open, internal::kNoNode, stop_, expansions_, priority_, expansion,
        internal::PlainParentUpdate(),
        ClosedListener{scratch_.fifo(), request_.expansion_recorder, view_}, halt);
    // Halted (kFound) or OPEN ran dry (kNoPath): the episode is over.
    return outcome == PlanOutcome::kNoPath ? PlanOutcome::kFound : outcome;
  }

  // A look-ahead search proves the goal unreachable only when the agent's
  // whole component fits in it; beyond that the agent would have to learn
  // its way through every cell first (seconds on a 512 x 512 map). So the
  // goal's reachability is settled aside: a breadth-first flood from the
  // start and one from the goal, each call advancing the smaller frontier by
  // up to `budget` cells (keeping episodes bounded), until the floods meet or
  // one runs dry.
  enum class Reach { kUnknown, kReachable, kUnreachable };
  static constexpr uint8_t kFromStart = 1;
  static constexpr uint8_t kFromGoal = 2;

  Reach CheckReachable(int32_t budget) {
    if (reach_ != Reach::kUnknown) return reach_;
    if (flood_[0].empty()) {  // first call
      const uint32_t start = view_.Index(request_.start.x, request_.start.y);
      scratch_.AddLearnedMarks(start, kFromStart);
      scratch_.AddLearnedMarks(goal_, kFromGoal);
      flood_[0].push_back(start);
      flood_[1].push_back(goal_);
    }
    for (int32_t n = 0; n < budget; ++n) {
      const size_t pending[2] = {flood_[0].size() - head_[0],
                                 flood_[1].size() - head_[1]};
      const int side = pending[0] <= pending[1] ? 0 : 1;
      if (pending[side] == 0) {
        reach_ = Reach::kUnreachable;
        break;
      }
      const uint8_t mine = side == 0 ? kFromStart : kFromGoal;
      const uint32_t at_index = flood_[side][head_[side]++];
      const Cell at = view_.CellOf(at_index);
      view_.ForEachNeighbor(at.x, at.y, [&](uint32_t next, int32_t, int32_t, double) {
        const uint8_t marks = scratch_.LearnedMarks(next);
        if (marks & (kFromStart | kFromGoal) & ~mine) reach_ = Reach::kReachable;
        if (marks & mine) return;
        scratch_.AddLearnedMarks(next, mine);
        flood_[side].push_back(next);
      });
      if (reach_ == Reach::kReachable) break;
    }
    if (reach_ != Reach::kUnknown) {
      for (std::vector<uint32_t>& queue : flood_) std::vector<uint32_t>().swap(queue);
    }
    return reach_;
  }

  void UpdateRtaa(const SearchScratch::OpenEntry& best) {
    const double f = best.g + H(best.index);
    for (const uint32_t s : scratch_.fifo()) {
      scratch_.SetLearned(s, f - scratch_.Raw(s).g);
    }
  }

  // Dijkstra from OPEN (keys: h) over reversed moves into CLOSED, whose values
  // are reset to +infinity first. Reuses the open-list storage as a
  // lazy-deletion heap; nodes are marked kNotInOpen once final.
  void UpdateLrta() {
    std::vector<SearchScratch::OpenEntry>& heap = scratch_.open();
    for (const uint32_t s : scratch_.fifo()) {
      scratch_.SetLearned(s, std::numeric_limits<double>::infinity());
    }
    for (SearchScratch::OpenEntry& e : heap) e.f = H(e.index);
    const auto later = [](const SearchScratch::OpenEntry& a,
                          const SearchScratch::OpenEntry& b) { return a.f > b.f; };
    std::make_heap(heap.begin(), heap.end(), later);
    size_t remaining = scratch_.fifo().size();
    while (remaining > 0 && !heap.empty()) {
      std::pop_heap(heap.begin(), heap.end(), later);
      const SearchScratch::OpenEntry e = heap.back();
      heap.pop_back();
      SearchScratch::Node& node = scratch_.Raw(e.index);
      if (node.open_pos == SearchScratch::kNotInOpen) continue;  // already final
      if (node.open_pos == SearchScratch::kClosed) --remaining;
      node.open_pos = SearchScratch::kNotInOpen;
      // Moves are reversible and cost what the target cell costs, so the
      // predecessors of e are its neighbours, each paying e's factor.
      const double enter = view_.Factor(e.index);
      const Cell at = view_.CellOf(e.index);
      view_.ForEachNeighbor(at.x, at.y, [&](uint32_t prev, int32_t, int32_t,
                                            double move_length) {
        if (!scratch_.Seen(prev) ||
            scratch_.Raw(prev).open_pos != SearchScratch::kClosed) {
          return;
        }
        const double h = e.f + move_length * enter;
        if (h >= scratch_.LearnedOr(prev, h)) return;
        scratch_.SetLearned(prev, h);
        heap.push_back({h, 0.0, prev});
        std::push_heap(heap.begin(), heap.end(), later);
      });
    }
  }

  // Appends the A* path from the agent's cell to `to` (exclusive of the
  // agent's cell, which ends `path` already).
  void Move(uint32_t to, std::vector<Cell>& path) const {
    const size_t first = path.size();
    for (uint32_t at = to; scratch_.Raw(at).parent != SearchScratch::kNoParent;
         at = scratch_.Raw(at).parent) {
      path.push_back(view_.CellOf(at));
    }
    std::reverse(path.begin() + static_cast<std::ptrdiff_t>(first), path.end());
  }

  const Grid& grid_;
  const PlanRequest& request_;
  const StopCondition& stop_;
  SearchScratch& scratch_;
  const Learning learning_;
  const internal::GridView view_;
  const LearnedPriority priority_;
  const uint32_t goal_;
  const int32_t lookahead_;
  const size_t max_moves_;
  // Cells per episode for CheckReachable(): a quarter of the look-ahead, so
  // it adds at most a quarter to the work of an episode, and only until the
  // floods meet. It starts once the trajectory is clearly longer than the
  // straight line, which most easy queries never reach.
  const int32_t flood_budget_;
  const size_t flood_after_moves_;
  int64_t expansions_ = 0;
  Reach reach_ = Reach::kUnknown;
  // The two floods' queues (from start, from goal) and their read positions.
  std::vector<uint32_t> flood_[2];
  size_t head_[2] = {0, 0};
};

class RealTimePlanner final : public GridPlanner {
 public:
  RealTimePlanner(std::string_view name, Learning learning, PlannerTraits traits)
      : GridPlanner(name, traits), learning_(learning) {}

 protected:
  absl::StatusOr<PlanResult> Search(const GridQuery& q) const override {
    return RealTimeSearch(q.grid, q.request, q.stop, q.scratch, learning_).Run();
  }

 private:
  Learning learning_;
};

}  // namespace

std::unique_ptr<Planner> MakeRtaaStarPlanner() {
  return std::make_unique<RealTimePlanner>(
      "rtaa_star", Learning::kRtaa,
      PlannerTraits{.real_time = true,
                    .description = "RTAA*: real-time adaptive A*, look-ahead A* "
                                   "episodes with h(s) = f(s') - g(s) learning; "
                                   "trajectory, not optimal"});
}

std::unique_ptr<Planner> MakeLrtaStarPlanner() {
  return std::make_unique<RealTimePlanner>(
      "lrta_star", Learning::kLrta,
      PlannerTraits{.real_time = true,
                    .description = "LRTA*: learning real-time A*, look-ahead A* "
                                   "episodes with Dijkstra-style h learning; "
                                   "trajectory, not optimal"});
}

}  // namespace pathd
