// The open list of the best-first searches in core/search/best_first.h: a
// binary min-heap over SearchScratch records with O(log n) decrease-key,
// ordered by (f, larger g first). Node ids are whatever the search's expansion
// policy numbers its nodes by (cells, or JPS jump-point ids). Searches by
// f = g (Dijkstra, the cost-to-go sweep) use MonotoneOpenList
// (radix_heap.h), which pops in this order.
#ifndef PATHD_CORE_SEARCH_OPEN_LIST_H_
#define PATHD_CORE_SEARCH_OPEN_LIST_H_

#include <bit>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/search/search_scratch.h"

namespace pathd::internal {

// Binary min-heap on (f, -g) stored in scratch.open(); each node's position is
// kept in its SearchScratch record for O(log n) decrease-key. Ties on f go to
// the larger g (the deeper node), which makes A* reach the goal with fewer
// expansions on open ground.
// Not thread-safe: one per search, over that search's scratch.
class OpenList {
 public:
  explicit OpenList(SearchScratch& scratch)
      : scratch_(scratch), heap_(scratch.open()) {}

  // The key an f is ordered by: f with the low kTieBits bits of its
  // mantissa cleared. Octile costs sum multiples of a full-precision
  // sqrt(2), so two paths of equal cost (a straight and a diagonal step in
  // either order) rarely give bit-equal f, and "larger g first" then almost
  // never fired (warthog, whose costs are integers, expanded 27% fewer nodes
  // on Denver_0_512). Rounding over a path stays near 1e-13 relative, so
  // equal f land in one bucket of 2^-32 relative width (unless they straddle
  // an edge, about one tie in a thousand) and compare by g. Truncation keeps
  // the order of f (f >= 0 here), so the order stays a strict weak order and
  // a search ends at most one bucket (2.3e-10 relative) above the optimum,
  // far inside the 1e-9 every optimality check allows. Compare f with Top()
  // through Key.
  static constexpr int kTieBits = 20;
  static double Key(double f) {
    return std::bit_cast<double>(std::bit_cast<uint64_t>(f) &
                                 ~((uint64_t{1} << kTieBits) - 1));
  }

  bool empty() const { return heap_.empty(); }
  size_t size() const { return heap_.size(); }

  // Inserts `index` or changes its key if it is already open. A lower g
  // usually lowers f, but not under every priority (greedy's f = h keeps f and
  // loses the larger-g tie-break), so the entry may have to move either way.
  void Push(uint32_t index, double f, double g) {
    f = Key(f);
    SearchScratch::Node& node = scratch_.Raw(index);
    if (node.open_pos >= 0) {
      SearchScratch::OpenEntry& entry = heap_[node.open_pos];
      const SearchScratch::OpenEntry updated{f, g, index};
      const bool better = Before(updated, entry);
      entry = updated;
      if (better) {
        SiftUp(node.open_pos);
      } else {
        SiftDown(node.open_pos);
      }
      return;
    }
    heap_.push_back({f, g, index});
    SiftUp(static_cast<int32_t>(heap_.size() - 1));
  }

  // Removes and returns the best entry; the node is marked closed.
  SearchScratch::OpenEntry Pop() {
    SearchScratch::OpenEntry top = heap_.front();
    scratch_.Raw(top.index).open_pos = SearchScratch::kClosed;
    const SearchScratch::OpenEntry last = heap_.back();
    heap_.pop_back();
    if (!heap_.empty()) {
      heap_[0] = last;
      scratch_.Raw(last.index).open_pos = 0;
      SiftDown(0);
    }
    return top;
  }

  const SearchScratch::OpenEntry& Top() const { return heap_.front(); }

 private:
  static bool Before(const SearchScratch::OpenEntry& a,
                     const SearchScratch::OpenEntry& b) {
    return a.f < b.f || (a.f == b.f && a.g > b.g);
  }

  void SiftUp(int32_t pos) {
    const SearchScratch::OpenEntry moving = heap_[pos];
    while (pos > 0) {
      const int32_t parent = (pos - 1) / 2;
      if (!Before(moving, heap_[parent])) break;
      heap_[pos] = heap_[parent];
      scratch_.Raw(heap_[pos].index).open_pos = pos;
      pos = parent;
    }
    heap_[pos] = moving;
    scratch_.Raw(moving.index).open_pos = pos;
  }

  void SiftDown(int32_t pos) {
    const SearchScratch::OpenEntry moving = heap_[pos];
    const int32_t n = static_cast<int32_t>(heap_.size());
    while (true) {
      int32_t child = 2 * pos + 1;
      if (child >= n) break;
      if (child + 1 < n && Before(heap_[child + 1], heap_[child])) ++child;
      if (!Before(heap_[child], moving)) break;
      heap_[pos] = heap_[child];
      scratch_.Raw(heap_[pos].index).open_pos = pos;
      pos = child;
    }
    heap_[pos] = moving;
    scratch_.Raw(moving.index).open_pos = pos;
  }

  SearchScratch& scratch_;
  std::vector<SearchScratch::OpenEntry>& heap_;
};

}  // namespace pathd::internal

#endif  // PATHD_CORE_SEARCH_OPEN_LIST_H_
