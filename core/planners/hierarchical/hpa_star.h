// HPA* (Botea, Müller & Schaeffer 2004, "Near Optimal Hierarchical
// Path-Finding"): plans on the abstract graph of hpa_graph.h and refines the
// abstract path to grid moves. The registry's `hpa_star` uses
// kHpaDefaultClusterSize; benchmarks and tests make other sizes here.
#ifndef PATHD_CORE_PLANNERS_HIERARCHICAL_HPA_STAR_H_
#define PATHD_CORE_PLANNERS_HIERARCHICAL_HPA_STAR_H_

#include <cstdint>
#include <memory>

#include "core/search/planner.h"

namespace pathd {

// Cluster side of the registered planner, cells. docs/decisions.md ("HPA*")
// gives the measurements it was chosen by.
inline constexpr int32_t kHpaDefaultClusterSize = 16;

// How the abstract path becomes grid moves.
enum class HpaRefinement {
  // One A* inside the union of the clusters the abstract path passes
  // through (its corridor): the best path in that corridor, so the detours
  // through transitions mostly vanish. The registered planner's.
  kCorridor,
  // Botea et al.'s: one A* inside the cluster of each abstract edge, so
  // the path runs through every transition of the abstract path.
  kPerEdge,
};

// An `hpa_star` planner with clusters of cluster_size x cluster_size cells
// (precondition: >= 2). Thread-safe like every Planner.
std::unique_ptr<Planner> MakeHpaStarPlanner(
    int32_t cluster_size, HpaRefinement refinement = HpaRefinement::kCorridor);

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_HIERARCHICAL_HPA_STAR_H_
