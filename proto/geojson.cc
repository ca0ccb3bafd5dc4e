#include "proto/geojson.h"

#include <cmath>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "proto/path_codec.h"

namespace pathd {
namespace {

std::string Position(const v1::WorldPoint& p) {
  return absl::StrFormat("[%.6f, %.6f]", p.x(), p.y());
}

// A ring as GeoJSON positions, the first repeated at the end as RFC 7946
// asks.
std::string Ring(const v1::WorldRing& ring) {
  std::vector<std::string> coords;
  for (const v1::WorldPoint& p : ring.points()) coords.push_back(Position(p));
  if (!coords.empty()) coords.push_back(coords.front());
  return absl::StrCat("[", absl::StrJoin(coords, ", "), "]");
}

// JSON has no infinity or NaN: an unreachable cost prints as null.
std::string Number(double value) {
  return std::isfinite(value) ? absl::StrFormat("%.9g", value) : "null";
}

}  // namespace

std::string PlanGeoJson(const v1::PlanResponse& answer, std::string_view map) {
  // A packed-only answer (options.path_encoding PACKED) draws the same line;
  // bytes that do not decode draw none.
  v1::PlanResponse unpacked;
  const bool packed_only = answer.path_size() == 0 && !answer.packed_path().empty();
  if (packed_only) {
    unpacked = answer;
    UnpackPlanPath(&unpacked).IgnoreError();
  }
  const v1::PlanResponse& plan = packed_only ? unpacked : answer;
  std::vector<std::string> coords;
  if (plan.world_polyline_size() > 0) {
    for (const v1::WorldPoint& p : plan.world_polyline()) coords.push_back(Position(p));
  } else {
    for (const v1::WorldPoint& p : plan.world_path()) coords.push_back(Position(p));
  }
  // A LineString needs two positions: a start that is the goal repeats it.
  if (coords.size() == 1) coords.push_back(coords.front());
  const std::string geometry =
      coords.empty() ? "null"
                     : absl::StrCat("{\"type\": \"LineString\", \"coordinates\": [",
                                    absl::StrJoin(coords, ", "), "]}");
  return absl::StrFormat(
      "{\"type\": \"FeatureCollection\", \"features\": [{\"type\": \"Feature\", "
      "\"geometry\": %s, \"properties\": {\"map\": \"%s\", \"map_version\": %d, "
      "\"frame_id\": \"%s\", \"planner\": \"%s\", \"found\": %s, \"outcome\": \"%s\", "
      "\"start\": [%d, %d], \"goal\": [%d, %d], \"cost\": %s, \"length\": %s, "
      "\"cost_m\": %s, \"length_m\": %s, \"expansions\": %d}}]}\n",
      geometry, std::string(map), plan.map_version(), plan.frame_id(), plan.planner(),
      plan.found() ? "true" : "false", v1::PlanOutcome_Name(plan.outcome()),
      plan.start().x(), plan.start().y(), plan.goal().x(), plan.goal().y(),
      Number(plan.cost()), Number(plan.length()), Number(plan.cost_m()),
      Number(plan.length_m()), plan.expansions());
}

std::string IsochroneGeoJson(const v1::IsochroneResponse& r, std::string_view map) {
  std::vector<std::string> polygons;
  for (const v1::IsochronePolygon& p : r.polygons()) {
    std::vector<std::string> rings{Ring(p.world_exterior())};
    for (const v1::WorldRing& hole : p.world_holes()) rings.push_back(Ring(hole));
    polygons.push_back(absl::StrCat("[", absl::StrJoin(rings, ", "), "]"));
  }
  return absl::StrFormat(
      "{\"type\": \"FeatureCollection\", \"features\": [{\"type\": \"Feature\", "
      "\"geometry\": {\"type\": \"MultiPolygon\", \"coordinates\": [%s]}, "
      "\"properties\": {\"map\": \"%s\", \"map_version\": %d, \"frame_id\": \"%s\", "
      "\"start\": [%d, %d], \"budget_m\": %.6f, \"reachable_cells\": %d, "
      "\"area_m2\": %.6f}}]}\n",
      absl::StrJoin(polygons, ", "), std::string(map), r.map_version(), r.frame_id(),
      r.start().x(), r.start().y(), r.budget_m(), r.reachable_cells(), r.area_m2());
}

}  // namespace pathd
