#!/usr/bin/python3
"""A robot driving through a pathd Navigate session.

The robot creates its map, opens a session from its start to its goal and
drives along the session's path one pose per step. Two things get in its
way:
  * an operator (a second client, on its own channel) closes the door the
    robot is heading for with UpdateMap: the server pushes the repaired path
    unasked (MAP_CHANGED) and the robot follows that one, through the other
    door;
  * there an obstacle the map does not know about yet comes within sensor
    range: the robot reports it as an observation, and the answer is the
    path around it.
Every step is checked against the world (one move, no obstacle), so a stale
path shows up as a collision.

Run against `make serve` (see docs/python.md):
    PYTHONPATH=build/client/python python3 client/python/examples/robot_loop.py
Exit status 0 when the robot reaches its goal, 1 otherwise.
"""

import argparse
import os
import sys

try:
    from pathd_client import (LETHAL, Cell, NavigateUpdate, PathdClient, PathdError,
                              SetCell)
except ModuleNotFoundError as missing:
    sys.exit(f"{missing}: build pathd, then put build/client/python on PYTHONPATH "
             "and run this with Debian's /usr/bin/python3 (docs/python.md)")

# The map as the robot knows it at the start: a wall with a door at the top
# (row 0) and a wide one at the bottom (rows 5-6).
ROWS = [
    "....................",
    "..........@.........",
    "..........@.........",
    "..........@.........",
    "..........@.........",
    "....................",
    "....................",
]
START = Cell(2, 2)
GOAL = Cell(17, 2)
# In the world but not on the map: the robot finds it with its sensor.
HIDDEN_OBSTACLE = Cell(10, 5)
SENSOR_RANGE = 2  # cells (Chebyshev distance)
TOP_DOOR = Cell(10, 0)
OPERATOR_STEP = 2  # after this many steps the operator closes TOP_DOOR


def describe(path: list[Cell]) -> str:
    cells = " ".join(f"({c.x},{c.y})" for c in path[:6])
    return f"{len(path) - 1} steps: {cells}{' ...' if len(path) > 6 else ''}"


def show(what: str, update: NavigateUpdate) -> None:
    plan = update.plan
    if plan.found:
        print(f"  {what}: path of {describe(plan.path)} (cost {plan.cost:.2f}, "
              f"map version {plan.map_version})")
    else:
        print(f"  {what}: no path ({plan.outcome}: {plan.reason})")


def drive(client: PathdClient, operator: PathdClient, map_name: str,
          max_steps: int, push_timeout: float) -> bool:
    blocked_by_operator: set[Cell] = set()
    hidden = {HIDDEN_OBSTACLE}
    with client.navigate(map_name, START, GOAL) as nav:
        print(f"session {nav.session_id} open on '{map_name}', "
              f"{START.x},{START.y} -> {GOAL.x},{GOAL.y}")
        show("opened", nav.opened)
        position = START
        for step in range(1, max_steps + 1):
            for push in nav.poll_pushes():
                show("pushed (unasked)", push)
            # The sensor: obstacles within range that the map lacks.
            seen = [c for c in hidden
                    if max(abs(c.x - position.x), abs(c.y - position.y)) <= SENSOR_RANGE]
            if seen:
                hidden.difference_update(seen)
                print(f"step {step}: sensor sees an obstacle at "
                      + ", ".join(f"({c.x},{c.y})" for c in seen))
                show("observed", nav.observe([SetCell(c.x, c.y, LETHAL) for c in seen]))
            path = nav.path
            if not nav.latest.plan.found or len(path) < 2:
                print(f"step {step}: no way on from ({position.x},{position.y})")
                return False
            target = path[1]
            if max(abs(target.x - position.x), abs(target.y - position.y)) != 1:
                print(f"step {step}: ({target.x},{target.y}) is not one move away")
                return False
            if target in blocked_by_operator or target == HIDDEN_OBSTACLE:
                print(f"step {step}: collision at ({target.x},{target.y})")
                return False
            position = target
            answer = nav.move(position)
            print(f"step {step}: at ({position.x},{position.y})")
            if position == GOAL:
                print(f"reached the goal in {step} steps, "
                      f"{len(nav.pushes)} pushed path(s) received")
                return True
            if step == OPERATOR_STEP:
                on_path = TOP_DOOR in answer.plan.path
                blocked_by_operator.add(TOP_DOOR)
                result = operator.update_map(
                    map_name, [SetCell(TOP_DOOR.x, TOP_DOOR.y, LETHAL)])
                print(f"operator: closes the door at ({TOP_DOOR.x},{TOP_DOOR.y}), "
                      f"{'on' if on_path else 'not on'} the robot's path "
                      f"(map version {result.version})")
                if not on_path:
                    continue
                # The robot sends nothing until the push arrives, so the
                # server has to push: the change is on the robot's path.
                push = nav.wait_push(push_timeout)
                if push is None:
                    print(f"no pushed path within {push_timeout:g} s")
                    return False
                show("pushed (unasked)", push)
        print(f"gave up after {max_steps} steps")
        return False


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--server", default=os.environ.get("PATHD_SERVER", "127.0.0.1:50051"),
                        help="pathd address (default: $PATHD_SERVER or 127.0.0.1:50051)")
    parser.add_argument("--map", default="robot_loop", help="map name to create (replaced)")
    parser.add_argument("--keep", action="store_true", help="keep the map afterwards")
    parser.add_argument("--timeout", type=float, default=10.0,
                        help="seconds per call and per wait for a pushed path")
    args = parser.parse_args()

    # The operator is another program in real life: its own channel.
    with PathdClient(args.server, timeout=args.timeout) as client, \
            PathdClient(args.server, timeout=args.timeout) as operator:
        try:
            info = client.create_map(args.map, ROWS, replace=True)
            print(f"map '{info.name}': {info.width}x{info.height}, version {info.version}")
            plan = client.plan(args.map, START, GOAL, planner="astar")
            print(f"A* plan: {describe(plan.path)} (cost {plan.cost:.2f})")
            reached = drive(client, operator, args.map, max_steps=100,
                            push_timeout=args.timeout)
            if not args.keep:
                client.delete_map(args.map)
        except PathdError as error:
            print(f"error: {error}", file=sys.stderr)
            return 1
    return 0 if reached else 1


if __name__ == "__main__":
    sys.exit(main())
