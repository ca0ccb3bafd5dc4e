// The name -> planner registry with every built-in planner (the list lives in
// registry.cc); everything outside core/planners/ creates planners by name.
#ifndef PATHD_CORE_SEARCH_REGISTRY_H_
#define PATHD_CORE_SEARCH_REGISTRY_H_

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/search/planner.h"

namespace pathd {

// Name -> factory registry. Thread-safe after start-up: registration happens
// in RegisterBuiltinPlanners() before any lookup.
class PlannerRegistry {
 public:
  using Factory = std::function<std::unique_ptr<Planner>()>;

  // The process-wide registry with every built-in planner registered.
  static const PlannerRegistry& Default();

  // Registers a planner under its name(); fails with ALREADY_EXISTS on a
  // duplicate name.
  absl::Status Register(Factory factory);

  // Creates the planner called `name`; NOT_FOUND lists the known names.
  absl::StatusOr<std::unique_ptr<Planner>> Create(std::string_view name) const;
  // A shared instance (planners are stateless), or nullptr for unknown names.
  const Planner* Get(std::string_view name) const;
  // Registered names, sorted.
  std::vector<std::string> Names() const;

 private:
  std::vector<std::unique_ptr<Planner>> planners_;
  std::vector<Factory> factories_;
};

}  // namespace pathd

#endif  // PATHD_CORE_SEARCH_REGISTRY_H_
