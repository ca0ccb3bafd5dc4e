// Per-thread search memory reused across queries. Each cell's record carries
// the id of the search that last wrote it, so starting a new search costs O(1)
// instead of clearing O(map) memory; memory grows only for a larger map.
// The records live in pages the kernel commits only when a search writes
// them, so a short search on a huge map costs the pages it touched, not 24
// bytes per map cell (docs/performance.md, "Huge maps").
#ifndef PATHD_CORE_SEARCH_SEARCH_SCRATCH_H_
#define PATHD_CORE_SEARCH_SEARCH_SCRATCH_H_

#include <sys/mman.h>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <new>
#include <memory>
#include <type_traits>
#include <utility>
#include <vector>

namespace pathd {

// An array of trivially copyable T, all bytes zero, in its own anonymous
// mapping: a page is committed when first written, and Zero() hands every
// page back to the kernel (reads see zeros again). Not thread-safe.
template <typename T>
class ZeroPageArray {
  static_assert(std::is_trivially_copyable_v<T>);

 public:
  ZeroPageArray() = default;
  ZeroPageArray(const ZeroPageArray&) = delete;
  ZeroPageArray& operator=(const ZeroPageArray&) = delete;
  ~ZeroPageArray() { Unmap(); }

  size_t size() const { return size_; }
  T& operator[](size_t i) { return data_[i]; }
  const T& operator[](size_t i) const { return data_[i]; }

  // n zero elements; the old contents are dropped. Throws std::bad_alloc
  // when the mapping fails, as a vector would.
  void Reallocate(size_t n) {
    Unmap();
    if (n == 0) return;
    void* p = mmap(nullptr, n * sizeof(T), PROT_READ | PROT_WRITE,
                   MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
    if (p == MAP_FAILED) throw std::bad_alloc();
    data_ = static_cast<T*>(p);
    size_ = n;
  }
  // Every element back to zero, and every page back to the kernel.
  void Zero() {
    if (data_ != nullptr) madvise(data_, size_ * sizeof(T), MADV_DONTNEED);
  }

 private:
  void Unmap() {
    if (data_ != nullptr) munmap(data_, size_ * sizeof(T));
    data_ = nullptr;
    size_ = 0;
  }
  T* data_ = nullptr;
  size_t size_ = 0;
};

// Not thread-safe: one per worker thread (or per caller).
class SearchScratch {
 public:
  static constexpr uint32_t kNoParent = std::numeric_limits<uint32_t>::max();
  static constexpr int32_t kNotInOpen = -1;
  static constexpr int32_t kClosed = -2;

  struct Node {
    double g;
    uint32_t search_id;
    uint32_t parent;
    // Position in the open list, kNotInOpen or kClosed.
    int32_t open_pos;
  };

  // Entry of the open list; f and g are copied in for cache locality.
  struct OpenEntry {
    double f;
    double g;
    uint32_t index;
  };

  // State a planner derives from a map and keeps between queries on this
  // thread (JPS: bit-packed passability). Before each use the planner must
  // check that it still describes the grid it is given: the same Grid object
  // may have been edited since.
  class Extension {
   public:
    virtual ~Extension() = default;
    // Bytes held, for MemoryBytes().
    virtual size_t MemoryBytes() const = 0;
  };

  SearchScratch() = default;
  SearchScratch(const SearchScratch&) = delete;
  SearchScratch& operator=(const SearchScratch&) = delete;

  // Starts a new search over `cells` cells. O(1) unless the grid is larger
  // than any seen before or the 32-bit search id wraps (every 4 billion
  // searches), in which case the records are reset.
  //
  // Records are zero until a search writes them (search id 0 is never
  // current). Above kReleaseScratchBytes the pages the previous search
  // wrote go back to the kernel first, so a worker that once searched far on
  // a huge map does not keep gigabytes resident: the resident size is what
  // the current search touched. Below it they stay, and reused pages cost no
  // fault.
  static constexpr size_t kReleaseScratchBytes = size_t{256} << 20;
  void BeginSearch(size_t cells) {
    if (cells > nodes_.size()) {
      nodes_.Reallocate(cells);
      search_id_ = 0;
    } else if (nodes_.size() * sizeof(Node) > kReleaseScratchBytes) {
      nodes_.Zero();
      search_id_ = 0;
    }
    if (++search_id_ == 0) {
      nodes_.Zero();
      search_id_ = 1;
    }
    open_.clear();
    fifo_.clear();
  }

  // True when the current search has written cell i.
  bool Seen(size_t i) const { return nodes_[i].search_id == search_id_; }

  // The record of cell i, initialised for this search on first access.
  Node& At(size_t i) {
    Node& n = nodes_[i];
    if (n.search_id != search_id_) {
      n = Node{std::numeric_limits<double>::infinity(), search_id_, kNoParent,
               kNotInOpen};
    }
    return n;
  }
  // Raw access without initialisation; only valid when Seen(i).
  Node& Raw(size_t i) { return nodes_[i]; }
  const Node& Raw(size_t i) const { return nodes_[i]; }

  // Storage for the open list (binary heap) and for FIFO queues (BFS).
  std::vector<OpenEntry>& open() { return open_; }
  std::vector<uint32_t>& fifo() { return fifo_; }

  // Per-cell state that outlives BeginSearch(), for one query of a real-time
  // planner: the heuristic it learns over its many look-ahead searches, and
  // a few mark bits. BeginLearning() forgets all of it in O(1), stamped like
  // the nodes.
  void BeginLearning(size_t cells) {
    if (cells > learned_.size()) learned_.resize(cells, Learned{0.0, 0, 0});
    if (++learning_id_ == 0) {
      for (Learned& l : learned_) l.learning_id = 0;
      learning_id_ = 1;
    }
  }
  // True when cell i has a value since the last BeginLearning().
  bool HasLearned(size_t i) const {
    return learned_[i].learning_id == learning_id_ && (learned_[i].bits & kHasValue);
  }
  // The value of cell i, or `fallback` when it has none.
  double LearnedOr(size_t i, double fallback) const {
    return HasLearned(i) ? learned_[i].value : fallback;
  }
  void SetLearned(size_t i, double value) {
    Learned& l = FreshLearned(i);
    l.value = value;
    l.bits |= kHasValue;
  }
  // Mark bits 0..6 of cell i, all clear after BeginLearning().
  uint8_t LearnedMarks(size_t i) const {
    return learned_[i].learning_id == learning_id_ ? learned_[i].bits >> 1 : 0;
  }
  void AddLearnedMarks(size_t i, uint8_t marks) {
    FreshLearned(i).bits |= static_cast<uint8_t>(marks << 1);
  }

  // This scratch's instance of T (an Extension), default-constructed on first
  // use. A linear lookup: a scratch holds one per planner kind at most.
  template <typename T>
  T& extension() {
    static_assert(std::is_base_of_v<Extension, T>);
    const void* const key = &extension_key_<T>;
    for (auto& [k, e] : extensions_) {
      if (k == key) return static_cast<T&>(*e);
    }
    extensions_.emplace_back(key, std::make_unique<T>());
    return static_cast<T&>(*extensions_.back().second);
  }

  // Bytes held, for metrics.
  size_t MemoryBytes() const {
    // The nodes' mapping, whether its pages are resident or not.
    size_t bytes = nodes_.size() * sizeof(Node) +
                   open_.capacity() * sizeof(OpenEntry) +
                   fifo_.capacity() * sizeof(uint32_t) +
                   learned_.capacity() * sizeof(Learned);
    for (const auto& [key, e] : extensions_) bytes += e->MemoryBytes();
    return bytes;
  }
  uint32_t search_id() const { return search_id_; }

 private:
  ZeroPageArray<Node> nodes_;
  std::vector<OpenEntry> open_;
  std::vector<uint32_t> fifo_;
  uint32_t search_id_ = 0;

  struct Learned {
    double value;
    uint32_t learning_id;
    // kHasValue, then the mark bits.
    uint8_t bits;
  };
  static constexpr uint8_t kHasValue = 1;
  Learned& FreshLearned(size_t i) {
    Learned& l = learned_[i];
    if (l.learning_id != learning_id_) l = Learned{0.0, learning_id_, 0};
    return l;
  }
  std::vector<Learned> learned_;
  uint32_t learning_id_ = 0;
  // One distinct address per extension type (not const, so no linker can fold
  // two of them into one).
  template <typename T>
  static inline char extension_key_ = 0;
  std::vector<std::pair<const void*, std::unique_ptr<Extension>>> extensions_;
};

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_SEARCH_SCRATCH_H_
