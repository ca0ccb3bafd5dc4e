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

// An `hpa_star` planner with clusters of cluster_size x cluster_size cells
// (precondition: >= 2). Thread-safe like every Planner.
std::unique_ptr<Planner> MakeHpaStarPlanner(int32_t cluster_size);

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_HIERARCHICAL_HPA_STAR_H_
