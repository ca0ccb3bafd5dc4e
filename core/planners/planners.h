// Factories of the built-in planners. The registry (registry.cc) is the only
// caller; everything else creates planners by name.
#ifndef PATHD_CORE_PLANNERS_PLANNERS_H_
#define PATHD_CORE_PLANNERS_PLANNERS_H_

#include <memory>

#include "core/search/planner.h"

namespace pathd {

std::unique_ptr<Planner> MakeAStarPlanner();
std::unique_ptr<Planner> MakeDijkstraPlanner();
std::unique_ptr<Planner> MakeBfsPlanner();
std::unique_ptr<Planner> MakeWavefrontPlanner();
std::unique_ptr<Planner> MakeDistanceTransformPlanner();
std::unique_ptr<Planner> MakeDistanceTransformExactPlanner();
std::unique_ptr<Planner> MakePotentialFieldPlanner();
std::unique_ptr<Planner> MakeDfsPlanner();
std::unique_ptr<Planner> MakeGreedyPlanner();
std::unique_ptr<Planner> MakeWeightedAStarPlanner();
std::unique_ptr<Planner> MakeRtaaStarPlanner();
std::unique_ptr<Planner> MakeLrtaStarPlanner();
std::unique_ptr<Planner> MakeThetaStarPlanner();
std::unique_ptr<Planner> MakeLazyThetaStarPlanner();
std::unique_ptr<Planner> MakeJpsPlanner();
// JPS+ over per-version jump tables advanced around changed cells.
std::unique_ptr<Planner> MakeJpsPlusPlanner();
std::unique_ptr<Planner> MakeLpaStarPlanner();
std::unique_ptr<Planner> MakeDStarLitePlanner();
std::unique_ptr<Planner> MakeShortestPathMapPlanner();
std::unique_ptr<Planner> MakeTrapezoidalPlanner();
std::unique_ptr<Planner> MakeVoronoiPlanner();
std::unique_ptr<Planner> MakeVisibilityGraphPlanner();
std::unique_ptr<Planner> MakeMinimalConstructPlanner();
std::unique_ptr<Planner> MakeEuclideanSpmPlanner();
std::unique_ptr<Planner> MakeNavMeshPlanner();
std::unique_ptr<Planner> MakeStateLatticePlanner();
std::unique_ptr<Planner> MakeHybridAStarPlanner();
std::unique_ptr<Planner> MakeHpaStarPlanner();
std::unique_ptr<Planner> MakeQuadtreePlanner();
std::unique_ptr<Planner> MakeAntColonyPlanner();
std::unique_ptr<Planner> MakeReactionDiffusionPlanner();

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_PLANNERS_H_
