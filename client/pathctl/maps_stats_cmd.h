// The one-line description of a geometric structure that maps stats and
// render --overlay print.
#ifndef PATHD_CLIENT_PATHCTL_MAPS_STATS_CMD_H_
#define PATHD_CLIENT_PATHCTL_MAPS_STATS_CMD_H_

#include <string>

#include "core/geometry/structure.h"

namespace pathd::pathctl {

// "mesh: 250 tiles, 1204 vertices, 1378 triangles, 823 polygons; 96.0 KiB;
// built in 3.412 ms".
std::string StructureSummary(const GeometricStructure& structure);

}  // namespace pathd::pathctl

#endif  // PATHD_CLIENT_PATHCTL_MAPS_STATS_CMD_H_
