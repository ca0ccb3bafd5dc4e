// The planner registry and the list of built-in planners.
#include "core/search/registry.h"

#include <algorithm>
#include <cstdlib>

#include "absl/status/status.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "core/planners/planners.h"

namespace pathd {

const PlannerRegistry& PlannerRegistry::Default() {
  // Built once, on first use, then only read: safe to share between threads.
  static const PlannerRegistry* const kRegistry = [] {
    auto* registry = new PlannerRegistry();
    for (PlannerRegistry::Factory factory : {
             PlannerRegistry::Factory(&MakeAStarPlanner),
             PlannerRegistry::Factory(&MakeDijkstraPlanner),
             PlannerRegistry::Factory(&MakeBfsPlanner),
             PlannerRegistry::Factory(&MakeWavefrontPlanner),
             PlannerRegistry::Factory(&MakeDistanceTransformPlanner),
             PlannerRegistry::Factory(&MakeDistanceTransformExactPlanner),
             PlannerRegistry::Factory(&MakePotentialFieldPlanner),
             PlannerRegistry::Factory(&MakeDfsPlanner),
             PlannerRegistry::Factory(&MakeGreedyPlanner),
             PlannerRegistry::Factory(&MakeWeightedAStarPlanner),
             PlannerRegistry::Factory(&MakeRtaaStarPlanner),
             PlannerRegistry::Factory(&MakeLrtaStarPlanner),
             PlannerRegistry::Factory(&MakeThetaStarPlanner),
             PlannerRegistry::Factory(&MakeLazyThetaStarPlanner),
             PlannerRegistry::Factory(&MakeJpsPlanner),
             PlannerRegistry::Factory(&MakeLpaStarPlanner),
             PlannerRegistry::Factory(&MakeDStarLitePlanner),
             PlannerRegistry::Factory(&MakeShortestPathMapPlanner),
             PlannerRegistry::Factory(&MakeTrapezoidalPlanner),
             PlannerRegistry::Factory(&MakeVoronoiPlanner),
             PlannerRegistry::Factory(&MakeVisibilityGraphPlanner),
             PlannerRegistry::Factory(&MakeMinimalConstructPlanner),
             PlannerRegistry::Factory(&MakeEuclideanSpmPlanner),
             PlannerRegistry::Factory(&MakeNavMeshPlanner),
             PlannerRegistry::Factory(&MakeStateLatticePlanner),
             PlannerRegistry::Factory(&MakeHybridAStarPlanner),
             PlannerRegistry::Factory(&MakeHpaStarPlanner),
             PlannerRegistry::Factory(&MakeQuadtreePlanner),
             PlannerRegistry::Factory(&MakeAntColonyPlanner),
             PlannerRegistry::Factory(&MakeReactionDiffusionPlanner),
             PlannerRegistry::Factory(&MakeJpsPlusPlanner),
         }) {
      absl::Status status = registry->Register(std::move(factory));
      if (!status.ok()) std::abort();  // a programming error in this list
    }
    return registry;
  }();
  return *kRegistry;
}

absl::Status PlannerRegistry::Register(Factory factory) {
  std::unique_ptr<Planner> planner = factory();
  if (planner == nullptr) return absl::InvalidArgumentError("factory returned null");
  if (Get(planner->name()) != nullptr) {
    return absl::AlreadyExistsError(
        absl::StrFormat("planner '%s' is already registered", planner->name()));
  }
  planners_.push_back(std::move(planner));
  factories_.push_back(std::move(factory));
  return absl::OkStatus();
}

absl::StatusOr<std::unique_ptr<Planner>> PlannerRegistry::Create(
    std::string_view name) const {
  for (size_t i = 0; i < planners_.size(); ++i) {
    if (planners_[i]->name() == name) return factories_[i]();
  }
  return absl::NotFoundError(absl::StrFormat(
      "unknown planner '%s' (known: %s)", name, absl::StrJoin(Names(), ", ")));
}

const Planner* PlannerRegistry::Get(std::string_view name) const {
  for (const auto& planner : planners_) {
    if (planner->name() == name) return planner.get();
  }
  return nullptr;
}

std::vector<std::string> PlannerRegistry::Names() const {
  std::vector<std::string> names;
  for (const auto& planner : planners_) names.emplace_back(planner->name());
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace pathd
