// The one incremental search behind LpaStar, DStarLite and ShortestPathMap
// (core/incremental/incremental_search.h): LPA* (Koenig, Likhachev & Furcy
// 2004) in the optimized form of D* Lite (Koenig & Likhachev 2002, Figure 4): the km key modifier,
// rhs updated from the one changed edge instead of rescanning every neighbour
// where that is enough, and lazy keys (an entry is re-keyed when it reaches the
// top of the heap, stale entries are dropped there). Internal to core.
#ifndef PATHD_CORE_INCREMENTAL_ENGINE_H_
#define PATHD_CORE_INCREMENTAL_ENGINE_H_

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "absl/container/flat_hash_map.h"
#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_format.h"
#include "absl/types/span.h"
#include "core/search/endpoints.h"
#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/incremental/incremental_search.h"
#include "core/incremental/move_model.h"
#include "core/search/grid_view.h"
#include "core/search/planner.h"
#include "core/search/radix_heap.h"

namespace pathd::internal {

inline constexpr uint32_t kNoCell = std::numeric_limits<uint32_t>::max();

// Open-list key of the focused searches (LPA*, D* Lite):
// [min(g, rhs) + h + km; min(g, rhs)], compared lexicographically.
struct FocusedKey {
  double k1;
  double k2;
  friend bool operator<(const FocusedKey& a, const FocusedKey& b) {
    return a.k1 < b.k1 || (a.k1 == b.k1 && a.k2 < b.k2);
  }
  friend bool operator==(const FocusedKey& a, const FocusedKey& b) = default;
};

// The f-like part of an open-list key, for progress reports: k1 of a focused
// key, the key itself for the shortest path map's float keys.
inline double PrimaryKey(const FocusedKey& key) { return key.k1; }
inline double PrimaryKey(float key) { return key; }

// g and rhs of every cell as doubles: 16 bytes per cell.
class DenseStore {
 public:
  using Value = double;
  void Reset(size_t cells) {
    g_.assign(cells, std::numeric_limits<double>::infinity());
    rhs_.assign(cells, std::numeric_limits<double>::infinity());
  }
  double g(uint32_t i) const { return g_[i]; }
  double rhs(uint32_t i) const { return rhs_[i]; }
  void set_g(uint32_t i, double v) { g_[i] = v; }
  void set_rhs(uint32_t i, double v) { rhs_[i] = v; }
  size_t MemoryBytes() const { return (g_.capacity() + rhs_.capacity()) * sizeof(double); }

 private:
  std::vector<double> g_;
  std::vector<double> rhs_;
};

// g of every cell as a float (the shortest path map's field, 4 bytes per
// cell). Once the search has run to an empty open list every cell is
// consistent (rhs == g), so rhs is kept only for the inconsistent cells of a
// repair, in a hash map that Settle() frees. A build from scratch makes almost
// every cell inconsistent at some point; it keeps rhs in a dense array instead
// (from Reset), which Settle() frees as well: 8 bytes per cell while building.
class FieldStore {
 public:
  using Value = float;
  // Every g = rhs = infinity, rhs dense until Settle().
  void Reset(size_t cells) {
    g_.assign(cells, std::numeric_limits<float>::infinity());
    dense_rhs_.assign(cells, std::numeric_limits<float>::infinity());
    absl::flat_hash_map<uint32_t, float>().swap(sparse_rhs_);
  }
  float g(uint32_t i) const { return g_[i]; }
  float rhs(uint32_t i) const {
    if (!dense_rhs_.empty()) return dense_rhs_[i];
    const auto it = sparse_rhs_.find(i);
    return it == sparse_rhs_.end() ? g_[i] : it->second;
  }
  void set_rhs(uint32_t i, float v) {
    if (!dense_rhs_.empty()) {
      dense_rhs_[i] = v;
    } else if (v == g_[i]) {
      sparse_rhs_.erase(i);
    } else {
      sparse_rhs_.insert_or_assign(i, v);
    }
  }
  // Changes g and keeps rhs (an absent entry meant rhs == old g).
  void set_g(uint32_t i, float v) {
    if (!dense_rhs_.empty()) {
      g_[i] = v;
      return;
    }
    const auto it = sparse_rhs_.find(i);
    const float r = it == sparse_rhs_.end() ? g_[i] : it->second;
    g_[i] = v;
    if (r == v) {
      if (it != sparse_rhs_.end()) sparse_rhs_.erase(it);
    } else if (it != sparse_rhs_.end()) {
      it->second = r;
    } else {
      sparse_rhs_.emplace(i, r);
    }
  }
  // Precondition: the search ran to an empty open list (all consistent).
  void Settle() {
    std::vector<float>().swap(dense_rhs_);
    absl::flat_hash_map<uint32_t, float>().swap(sparse_rhs_);
  }
  absl::Span<const float> field() const { return g_; }
  size_t MemoryBytes() const {
    // A flat_hash_map slot plus its control byte per bucket.
    const size_t map_bytes =
        sparse_rhs_.bucket_count() * (sizeof(std::pair<uint32_t, float>) + 1);
    return (g_.capacity() + dense_rhs_.capacity()) * sizeof(float) + map_bytes;
  }
  // For tests that provoke the path-extraction guard.
  void CorruptForTest(uint32_t i, float v) { g_[i] = v; }

 private:
  std::vector<float> g_;
  std::vector<float> dense_rhs_;
  absl::flat_hash_map<uint32_t, float> sparse_rhs_;
};

// LPA* forward from the start (Forward = true, heuristic towards the goal)
// and D* Lite backward from the goal (heuristic towards the moving start).
template <bool Forward>
struct FocusedConfig {
  static constexpr bool kForward = Forward;
  static constexpr bool kFocused = true;
  using Store = DenseStore;
  using Key = FocusedKey;
};

// The shortest path map: backward from the goal, no heuristic, no target; the
// search runs until the open list is empty. Keys are the float min(g, rhs).
struct FieldConfig {
  static constexpr bool kForward = false;
  static constexpr bool kFocused = false;
  using Store = FieldStore;
  using Key = float;
};

// The incremental search over one grid. rhs(u) = min over legal moves between
// u and a neighbour p of W(u, p) + g(p), where W(u, p) is the cost of the move
// p -> u in a forward search (entering u) and of u -> p in a backward search
// (entering p), and rhs(root) = 0 for the root (start or goal). With a target
// the search stops once the target is consistent and no key on the open list
// is below the target's; without one it runs until every cell is consistent.
//
// Values are Store::Value. Sums are computed in double and rounded to Value
// once, and the float field compares the rounded values, so "consistent"
// (g == rhs) and "rhs came through this edge" (rhs == W + g) are exact tests:
// the field is the unique fixed point of g(u) = min float(W + g(p)), whichever
// order the repairs run in, and a repaired field equals a rebuilt one bit for
// bit.
//
// Copyable (ShortestPathMap::Clone); not thread-safe.
template <typename Config>
class IncrementalSearch {
 public:
  using Store = typename Config::Store;
  using Value = typename Store::Value;
  using Key = typename Config::Key;
  static constexpr Value kInf = std::numeric_limits<Value>::infinity();

  // Precondition: `grid` is valid for cost (ValidateEndpoints), root in bounds.
  IncrementalSearch(std::shared_ptr<const Grid> grid, const CostParams& cost,
                    const MoveRules& rules, Cell root)
      : grid_(std::move(grid)),
        cost_(cost),
        rules_(rules),
        model_(*grid_, cost_, rules_),
        root_(model_.Index(root)) {}

  // Forgets everything: g = rhs = infinity, rhs(root) = 0, root open.
  void Reset() {
    store_.Reset(grid_->size());
    heap_.clear();
    km_ = 0.0;
    store_.set_rhs(root_, 0);
    UpdateVertex(root_);
  }

  // The target cell whose consistency ends the search (the goal for LPA*, the
  // start for D* Lite) and the cell the heuristic measures to.
  void SetTarget(Cell target) {
    target_ = model_.Index(target);
    focus_ = target;
  }
  void AddKm(double delta) { km_ += delta; }
  double km() const { return km_; }

  // h(a, b) under the move rules: octile (with the configured diagonal) or
  // Manhattan distance, 0 when the heuristic is off. Consistent because every
  // cell factor is >= 1.
  double Heuristic(Cell a, Cell b) const {
    if (!rules_.heuristic) return 0.0;
    const double dx = std::abs(a.x - b.x);
    const double dy = std::abs(a.y - b.y);
    if (!model_.eight()) return dx + dy;
    return dx > dy ? dx + (rules_.diagonal_length - 1.0) * dy
                   : dy + (rules_.diagonal_length - 1.0) * dx;
  }

  const Grid& grid() const { return *grid_; }
  const CostParams& cost() const { return cost_; }
  const MoveModel& model() const { return model_; }
  uint32_t root() const { return root_; }
  Value g(uint32_t i) const { return store_.g(i); }
  Value rhs(uint32_t i) const { return store_.rhs(i); }
  Store& store() { return store_; }
  const Store& store() const { return store_; }

  // Heap memory: the per-cell store and the open list (the object itself is
  // counted by its owner).
  size_t MemoryBytes() const {
    return store_.MemoryBytes() + heap_.capacity() * sizeof(Entry);
  }

  // Switches to `grid` (same size) and updates rhs of every cell whose
  // incoming edge costs changed because a cell in `changed` changed: the cell
  // itself, and its neighbours (moves into or out of it, and diagonals that
  // pass its corner). Per edge as in D* Lite's main loop: a cheaper edge can
  // only lower rhs (rhs = min(rhs, W_new + g)); a dearer one matters only when
  // rhs came through it (rhs == W_old + g), and then rhs is recomputed from
  // every neighbour. Preconditions: same size, every changed cell in bounds.
  void SwitchGrid(std::shared_ptr<const Grid> grid, absl::Span<const Cell> changed) {
    // old_model reads the old grid's cells: keep them alive until done.
    const std::shared_ptr<const Grid> old_grid = std::move(grid_);
    const MoveModel old_model = model_;
    grid_ = std::move(grid);
    model_ = MoveModel(*grid_, cost_, rules_);
    const int32_t w = model_.width(), h = model_.height();
    for (const Cell v : changed) {
      for (int32_t y = std::max(v.y - 1, 0); y <= std::min(v.y + 1, h - 1); ++y) {
        for (int32_t x = std::max(v.x - 1, 0); x <= std::min(v.x + 1, w - 1); ++x) {
          RepairRhs(old_model, x, y);
        }
      }
    }
  }

  // ComputeShortestPath: expands inconsistent cells in key order until the
  // target is settled (or, without a target, until the open list is empty),
  // polling `stop` before each expansion. A stop leaves every invariant in
  // place, so calling Compute again continues. Returns kFound when the search
  // completed (whether or not the target is reachable) or the stop's outcome.
  struct ComputeEnd {
    PlanOutcome outcome;
    int64_t expansions;
  };
  ComputeEnd Compute(const StopCondition& stop) {
    MaybeCompact();
    int64_t expansions = 0;
    while (!heap_.empty()) {
      const Entry top = heap_.front();
      if (TargetSettled(top.key)) break;
      const uint32_t u = top.index;
      const Value gu = store_.g(u);
      const Value ru = store_.rhs(u);
      if (gu == ru) {  // stale: made consistent since it was pushed
        PopTop();
        continue;
      }
      const Key key = KeyOf(u, gu, ru);
      if (!(key == top.key)) {  // lazy key update (km moved, or a stale duplicate)
        PopTop();
        Push(u, key);
        continue;
      }
      if (const PlanOutcome why = stop.Check(expansions, PrimaryKey(key));
          why != PlanOutcome::kFound) {
        return {why, expansions};
      }
      PopTop();
      ++expansions;
      if (gu > ru) {
        // Overconsistent: settle u and offer it to the cells that may step to
        // it; only a lower rhs can result, so no rescans.
        store_.set_g(u, ru);
        model_.ForEachMove(u, [&](uint32_t p, bool diagonal) {
          if (p == root_) return;
          const Value candidate = Add(Weight(p, u, diagonal), ru);
          if (candidate < store_.rhs(p)) {
            store_.set_rhs(p, candidate);
            UpdateVertex(p);
          }
        });
      } else {
        // Underconsistent: raise u to infinity; only the cells whose rhs came
        // through u need a rescan.
        store_.set_g(u, kInf);
        model_.ForEachMove(u, [&](uint32_t p, bool diagonal) {
          if (p == root_) return;
          if (store_.rhs(p) == Add(Weight(p, u, diagonal), gu)) {
            store_.set_rhs(p, RhsFromNeighbors(p));
            UpdateVertex(p);
          }
        });
        UpdateVertex(u);
      }
    }
    if (heap_.empty()) {
      // Nothing left to do: free the open list (the field keeps none).
      std::vector<Entry>().swap(heap_);
      compact_at_ = kMinCompact;
    }
    return {PlanOutcome::kFound, expansions};
  }

  // Compute right after Reset() for the shortest path map (no target, no
  // heuristic): every key is then a settled cell's float(W + g) >= g, so keys
  // never decrease and the open list can be a radix heap over the floats'
  // bits (core/search/radix_heap.h), a third cheaper than the binary heap
  // (docs/performance.md, "Dijkstra and the cost-to-go on a radix heap").
  // Every cell is overconsistent when it surfaces (g still infinite) and
  // settles once, so this is Compute's overconsistent branch alone and the
  // field is the same fixed point, bit for bit. A stop hands the entries left
  // to the binary heap, so a later Compute continues.
  ComputeEnd ComputeFromReset(const StopCondition& stop)
    requires(!Config::kFocused)
  {
    RadixHeap<uint32_t> open;
    for (const Entry& e : heap_) open.Push(KeyBits(e.key), e.index);
    heap_.clear();
    int64_t expansions = 0;
    while (!open.empty()) {
      const auto top = open.Pop();
      const uint32_t u = top.value;
      const Value gu = store_.g(u);
      const Value ru = store_.rhs(u);
      // Settled already, or a duplicate from before rhs fell further.
      if (gu == ru || KeyBits(ru) != top.key) continue;
      if (const PlanOutcome why = stop.Check(expansions, ru); why != PlanOutcome::kFound) {
        Push(u, ru);
        while (!open.empty()) {
          const auto e = open.Pop();
          Push(e.value, std::bit_cast<float>(static_cast<uint32_t>(e.key)));
        }
        return {why, expansions};
      }
      ++expansions;
      store_.set_g(u, ru);
      model_.ForEachMove(u, [&](uint32_t p, bool diagonal) {
        if (p == root_) return;
        const Value candidate = Add(Weight(p, u, diagonal), ru);
        if (candidate < store_.rhs(p)) {
          store_.set_rhs(p, candidate);
          open.Push(KeyBits(candidate), p);
        }
      });
    }
    std::vector<Entry>().swap(heap_);
    compact_at_ = kMinCompact;
    return {PlanOutcome::kFound, expansions};
  }

  // The next cell on the way from u to the root: the neighbour p minimising
  // W(u, p) + g(p) (ties to the first in move order), and that sum. nullopt
  // when no neighbour has a finite g.
  struct Step {
    uint32_t cell;
    double cost;  // W(u, p), the cost of the move between u and p
  };
  std::optional<Step> Downhill(uint32_t u) const {
    std::optional<Step> best;
    double best_sum = std::numeric_limits<double>::infinity();
    model_.ForEachMove(u, [&](uint32_t p, bool diagonal) {
      const double w = Weight(u, p, diagonal);
      const double sum = w + static_cast<double>(store_.g(p));
      if (sum < best_sum) {
        best_sum = sum;
        best = Step{p, w};
      }
    });
    return best;
  }

  // The cells from `from` down to the root, following Downhill. The guard
  // against a broken state: g must fall strictly at every step (so no cell
  // repeats and the walk ends within the number of cells); otherwise INTERNAL
  // naming the cell where the descent stopped. Precondition: g(from) finite.
  absl::StatusOr<std::vector<Cell>> Descend(uint32_t from) const {
    std::vector<Cell> path{model_.CellOf(from)};
    uint32_t at = from;
    const size_t cells = grid_->size();
    while (at != root_) {
      const std::optional<Step> next = Downhill(at);
      if (!next.has_value() || !(store_.g(next->cell) < store_.g(at)) ||
          path.size() > cells) {
        return absl::InternalError(absl::StrFormat(
            "incremental search state broken: the descent from %s stops at %s "
            "(g %g) after %d steps with no neighbour of lower g",
            CellToString(path.front()), CellToString(model_.CellOf(at)),
            static_cast<double>(store_.g(at)), path.size() - 1));
      }
      at = next->cell;
      path.push_back(model_.CellOf(at));
    }
    return path;
  }

 private:
  static constexpr size_t kMinCompact = 4096;
  static constexpr double kKeyTieTolerance = 1e-9;

  struct Entry {
    Key key;
    uint32_t index;
  };
  // Min-heap order for std::push_heap / pop_heap.
  struct Later {
    bool operator()(const Entry& a, const Entry& b) const { return b.key < a.key; }
  };

  // A non-negative float key as an integer of the same order.
  static uint64_t KeyBits(float key) { return std::bit_cast<uint32_t>(key); }

  static Value Add(double w, Value g) {
    return static_cast<Value>(w + static_cast<double>(g));
  }

  // W(u, p): the cost term of rhs(u) through neighbour p.
  double Weight(uint32_t u, uint32_t p, bool diagonal) const {
    return model_.MoveCost(Config::kForward ? u : p, diagonal);
  }
  double Weight(const MoveModel& m, uint32_t u, uint32_t p, bool diagonal) const {
    return m.MoveCost(Config::kForward ? u : p, diagonal);
  }

  Key KeyOf(uint32_t u, Value g, Value rhs) const {
    const Value m = std::min(g, rhs);
    if constexpr (Config::kFocused) {
      const double k2 = static_cast<double>(m);
      return Key{k2 + Heuristic(focus_, model_.CellOf(u)) + km_, k2};
    } else {
      return m;
    }
  }

  // "TopKey() >= CalculateKey(target) and the target consistent": LPA*'s
  // test and the unoptimized D* Lite's (the optimized one stops while the
  // start is still overconsistent, g > rhs). Settling the target costs one
  // expansion and makes its g the path cost, which the extraction checks, and
  // the lecture's example prints exactly these states.
  // Every cell on an optimal path has k1 equal to the target's in exact
  // arithmetic (g + h is constant along it for a consistent h) and a smaller
  // k2, so it is expanded first; but the two k1 sums round differently, and a
  // tie that rounds the wrong way would stop the search with such a cell
  // still inconsistent. So k1 values within a relative 1e-9 count as a tie
  // and are all expanded, whatever their k2: the extra work is the near-ties
  // only.
  bool TargetSettled(const Key& top) const {
    if (target_ == kNoCell) return false;
    const Value gt = store_.g(target_);
    const Value rt = store_.rhs(target_);
    if (gt != rt) return false;
    if constexpr (Config::kFocused) {
      const double k1 = KeyOf(target_, gt, rt).k1;
      return top.k1 > k1 + kKeyTieTolerance * (1.0 + std::abs(k1));
    } else {
      return !(top < KeyOf(target_, gt, rt));
    }
  }

  void Push(uint32_t u, const Key& key) {
    heap_.push_back(Entry{key, u});
    std::push_heap(heap_.begin(), heap_.end(), Later());
  }
  void PopTop() {
    std::pop_heap(heap_.begin(), heap_.end(), Later());
    heap_.pop_back();
  }

  // Queues u when inconsistent. Entries are never removed or re-keyed in
  // place: Compute drops or re-keys them when they surface.
  void UpdateVertex(uint32_t u) {
    const Value gu = store_.g(u);
    const Value ru = store_.rhs(u);
    if (gu != ru) Push(u, KeyOf(u, gu, ru));
  }

  Value RhsFromNeighbors(uint32_t u) const {
    if (u == root_) return 0;
    Value best = kInf;
    model_.ForEachMove(u, [&](uint32_t p, bool diagonal) {
      best = std::min(best, Add(Weight(u, p, diagonal), store_.g(p)));
    });
    return best;
  }

  // The per-edge rule of SwitchGrid for the cell (x, y).
  void RepairRhs(const MoveModel& old_model, int32_t x, int32_t y) {
    const uint32_t u = model_.Index(Cell{x, y});
    if (u == root_) return;
    const int moves = model_.eight() ? 8 : 4;
    const auto w = static_cast<int64_t>(model_.width());
    Value r = store_.rhs(u);
    bool rescan = false;
    for (int m = 0; m < moves; ++m) {
      const int32_t dx = kMoves[m].dx, dy = kMoves[m].dy;
      const bool diagonal = dx != 0 && dy != 0;
      const bool was = old_model.Legal(x, y, dx, dy);
      const bool is = model_.Legal(x, y, dx, dy);
      if (!was && !is) continue;
      const auto p = static_cast<uint32_t>(static_cast<int64_t>(u) + dy * w + dx);
      const double w_old = was ? Weight(old_model, u, p, diagonal)
                               : std::numeric_limits<double>::infinity();
      const double w_new = is ? Weight(u, p, diagonal)
                              : std::numeric_limits<double>::infinity();
      if (w_new == w_old) continue;
      const Value gp = store_.g(p);
      if (w_new < w_old) {
        r = std::min(r, Add(w_new, gp));
      } else if (gp != kInf && r == Add(w_old, gp)) {
        rescan = true;
      }
    }
    if (rescan) r = RhsFromNeighbors(u);
    if (r != store_.rhs(u)) {
      store_.set_rhs(u, r);
      UpdateVertex(u);
    }
  }

  // Duplicates and stale entries pile up in a lazy heap; when it has doubled
  // since the last clean-up, keep one entry per inconsistent cell, re-keyed.
  // Amortised O(1) per push.
  void MaybeCompact() {
    if (heap_.size() < compact_at_) return;
    std::sort(heap_.begin(), heap_.end(),
              [](const Entry& a, const Entry& b) { return a.index < b.index; });
    size_t kept = 0;
    for (size_t i = 0; i < heap_.size(); ++i) {
      const uint32_t u = heap_[i].index;
      if (kept > 0 && heap_[kept - 1].index == u) continue;
      const Value gu = store_.g(u);
      const Value ru = store_.rhs(u);
      if (gu == ru) continue;
      heap_[kept++] = Entry{KeyOf(u, gu, ru), u};
    }
    heap_.resize(kept);
    std::make_heap(heap_.begin(), heap_.end(), Later());
    compact_at_ = std::max(kMinCompact, 2 * heap_.size());
  }

  std::shared_ptr<const Grid> grid_;
  CostParams cost_;
  MoveRules rules_;
  MoveModel model_;
  uint32_t root_;
  uint32_t target_ = kNoCell;
  Cell focus_;
  double km_ = 0.0;
  Store store_;
  std::vector<Entry> heap_;
  size_t compact_at_ = kMinCompact;
};

// Access for tests (and the registry's SPM wrapper) to what the public API of
// core/incremental/incremental_search.h keeps private.
class IncrementalAccess {
 public:
  // A D* Lite with non-default move rules (the lecture's D* Lite example).
  static absl::StatusOr<std::unique_ptr<DStarLite>> CreateDStarLite(
      std::shared_ptr<const Grid> grid, Cell goal, CostParams cost,
      const MoveRules& rules);
  // Plan()'s search without the path extraction, which measures paths under
  // DESIGN.md's cost model and so rejects the lecture example's corner cuts.
  static PlanOutcome ComputeShortestPath(DStarLite& dstar, const StopCondition& stop);
  // Overwrites one field value, to provoke the extraction guard.
  static void CorruptField(ShortestPathMap& map, Cell c, float value);
  // Overwrites g of one cell, to provoke the extraction guard.
  static void CorruptG(DStarLite& dstar, Cell c, double value);
  // For every cell, the cost measured in double of the path PathFrom returns
  // from it (+infinity where the goal is unreachable): the field's own values
  // are floats, this is what the path costs. INTERNAL as PathFrom.
  static absl::StatusOr<std::vector<double>> PathCosts(const ShortestPathMap& map);
};

}  // namespace pathd::internal

#endif  // PATHD_CORE_INCREMENTAL_ENGINE_H_
