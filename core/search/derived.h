// Derived representations of a map version: what a planner builds from the
// grid before it can search (a free-space bitmap, a visibility graph, a
// navigation mesh, a Voronoi graph, a shortest path map to one goal). A
// planner asks for one through PlanRequest::derived with a key naming the
// kind and every parameter it depends on; the server's DerivedCache
// (server/derived_cache.h) keeps one value per (map version, key), builds it
// once under concurrency, advances it from the previous version's value with
// that version's changed cells, and counts it in the memory budget. Without
// a store (tests, a robot linking core) the value is built for the query.
//
// A build can take minutes (a visibility graph tests O(V^2) pairs), so it
// runs under the requesting query's stop condition (DerivedStop): a long
// build polls it and gives up, and a query waiting for another's build waits
// only until its own deadline.
#ifndef PATHD_CORE_SEARCH_DERIVED_H_
#define PATHD_CORE_SEARCH_DERIVED_H_

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <utility>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "absl/types/span.h"
#include "core/map/grid.h"

namespace pathd {

// From core/search/plan_types.h (which includes this header for
// PlanRequest::derived) and stop_condition.h (which includes that one).
class StopCondition;
enum class PlanOutcome;
struct PlanResult;

// A derived build's view of the requesting query's stop condition, and a
// note of what gave up when it fired, for the query's message. Only the
// deadline and cancellation apply: the expansion budget counts search work,
// and a build's work is not the query's to budget. Made by the planner for
// one query and used on its thread (the store runs a query's builds on the
// caller's thread); thread-compatible.
class DerivedStop {
 public:
  // Never fires.
  DerivedStop() = default;
  // `condition` must outlive this.
  explicit DerivedStop(const StopCondition& condition) : condition_(&condition) {}

  // The condition fired: give up. Reads the clock, so a build calls it after
  // a few milliseconds of work at most (a visibility graph: once per
  // vertex), not after every unit of it.
  bool Stopped() const;
  // kTimeout or kCancelled when the condition fired, else kFound.
  PlanOutcome Outcome() const;
  // The query's deadline (InfiniteFuture when none): how long a wait for
  // another query's build may last.
  absl::Time deadline() const;

  // Records what gave up, as the subject of the query's message ("building
  // the visibility graph of this map version (49154 vertices)"). The first
  // note stands: a build nested in another (the visibility graph under a
  // shortest path map) gives up first, and it is what was running.
  void Note(std::string what) {
    if (stopped_while_.empty()) stopped_while_ = std::move(what);
  }
  // Empty until something gave up.
  const std::string& stopped_while() const { return stopped_while_; }

 private:
  // Null: never fires.
  const StopCondition* condition_ = nullptr;
  std::string stopped_while_;
};

// The result of a query whose planner got no derived value from GetDerived:
// the outcome the stop condition gives (kTimeout or kCancelled) and what was
// running, for the caller's message. INTERNAL when the condition had not
// fired (a build returned null without being stopped).
absl::StatusOr<PlanResult> StoppedWhileDeriving(const DerivedStop& stop);

// How to make one kind of derived value, type-erased for the store. build
// and advance run on the requesting query's thread under its `stop`; a long
// one polls it and returns null when it fired (after noting what it was
// doing, or the store notes "building <what>").
struct DerivedRecipe {
  // The value for `grid`, from scratch; null: stopped.
  std::function<std::shared_ptr<const void>(const Grid& grid, DerivedStop& stop)>
      build;
  // The value for `grid` from `previous`, the value of an older version of
  // the same map, whose cells differ from `grid` only in `changed` (which
  // may also list cells that did not change: a server store passes the
  // union of several updates' cells, one changed back among them);
  // null: rebuild (build then returns null at once if `stop` fired). May be
  // empty (always rebuild).
  std::function<std::shared_ptr<const void>(const void* previous,
                                            const Grid& grid,
                                            absl::Span<const Cell> changed,
                                            DerivedStop& stop)>
      advance;
  // Memory the value holds, for the budget.
  std::function<size_t(const void* value)> bytes;
  // What the value is, for messages: "the visibility graph of this map
  // version". Empty: the key says it.
  std::string what;
};

// Where derived values of the grid being planned on live. Thread-safe.
class DerivedStore {
 public:
  virtual ~DerivedStore() = default;
  // The value under `key` for the query's grid (the one this store was made
  // for), made with `recipe` under `stop` when missing. Null when `stop`
  // fired first, while this query built it or while it waited for another
  // query's build (a query never waits past its own deadline); `stop` then
  // says what it was doing.
  virtual std::shared_ptr<const void> Get(const std::string& key,
                                          const DerivedRecipe& recipe,
                                          DerivedStop& stop) = 0;
};

// A typed view of a recipe, for builds that poll the query's stop condition:
//   build(const Grid&, DerivedStop&) -> std::shared_ptr<const T>
//   advance(const T& previous, const Grid&, absl::Span<const Cell> changed,
//           DerivedStop&) -> std::shared_ptr<const T>
//   bytes(const T&) -> size_t
// Returns the store's value for the query's grid, or one built now when
// `store` is null; null when `stop` fired first (stop.stopped_while() says
// what was running). `what` names the value in messages ("the visibility
// graph of this map version").
template <typename T, typename BuildFn, typename AdvanceFn, typename BytesFn>
std::shared_ptr<const T> GetDerived(DerivedStore* store, const Grid& grid,
                                    const std::string& key, std::string_view what,
                                    DerivedStop& stop, BuildFn build,
                                    AdvanceFn advance, BytesFn bytes) {
  if (store == nullptr) {
    std::shared_ptr<const T> value = build(grid, stop);
    if (value == nullptr) stop.Note("building " + std::string(what));
    return value;
  }
  DerivedRecipe recipe;
  recipe.build = [build](const Grid& g, DerivedStop& s) -> std::shared_ptr<const void> {
    return build(g, s);
  };
  recipe.advance = [advance](const void* previous, const Grid& g,
                             absl::Span<const Cell> changed,
                             DerivedStop& s) -> std::shared_ptr<const void> {
    return advance(*static_cast<const T*>(previous), g, changed, s);
  };
  recipe.bytes = [bytes](const void* value) {
    return bytes(*static_cast<const T*>(value));
  };
  recipe.what = std::string(what);
  return std::static_pointer_cast<const T>(store->Get(key, recipe, stop));
}

// The same for builds that do not poll (they are fast): build(const Grid&),
// advance(const T&, const Grid&, changed), bytes(const T&). Never null: a
// query waiting for another's build of it waits for as long as that takes.
template <typename T, typename BuildFn, typename AdvanceFn, typename BytesFn>
std::shared_ptr<const T> GetDerived(DerivedStore* store, const Grid& grid,
                                    const std::string& key, BuildFn build,
                                    AdvanceFn advance, BytesFn bytes) {
  DerivedStop never;
  return GetDerived<T>(
      store, grid, key, key, never,
      [build](const Grid& g, DerivedStop&) { return build(g); },
      [advance](const T& previous, const Grid& g, absl::Span<const Cell> changed,
                DerivedStop&) { return advance(previous, g, changed); },
      bytes);
}

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_DERIVED_H_
