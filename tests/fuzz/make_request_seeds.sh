#!/usr/bin/env bash
# Regenerates tests/fuzz/corpus/request_fuzz/seed_*: request_fuzz's seeds are
# binary protos (a selector byte, then the message), written here from text
# format with protoc so they can be read and changed. Crash inputs the fuzzer
# found are kept beside them as crash_* (not generated).
set -euo pipefail
cd "$(dirname "$0")/../.."
out=tests/fuzz/corpus/request_fuzz
mkdir -p "$out"
rm -f "$out"/seed_*

# seed NAME SELECTOR TYPE TEXT: selector 0 PlanRequest, 1 UpdateMapRequest,
# 2 CreateMapRequest (request_fuzz.cc).
seed() {
  local name=$1 selector=$2 type=$3 text=$4
  { printf "\\x0${selector}"
    protoc -I proto --encode="pathd.v1.${type}" pathd/v1/map_service.proto \
      pathd/v1/planner_service.proto <<<"$text"
  } >"$out/seed_${name}"
}

plan() { seed "plan_$1" 0 PlanRequest "$2"; }
ends='start { cell { x: 0 y: 0 } } goal { cell { x: 23 y: 19 } }'
for planner in ASTAR DIJKSTRA BFS DFS GREEDY WEIGHTED_ASTAR WAVEFRONT \
    DISTANCE_TRANSFORM DISTANCE_TRANSFORM_EXACT JPS THETA_STAR LAZY_THETA_STAR \
    RTAA_STAR LRTA_STAR POTENTIAL_FIELD LPA_STAR DSTAR_LITE SPM; do
  plan "${planner,,}" "map: 'weighted' planner: PLANNER_${planner} ${ends}"
done
plan jps_open "map: 'open' planner: PLANNER_JPS start { cell { x: 0 y: 0 } } goal { cell { x: 7 y: 5 } }"
plan unspecified_open "map: 'open' start { cell { x: 0 y: 0 } } goal { cell { x: 7 y: 7 } }"
plan four_connected "map: 'weighted' ${ends} options { connectivity: CONNECTIVITY_FOUR cost_weight: 3 unknown_is_free: true }"
plan world_points "map: 'weighted' start { world { x: -2.3 y: 1.2 } } goal { world { x: 1.0 y: 4.0 } } options { goal_tolerance_m: 1.5 }"
plan world_off_map "map: 'weighted' start { world { x: 100 y: 1.2 } } goal { cell { x: 23 y: 19 } }"
plan radius_cells "map: 'open' start { cell { x: 0 y: 0 } } goal { cell { x: 7 y: 7 } } options { robot_radius_cells: 1.5 simplify: true }"
plan radius_m "map: 'weighted' ${ends} options { robot_radius_m: 0.3 goal_tolerance_cells: 4 }"
plan via "map: 'weighted' planner: PLANNER_DIJKSTRA ${ends} via { cell { x: 12 y: 10 } } via { cell { x: 5 y: 15 } } allow_partial: true options { simplify: true }"
plan via_blocked "map: 'weighted' ${ends} via { cell { x: 30 y: 3 } }"
plan cost_to_go "map: 'open' planner: PLANNER_SPM start { cell { x: 1 y: 2 } } goal { cell { x: 6 y: 5 } } options { return_cost_to_go: true }"
plan expansions "map: 'weighted' planner: PLANNER_THETA_STAR ${ends} options { return_expansions: true max_expansions: 50 }"
plan lookahead "map: 'weighted' planner: PLANNER_RTAA_STAR ${ends} options { lookahead: 7 heuristic_weight: 2.5 }"
plan potential "map: 'open' planner: PLANNER_POTENTIAL_FIELD start { cell { x: 0 y: 0 } } goal { cell { x: 7 y: 7 } } options { potential_field { attractive: ATTRACTIVE_POTENTIAL_CONIC attractive_gain: 2 switch_distance: 3 repulsive_gain: 4 influence_distance: 2 step_size: 0.5 max_steps: 100 } }"
plan bad_options "map: 'weighted' ${ends} options { heuristic_weight: 0.5 max_expansions: -1 lookahead: -3 }"
plan unknown_planner "map: 'weighted' planner: 99 ${ends}"
plan missing_map "map: 'nope' ${ends}"

update() { seed "update_$1" 1 UpdateMapRequest "$2"; }
update cells "name: 'weighted' changes { cell { x: 1 y: 1 } cost: 254 } changes { cell { x: 2 y: 3 } cost: 0 }"
update rect "name: 'open' changes { rect { x_min: 1 y_min: 2 x_max: 6 y_max: 3 } cost: 100 } expected_version: 1"
update wrong_version "name: 'open' changes { cell { x: 1 y: 1 } cost: 1 } expected_version: 7"
update off_map "name: 'open' changes { rect { x_min: -1 y_min: 0 x_max: 9 y_max: 0 } cost: 3 }"
update bad_cost "name: 'open' changes { cell { x: 1 y: 1 } cost: 256 }"
update no_target "name: 'open' changes { cost: 5 }"
update whole_map "name: 'weighted' changes { rect { x_min: 0 y_min: 0 x_max: 23 y_max: 19 } cost: 7 } changes { cell { x: 0 y: 0 } cost: 255 }"

create() { seed "create_$1" 2 CreateMapRequest "$2"; }
create raw "name: 'raw' raw { width: 3 height: 2 cells: '\\000\\376\\377\\001\\000\\375' } resolution: 0.5 origin { x: 1 y: 2 yaw: 0.1 }"
create raw_wrong_length "name: 'raw' raw { width: 3 height: 3 cells: '\\000' }"
create raw_too_big "name: 'raw' raw { width: 65536 height: 65536 }"
create movingai "name: 'mai' movingai_text: 'type octile\\nheight 2\\nwidth 3\\nmap\\n.@.\\nG.T\\n'"
create ros "name: 'ros' ros_map { yaml: 'image: x.pgm\\nresolution: 0.05\\norigin: [0, 0, 0]\\nmode: scale\\n' image: 'P2\\n2 2\\n255\\n0 100\\n200 255\\n' }"
create map_dir "name: 'dir' map_dir_file: 'small.map' resolution: 2"
create map_dir_sub "name: 'dir' map_dir_file: 'sub/../sub/inner.map'"
create map_dir_ros "name: 'dir' map_dir_file: 'ros.yaml'"
create map_dir_escape "name: 'dir' map_dir_file: '../outside.map'"
create map_dir_symlink "name: 'dir' map_dir_file: 'escape.map'"
create map_dir_yaml_escape "name: 'dir' map_dir_file: 'escape.yaml'"
create replace "name: 'open' replace: true raw { width: 1 height: 1 cells: '\\000' }"
create exists "name: 'open' raw { width: 1 height: 1 cells: '\\000' }"
create bad_name "name: '../x' raw { width: 1 height: 1 cells: '\\000' }"
ls "$out" | grep -c '^seed_'
