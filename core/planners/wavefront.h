// The wave-front planner's label grid (the "Wave-Front Planner" of the lecture
// "Path Planning in Discrete Sampled Space"): obstacles 1, the goal 2, and
// every other reached cell one more than the neighbour the wave came from.
// Exposed so tests and visualisations can compare labels with the lecture's
// worked example; the planner itself is "wavefront".
#ifndef PATHD_CORE_PLANNERS_WAVEFRONT_H_
#define PATHD_CORE_PLANNERS_WAVEFRONT_H_

#include <cstdint>
#include <optional>
#include <vector>

#include "core/map/cost_model.h"
#include "core/map/grid.h"
#include "core/search/planner.h"

namespace pathd {

inline constexpr int32_t kWavefrontUnlabelled = 0;
inline constexpr int32_t kWavefrontObstacle = 1;
inline constexpr int32_t kWavefrontGoal = 2;

// A labelled grid and how the flood ended.
struct WavefrontLabelling {
  // Row-major: kWavefrontObstacle for cells not traversable under the cost
  // parameters, kWavefrontUnlabelled for traversable cells the wave did not
  // reach, else kWavefrontGoal + the number of moves to the goal.
  std::vector<int32_t> labels;
  // kFound when the flood finished (the start is labelled, or every reachable
  // cell is when there is no start), kNoPath when the wave died out before
  // reaching the start, else the stop condition's outcome.
  PlanOutcome outcome = PlanOutcome::kNoPath;
  // Cells whose neighbours were labelled.
  int64_t expansions = 0;
};

// Floods labels from `goal` under cost.connectivity (4: exactly the lecture's
// moves; 8: the diagonal moves too, without corner cutting). With a start the
// flood stops like the lecture's loop "while start cell is unlabelled": after the
// layer that labels the start, so every cell labelled at most the start's
// label is labelled and none beyond; without one it labels every reachable
// cell. Cell costs only decide what is blocked. Precondition: the goal (and
// start, if given) is on the grid and traversable.
WavefrontLabelling WavefrontLabels(const Grid& grid, Cell goal, const CostParams& cost,
                                   std::optional<Cell> start,
                                   const StopCondition& stop = StopCondition::None());

}  // namespace pathd

#endif  // PATHD_CORE_PLANNERS_WAVEFRONT_H_
