// GeoJSON (RFC 7946) of answers that are places in a map's world frame: a
// plan's path and an isochrone's region. The server's HTTP API
// (?format=geojson) and pathctl (--output geojson) print the same text.
// Coordinates are the map's world metres (frame_id), not longitude and
// latitude: RFC 7946's CRS is WGS 84, so these are for tools that take
// planar GeoJSON (QGIS with a local CRS, geojson.io-style viewers, Shapely).
#ifndef PATHD_PROTO_GEOJSON_H_
#define PATHD_PROTO_GEOJSON_H_

#include <string>
#include <string_view>

#include "pathd/v1/planner_service.pb.h"

namespace pathd {

// A FeatureCollection with one Feature: a LineString of the path in world
// metres (the any-angle polyline when there is one, else the cells' centres)
// or a null geometry when nothing was found, and the plan's figures as
// properties. A packed-only answer (PATH_ENCODING_PACKED) is decoded first. `map`: the map's name (A-Z a-z 0-9 . _ -, so no escaping).
std::string PlanGeoJson(const v1::PlanResponse& plan, std::string_view map);

// A FeatureCollection with one MultiPolygon Feature: exteriors
// counter-clockwise, holes clockwise, as RFC 7946 asks (the world frame's y
// axis points the way cell rows grow, so cell orientation carries over).
std::string IsochroneGeoJson(const v1::IsochroneResponse& isochrone, std::string_view map);

}  // namespace pathd

#endif  // PATHD_PROTO_GEOJSON_H_
