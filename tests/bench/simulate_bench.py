#!/usr/bin/env python3
"""`pathctl simulate` figures for docs/performance.md ("Local planners
through the server"): the 50 random scenarios of tests/e2e/simulate_test.py
and the shipped ones, against one real pathd, with local planner options
set for every robot, printing arrivals, contacts and the smallest gap
between two robots. A measurement, not a test: nothing is asserted.

    tests/bench/simulate_bench.py [--options "detour_range: 0"] \\
        [--planners orca,dwa,firas] [--runs 3] [--random] [--shipped]

Run from the repository root after building (build/server/pathd,
build/client/pathctl).
"""

import argparse
import os
import shutil
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "e2e"))
sys.path.insert(0, os.path.join(ROOT, "tests", "testing"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pathd", default=os.path.join(ROOT, "build/server/pathd"))
    parser.add_argument("--pathctl", default=os.path.join(ROOT, "build/client/pathctl"))
    parser.add_argument("--options", default="",
                        help="local planner options, a flow mapping body")
    parser.add_argument("--planners", default="orca")
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--random", action="store_true", help="the 50 random scenarios")
    parser.add_argument("--shipped", action="store_true", help="corridor2, circle8 and warehouse20")
    args = parser.parse_args()
    if not (args.random or args.shipped):
        args.random = args.shipped = True
    # simulate_test reads its binaries and options at import.
    sys.argv = [sys.argv[0], args.pathd, args.pathctl]
    os.environ["PATHD_SIM_OPTIONS"] = args.options
    import simulate_test as st  # pylint: disable=import-outside-toplevel

    daemon = st.Daemon()
    work = tempfile.TemporaryDirectory()
    try:
        for planner in args.planners.split(","):
            for run in range(args.runs):
                if args.random:
                    random_set(st, daemon, work.name, planner, run)
                if args.shipped:
                    for name in ("corridor2", "circle8", "warehouse20"):
                        shipped(st, daemon, work.name, name, planner, args.options, run)
    finally:
        daemon.stop()
        work.cleanup()


def summarise(summary):
    arrived = [r for r in summary["robots"] if r["end"] == "arrived"]
    times = [r["arrival_s"] for r in arrived]
    ratios = [r["driven_m"] / r["path_m"] for r in arrived if r["path_m"]]
    return {
        "arrived": len(arrived),
        "robots": len(summary["robots"]),
        "time_mean": sum(times) / len(times) if times else None,
        "time_max": max(times) if times else None,
        "driven_over_path": sum(ratios) / len(ratios) if ratios else None,
        "min_gap": summary["min_separation_m"],
        "contacts": summary["collisions"],
        "beyond_limits": summary["limit_violations"],
    }


def fmt(value):
    return "-" if value is None else f"{value:.3f}"


def random_set(st, daemon, work, planner, run):
    import random  # pylint: disable=import-outside-toplevel
    rng = random.Random(20261202)
    arrived = total = contacts = 0
    gaps = []
    for case in range(50):
        scenario, grid, n = st.random_scenario(rng, case)
        scenario = scenario.replace("local_planner: orca", f"local_planner: {planner}")
        path = os.path.join(work, f"random{case}.yaml")
        with open(path, "w") as f:
            f.write(scenario)
        with open(os.path.join(work, f"random{case}.map"), "w") as f:
            f.write(st.grid_text(grid))
        _, summary, _, stderr = st.simulate(daemon, path, work)
        if summary is None:
            print(f"random{case}: no summary: {stderr.strip()[:200]}")
            continue
        s = summarise(summary)
        arrived += s["arrived"]
        total += n
        contacts += s["contacts"]
        if s["min_gap"] is not None:
            gaps.append(s["min_gap"])
    print(f"random {planner} run {run}: {arrived}/{total} arrived "
          f"({100.0 * arrived / max(total, 1):.1f}%), {contacts} contacts, "
          f"{sum(1 for g in gaps if g < 0.01)} scenarios with a gap under 1 cm, "
          f"smallest gap {fmt(min(gaps) if gaps else None)} m", flush=True)


def shipped(st, daemon, work, name, planner, options, run):
    with open(os.path.join(st.EXAMPLES, f"{name}.yaml")) as f:
        text = f.read().replace("local_planner: orca", f"local_planner: {planner}")
    if options:
        text = text.replace("\nrobots:", f"\n  options: {{{options}}}\nrobots:", 1)
    for extra in ("room.map", "corridor.map"):
        shutil.copy(os.path.join(st.EXAMPLES, extra), work)
    path = os.path.join(work, f"{name}_{planner}.yaml")
    with open(path, "w") as f:
        f.write(text)
    _, summary, _, stderr = st.simulate(daemon, path, work)
    if summary is None:
        print(f"{name} {planner}: no summary: {stderr.strip()[:200]}")
        return
    s = summarise(summary)
    print(f"{name} {planner} run {run}: {s['arrived']}/{s['robots']} arrived, time to goal "
          f"mean {fmt(s['time_mean'])} max {fmt(s['time_max'])} s, driven/path "
          f"{fmt(s['driven_over_path'])}, min gap {fmt(s['min_gap'])} m, "
          f"{s['contacts']} contacts, {s['beyond_limits']} beyond limits", flush=True)


if __name__ == "__main__":
    main()
