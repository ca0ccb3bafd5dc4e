#!/usr/bin/env python3
"""Crash test of pathd --data_dir: kill -9 during concurrent updates, restart,
and check every acknowledged update survived and nothing else is half there.

One client thread per map sends updates through the real `pathctl`, one at a
time: update k of a map fills a 4 x 4 rectangle with a cost derived from k
(every 10th update of map crash0 replaces the map with an empty one instead),
so the map after n updates is known exactly and has version n + 1. The daemon
is killed with SIGKILL at a random moment (fixed seed), each client's update
in flight then fails, and after the restart every map must hold exactly the
state after n updates with n = the acknowledged ones, or one more when an
update was in flight: it may be wholly applied, never partly.

Usage: crash_test.py PATHD PATHCTL [--kills N] [--seed S]
"""

import argparse
import base64
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import threading
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                "..", "testing"))
from pathd_process import PathdProcess  # pylint: disable=wrong-import-position

SIZE = 32
MAPS = 4
RECT = 4


def op_is_replace(map_index, k):
    return map_index == 0 and k % 10 == 0


def op_rect(k):
    """The rectangle and cost update k (1-based) writes."""
    x0 = (k * 7) % (SIZE - RECT)
    y0 = (k * 13) % (SIZE - RECT)
    return x0, y0, x0 + RECT - 1, y0 + RECT - 1, 1 + (k * 37) % 252


def expected_cells(map_index, n):
    """Row-major cost bytes of map `map_index` after its first n updates."""
    cells = bytearray(SIZE * SIZE)
    for k in range(1, n + 1):
        if op_is_replace(map_index, k):
            cells = bytearray(SIZE * SIZE)
            continue
        x0, y0, x1, y1, cost = op_rect(k)
        for y in range(y0, y1 + 1):
            for x in range(x0, x1 + 1):
                cells[y * SIZE + x] = cost
    return bytes(cells)


class Daemon:
    """pathd on --data_dir, through the tests' launcher; its log appended to
    log_path across restarts."""

    def __init__(self, pathd, data_dir, log_path):
        self.process = PathdProcess(
            pathd, ["--data_dir=" + data_dir, "--snapshot_log_bytes=4096",
                    "--snapshot_interval=0", "--threads=2", "--log_level=warn"],
            log_path=log_path)
        self.address = self.process.address

    def kill(self):
        self.process.kill()

    def stop(self):
        return self.process.stop()


def pathctl(binary, address, *args):
    return subprocess.run([binary, "--server", address, *args],
                          capture_output=True, text=True)


class MapClient:
    """The updates of one map: applied so far and the one in flight."""

    def __init__(self, index):
        self.index = index
        self.name = "crash%d" % index
        self.applied = 0  # updates known to be in the map
        self.in_flight = None  # k of an update whose answer never came
        self.error = None  # raised again by the main thread

    def run(self, *args):
        try:
            self.send_updates(*args)
        except Exception as e:  # pylint: disable=broad-except
            self.error = e

    def send_updates(self, binary, address, blank_file, stop, acked):
        while not stop.is_set():
            k = self.applied + 1
            if op_is_replace(self.index, k):
                result = pathctl(binary, address, "maps", "create", self.name,
                                 "--from", blank_file, "--replace")
            else:
                x0, y0, x1, y1, cost = op_rect(k)
                result = pathctl(binary, address, "maps", "rect", self.name,
                                 str(x0), str(y0), str(x1), str(y1), str(cost))
            if result.returncode != 0:
                self.in_flight = k
                return
            if not op_is_replace(self.index, k):
                version = int(result.stdout.split("version")[1].split()[0])
                if version != k + 1:
                    raise AssertionError("%s: update %d acknowledged as version %d" %
                                         (self.name, k, version))
            self.applied = k
            acked[0] += 1


def check_map(binary, address, client, counts):
    result = pathctl(binary, address, "--json", "maps", "get", client.name, "--cells")
    if result.returncode != 0:
        raise AssertionError("%s missing after restart: %s" % (client.name, result.stderr))
    answer = json.loads(result.stdout)
    n = int(answer["info"]["version"]) - 1
    cells = base64.b64decode(answer.get("cells", ""))
    low = client.applied
    high = client.applied + (1 if client.in_flight is not None else 0)
    if not low <= n <= high:
        raise AssertionError("%s: recovered after %d updates; acknowledged %d, in flight %s" %
                             (client.name, n, low, client.in_flight))
    if cells != expected_cells(client.index, n):
        raise AssertionError("%s: cells after %d updates differ from the expected map "
                             "(an update half applied?)" % (client.name, n))
    if client.in_flight is not None:
        counts["applied" if n == high else "absent"] += 1
    client.applied = n
    client.in_flight = None
    counts["checked_maps"] += 1


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("pathd")
    parser.add_argument("pathctl")
    parser.add_argument("--kills", type=int, default=24)
    parser.add_argument("--seed", type=int, default=20240607)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    started = time.monotonic()

    with tempfile.TemporaryDirectory(prefix="pathd_crash_") as work:
        data_dir = os.path.join(work, "data")
        log_path = os.path.join(work, "pathd.log")
        blank = os.path.join(work, "blank.map")
        with open(blank, "w") as f:
            f.write("type octile\nheight %d\nwidth %d\nmap\n" % (SIZE, SIZE))
            f.write(("." * SIZE + "\n") * SIZE)
        clients = [MapClient(i) for i in range(MAPS)]
        counts = {"applied": 0, "absent": 0, "checked_maps": 0}
        acked = [0]
        try:
            daemon = Daemon(args.pathd, data_dir, log_path)
            for c in clients:
                r = pathctl(args.pathctl, daemon.address, "maps", "create", c.name,
                            "--from", blank)
                if r.returncode != 0:
                    raise AssertionError("create %s: %s" % (c.name, r.stderr))
            for _ in range(args.kills):
                stop = threading.Event()
                threads = [threading.Thread(target=c.run,
                                            args=(args.pathctl, daemon.address, blank,
                                                  stop, acked))
                           for c in clients]
                for t in threads:
                    t.start()
                time.sleep(rng.uniform(0.1, 1.0))
                daemon.kill()
                stop.set()
                for t in threads:
                    t.join()
                for c in clients:
                    if c.error is not None:
                        raise c.error
                daemon = Daemon(args.pathd, data_dir, log_path)
                for c in clients:
                    check_map(args.pathctl, daemon.address, c, counts)
            # A clean stop and start keeps everything too.
            if daemon.stop() != 0:
                raise AssertionError("pathd did not exit 0 on SIGTERM")
            daemon = Daemon(args.pathd, data_dir, log_path)
            for c in clients:
                check_map(args.pathctl, daemon.address, c, counts)
            daemon.stop()
        except Exception:
            with open(log_path, "rb") as f:
                tail = f.read()[-4000:].decode(errors="replace")
            sys.stderr.write("pathd log (tail):\n%s\n" % tail)
            raise
        with open(log_path, "rb") as f:
            torn = f.read().decode(errors="replace").count("cutting the log there")

    print("crash test: %d kills, %d acknowledged updates checked (%d map checks), "
          "in-flight updates found applied: %d, absent: %d; torn final records cut: %d; "
          "%.1f s" % (args.kills, acked[0], counts["checked_maps"], counts["applied"],
                      counts["absent"], torn, time.monotonic() - started))


if __name__ == "__main__":
    main()
