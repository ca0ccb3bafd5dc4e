// The open list of searches whose keys never decrease (Dijkstra's f = g, the
// backward cost-to-go sweep): a radix heap (Ahuja, Mehlhorn, Orlin & Tarjan
// 1990, "Faster algorithms for the shortest path problem") over 64-bit keys,
// in the order of OpenList, so it drops into BestFirstSearch in its place.
#ifndef PATHD_CORE_SEARCH_RADIX_HEAP_H_
#define PATHD_CORE_SEARCH_RADIX_HEAP_H_

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/search/open_list.h"
#include "core/search/search_scratch.h"

namespace pathd::internal {

// A radix heap over unsigned 64-bit keys for monotone use: every key pushed
// is at least the last one popped. Bucket 0 holds keys equal to the last
// popped one, bucket b > 0 keys whose highest bit differing from it is bit
// b - 1; a pop from an empty bucket 0 moves the lowest non-empty bucket down
// around its minimum, so each entry moves at most 64 times and in practice a
// few. Entries with equal keys pop in no particular order. Keys pushed below
// the last popped one are still ordered correctly, in a side list searched
// linearly: meant for rare exceptions, not for non-monotone use.
// Not thread-safe.
template <typename Value>
class RadixHeap {
 public:
  struct Entry {
    uint64_t key;
    Value value;
  };

  bool empty() const { return size_ == 0; }
  size_t size() const { return size_; }

  void Clear() {
    for (std::vector<Entry>& b : buckets_) b.clear();
    below_.clear();
    last_ = 0;
    size_ = 0;
  }

  void Push(uint64_t key, Value value) {
    ++size_;
    if (key < last_) [[unlikely]] {
      below_.push_back(Entry{key, value});
      return;
    }
    buckets_[BucketOf(key)].push_back(Entry{key, value});
  }

  // The entry Pop() returns next. Precondition: !empty().
  const Entry& Top() {
    if (!below_.empty()) [[unlikely]] {
      return *std::min_element(below_.begin(), below_.end(), KeyLess);
    }
    if (buckets_[0].empty()) Refill();
    return buckets_[0].back();
  }

  // Removes and returns an entry of least key. Precondition: !empty().
  Entry Pop() {
    --size_;
    if (!below_.empty()) [[unlikely]] {
      auto it = std::min_element(below_.begin(), below_.end(), KeyLess);
      const Entry e = *it;
      *it = below_.back();
      below_.pop_back();
      return e;
    }
    if (buckets_[0].empty()) Refill();
    const Entry e = buckets_[0].back();
    buckets_[0].pop_back();
    return e;
  }

  // Bytes held, for metrics.
  size_t MemoryBytes() const {
    size_t bytes = below_.capacity() * sizeof(Entry);
    for (const std::vector<Entry>& b : buckets_)
      bytes += b.capacity() * sizeof(Entry);
    return bytes;
  }

 private:
  static bool KeyLess(const Entry& a, const Entry& b) { return a.key < b.key; }

  size_t BucketOf(uint64_t key) const {
    return static_cast<size_t>(std::bit_width(key ^ last_));
  }

  // Bucket 0 is empty and some bucket is not: the lowest non-empty bucket's
  // minimum becomes last_ and its entries fall into lower buckets (all of
  // them share last_'s bits above their bucket's bit, so none stays).
  void Refill() {
    size_t b = 1;
    while (buckets_[b].empty()) ++b;
    std::vector<Entry>& from = buckets_[b];
    uint64_t least = from.front().key;
    for (const Entry& e : from) least = std::min(least, e.key);
    last_ = least;
    for (const Entry& e : from) buckets_[BucketOf(e.key)].push_back(e);
    from.clear();
  }

  std::array<std::vector<Entry>, 65> buckets_;
  std::vector<Entry> below_;
  uint64_t last_ = 0;
  size_t size_ = 0;
};

// The open list of BestFirstSearch for the priority f = g (Dijkstra, the
// backward cost-to-go sweep), where keys never decrease: a node's successors
// cost at least one move more. Same interface and same order as OpenList:
// by OpenList::Key(g), then the larger g first. Both are one 64-bit key:
// the bits of g >= 0 with the low kTieBits bits inverted, since the bit
// pattern of a non-negative double orders like its value. A successor's key
// is above its parent's while a move (>= 1) is wider than a key bucket
// (g < 2^32); beyond that the heap's side list keeps the order.
//
// Lazy deletion instead of decrease-key: a push that lowers a node's g adds
// an entry and leaves the old one, skipped when it surfaces (its g is no
// longer the node's). Nodes count as open once pushed (open_pos 0) and closed
// when popped, as OpenList marks them.
// Not thread-safe: one per search, over that search's scratch.
class MonotoneOpenList {
 public:
  // The heap's buckets, kept between searches by the thread's scratch.
  struct Storage : SearchScratch::Extension {
    RadixHeap<uint32_t> heap;
    size_t MemoryBytes() const override { return heap.MemoryBytes(); }
  };

  explicit MonotoneOpenList(SearchScratch& scratch)
      : scratch_(scratch), heap_(scratch.extension<Storage>().heap) {
    heap_.Clear();
  }

  bool empty() const { return open_nodes_ == 0; }
  size_t size() const { return open_nodes_; }

  // Inserts `index` or lowers its g. Precondition: f == g >= 0, lower than
  // any g pushed for `index` before. (A key below the last pop, which only
  // g past 2^32 gives, goes to the heap's side list: right, but linear.)
  void Push(uint32_t index, [[maybe_unused]] double f, double g) {
    SearchScratch::Node& node = scratch_.Raw(index);
    if (node.open_pos == SearchScratch::kNotInOpen) {
      node.open_pos = 0;
      ++open_nodes_;
    }
    heap_.Push(KeyOf(g), index);
  }

  // Removes and returns the best entry; the node is marked closed.
  // Precondition: !empty().
  SearchScratch::OpenEntry Pop() {
    SkipStale();
    const auto e = heap_.Pop();
    scratch_.Raw(e.value).open_pos = SearchScratch::kClosed;
    --open_nodes_;
    return EntryOf(e);
  }

  // The entry Pop() returns next (by value: f is OpenList::Key(g)).
  // Precondition: !empty().
  SearchScratch::OpenEntry Top() {
    SkipStale();
    return EntryOf(heap_.Top());
  }

  static constexpr uint64_t kTieMask = (uint64_t{1} << OpenList::kTieBits) - 1;
  static uint64_t KeyOf(double g) {
    return std::bit_cast<uint64_t>(g) ^ kTieMask;
  }
  static double GOf(uint64_t key) {
    return std::bit_cast<double>(key ^ kTieMask);
  }

 private:
  // Drops entries whose node was popped already or has a lower g since.
  void SkipStale() {
    while (true) {
      const auto& e = heap_.Top();
      const SearchScratch::Node& node = scratch_.Raw(e.value);
      if (node.open_pos != SearchScratch::kClosed && node.g == GOf(e.key))
        return;
      heap_.Pop();
    }
  }

  static SearchScratch::OpenEntry EntryOf(const RadixHeap<uint32_t>::Entry& e) {
    const double g = GOf(e.key);
    return SearchScratch::OpenEntry{OpenList::Key(g), g, e.value};
  }

  SearchScratch& scratch_;
  RadixHeap<uint32_t>& heap_;
  size_t open_nodes_ = 0;
};

}  // namespace pathd::internal

#endif  // PATHD_CORE_SEARCH_RADIX_HEAP_H_
