#include "core/geometry/structure.h"

#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"

namespace pathd {
namespace {

struct Kind {
  std::string_view name;
  GeometricStructure (*describe)(const Grid&, bool);
};

// One line per kind.
const std::vector<Kind>& Kinds() {
  static const std::vector<Kind>* const kKinds = new std::vector<Kind>{
      {"polygons", &DescribeObstaclePolygons},
      {"decomposition", &DescribeDecomposition},
      {"voronoi", &DescribeVoronoi},
      {"visibility", &DescribeVisibilityGraph},
      {"mesh", &DescribeNavMesh},
  };
  return *kKinds;
}

}  // namespace

const std::vector<std::string_view>& StructureKinds() {
  static const std::vector<std::string_view>* const kNames = [] {
    auto* names = new std::vector<std::string_view>();
    for (const Kind& k : Kinds()) names->push_back(k.name);
    return names;
  }();
  return *kNames;
}

absl::StatusOr<GeometricStructure> DescribeStructure(std::string_view kind,
                                                     const Grid& grid,
                                                     bool unknown_is_free) {
  for (const Kind& k : Kinds()) {
    if (k.name == kind) return k.describe(grid, unknown_is_free);
  }
  std::vector<std::string> known(StructureKinds().begin(), StructureKinds().end());
  return absl::InvalidArgumentError(absl::StrCat(
      "unknown structure '", std::string(kind), "'; known: ", absl::StrJoin(known, ", ")));
}

}  // namespace pathd
