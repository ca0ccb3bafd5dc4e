#!/usr/bin/env python3
"""path_bytes: what a plan's answer weighs with each PlanOptions.path_encoding.

Plans a few long paths on a running pathd (by default `make serve`'s
127.0.0.1:50051 with maps/ and, when given --map_dir maps, a 4096^2 map
tiled by tools/map_tile) once READABLE, once PACKED and once BOTH, checks
that the packed cells equal the readable ones, and prints the serialized
answer's bytes, the bytes of each path-carrying field group, and the Python
decoder's time. Figures, not assertions: docs/performance.md, "Packed
paths (issue 19)", records them with the commands.

  PYTHONPATH=build/client/python tests/bench/path_bytes.py [ADDRESS]
"""
import sys
import time

import grpc
from pathd.v1 import common_pb2
from pathd.v1 import planner_service_pb2 as pb
from pathd.v1 import planner_service_pb2_grpc as rpc

import pathd_client

# (map, start, goal, planner, simplify); maps the server does not hold are
# reported and skipped. Start and goal may move to free cells (snap_start,
# goal tolerance).
CASES = [
    ("arena2", (4, 98), (275, 206), "astar", False),
    ("depot", (20, 20), (380, 280), "astar", False),
    ("depot", (20, 20), (380, 280), "theta_star", False),
    ("berlin4096", (10, 10), (4000, 4000), "jps", False),
    ("berlin4096", (10, 10), (4000, 4000), "jps", True),
    ("berlin4096", (10, 10), (4000, 4000), "theta_star", False),
]


def main() -> int:
    address = sys.argv[1] if len(sys.argv) > 1 else "127.0.0.1:50051"
    channel = grpc.insecure_channel(
        address, options=[("grpc.max_receive_message_length", 1 << 30)])
    stub = rpc.PlannerServiceStub(channel)

    def plan(case, encoding):
        name, start, goal, planner, simplify = case
        request = pb.PlanRequest(
            map=name, start=common_pb2.Position(cell=common_pb2.Cell(x=start[0], y=start[1])),
            goal=common_pb2.Position(cell=common_pb2.Cell(x=goal[0], y=goal[1])),
            planner=pb.Planner.Value("PLANNER_" + planner.upper()),
            options=pb.PlanOptions(path_encoding=encoding, simplify=simplify,
                                   goal_tolerance_cells=60, snap_start=True,
                                   snap_start_max_cells=60))
        return stub.Plan(request, timeout=120)

    def field_bytes(answer, *fields):
        part = pb.PlanResponse()
        for field in fields:
            if field == "packed_path":
                part.packed_path = answer.packed_path
            else:
                getattr(part, field).MergeFrom(getattr(answer, field))
        return part.ByteSize()

    print(f"{'map':12} {'planner':10} {'simplify':8} {'cells':>6} {'readable B':>11} "
          f"{'packed B':>9} {'path+world_path B':>17} {'packed_path+frame B':>19} "
          f"{'poses+world_poses B':>19} {'py decode ms':>12}")
    for case in CASES:
        try:
            readable = plan(case, pb.PATH_ENCODING_READABLE)
        except grpc.RpcError as e:
            print(f"{case[0]}: {e.details()}")
            continue
        packed = plan(case, pb.PATH_ENCODING_PACKED)
        both = plan(case, pb.PATH_ENCODING_BOTH)
        t0 = time.perf_counter()
        cells = pathd_client.decode_packed_path(packed.packed_path)
        decode_s = time.perf_counter() - t0
        if [(c.x, c.y) for c in cells] != [(c.x, c.y) for c in readable.path]:
            print(f"{case[0]}: packed cells differ from the readable path")
            return 1
        print(f"{case[0]:12} {case[3]:10} {str(case[4]):8} {len(readable.path):6} "
              f"{readable.ByteSize():11} {packed.ByteSize():9} "
              f"{field_bytes(both, 'path', 'world_path'):17} "
              f"{field_bytes(both, 'packed_path', 'path_frame'):19} "
              f"{field_bytes(both, 'poses', 'world_poses'):19} {decode_s * 1e3:12.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
