// Lists the maps of a pathd server and plans once on the first of them,
// through the installed C++ client (find_package(pathd), pathd::client).
//   list_maps [HOST:PORT]   (default 127.0.0.1:50051)
#include <cstdio>
#include <string>

#include "absl/time/time.h"
#include "client/client.h"

int main(int argc, char** argv) {
  const std::string address =
      argc > 1 ? argv[1] : pathd::client::kDefaultServerAddress;
  // Every call gets this deadline and carries its map's name in the
  // x-pathd-map header.
  const pathd::client::PathdClient client(address, absl::Seconds(5));

  const auto health = client.CheckHealth();
  if (!health.ok()) {
    std::fprintf(stderr, "health: %s\n", health.status().ToString().c_str());
    return 1;
  }
  const auto maps = client.ListMaps();
  if (!maps.ok()) {
    std::fprintf(stderr, "ListMaps: %s\n", maps.status().ToString().c_str());
    return 1;
  }
  std::printf("%d map(s) on %s\n", maps->maps_size(), address.c_str());
  for (const pathd::v1::MapInfo& info : maps->maps()) {
    std::printf("%s %dx%d resolution %g version %llu\n", info.name().c_str(),
                info.width(), info.height(), info.resolution(),
                static_cast<unsigned long long>(info.version()));
  }
  if (maps->maps_size() == 0) return 0;

  // A plan between the map's first and last free cells: the cells come
  // with GetMap(include_cells).
  const pathd::v1::MapInfo& first = maps->maps(0);
  pathd::v1::GetMapRequest get;
  get.set_name(first.name());
  get.set_include_cells(true);
  const auto cells = client.GetMap(get);
  if (!cells.ok()) {
    std::fprintf(stderr, "GetMap: %s\n", cells.status().ToString().c_str());
    return 1;
  }
  const std::string& bytes = cells->cells();
  const size_t start = bytes.find('\0');
  const size_t goal = bytes.rfind('\0');
  if (start == std::string::npos) return 0;
  pathd::v1::PlanRequest plan;
  plan.set_map(first.name());
  plan.mutable_start()->mutable_cell()->set_x(static_cast<int>(start % first.width()));
  plan.mutable_start()->mutable_cell()->set_y(static_cast<int>(start / first.width()));
  plan.mutable_goal()->mutable_cell()->set_x(static_cast<int>(goal % first.width()));
  plan.mutable_goal()->mutable_cell()->set_y(static_cast<int>(goal / first.width()));
  const auto answer = client.Plan(plan);
  if (!answer.ok()) {
    std::fprintf(stderr, "Plan: %s\n", answer.status().ToString().c_str());
    return 1;
  }
  std::printf("plan on %s: found %s, %d cells, cost %.2f\n", first.name().c_str(),
              answer->found() ? "yes" : "no", answer->path_size(), answer->cost());
  return 0;
}
