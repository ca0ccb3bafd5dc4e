// Derived representations of a map version: what a planner builds from the
// grid before it can search (a free-space bitmap, a visibility graph, a
// navigation mesh, a Voronoi graph, a shortest path map to one goal). A
// planner asks for one through PlanRequest::derived with a key naming the
// kind and every parameter it depends on; the server's DerivedCache
// (server/derived_cache.h) keeps one value per (map version, key), builds it
// once under concurrency, advances it from the previous version's value with
// that version's changed cells, and counts it in the memory budget. Without
// a store (tests, a robot linking core) the value is built for the query.
#ifndef PATHD_CORE_SEARCH_DERIVED_H_
#define PATHD_CORE_SEARCH_DERIVED_H_

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "absl/types/span.h"
#include "core/map/grid.h"

namespace pathd {

// How to make one kind of derived value, type-erased for the store.
struct DerivedRecipe {
  // The value for `grid`, from scratch.
  std::function<std::shared_ptr<const void>(const Grid& grid)> build;
  // The value for `grid` from `previous`, the value of an older version of
  // the same map, whose cells differ from `grid` exactly in `changed`;
  // null: rebuild. May be empty (always rebuild).
  std::function<std::shared_ptr<const void>(const void* previous,
                                            const Grid& grid,
                                            absl::Span<const Cell> changed)>
      advance;
  // Memory the value holds, for the budget.
  std::function<size_t(const void* value)> bytes;
};

// Where derived values of the grid being planned on live. Thread-safe.
class DerivedStore {
 public:
  virtual ~DerivedStore() = default;
  // The value under `key` for the query's grid (the one this store was made
  // for), made with `recipe` when missing.
  virtual std::shared_ptr<const void> Get(const std::string& key,
                                          const DerivedRecipe& recipe) = 0;
};

// A typed view of a recipe: T must provide
//   static std::shared_ptr<const T> Build(const Grid&, Params...)
// through the lambdas the caller passes. Returns the store's value for the
// query's grid, or one built now when `store` is null.
template <typename T, typename BuildFn, typename AdvanceFn, typename BytesFn>
std::shared_ptr<const T> GetDerived(DerivedStore* store, const Grid& grid,
                                    const std::string& key, BuildFn build,
                                    AdvanceFn advance, BytesFn bytes) {
  if (store == nullptr) return build(grid);
  DerivedRecipe recipe;
  recipe.build = [build](const Grid& g) -> std::shared_ptr<const void> {
    return build(g);
  };
  recipe.advance = [advance](const void* previous, const Grid& g,
                             absl::Span<const Cell> changed)
      -> std::shared_ptr<const void> {
    return advance(*static_cast<const T*>(previous), g, changed);
  };
  recipe.bytes = [bytes](const void* value) {
    return bytes(*static_cast<const T*>(value));
  };
  return std::static_pointer_cast<const T>(store->Get(key, recipe));
}

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_DERIVED_H_
