#!/usr/bin/python3
"""`pip install ./client/python` works offline against Debian's grpcio and
protobuf: pip (Debian's, --no-build-isolation so nothing is downloaded;
--target because Debian's pip refuses system installs, PEP 668) builds the
package from a copy of client/python, its build step generating the stubs,
and the installed package -- alone on sys.path, not the CMake build's copy --
talks to a real pathd.

Run by ctest with PATHD_BIN set to the daemon; by hand:
    PATHD_BIN=build/server/pathd tests/client/pip_install_test.py
"""

import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import unittest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]

# Runs in a fresh interpreter whose sys.path holds the installed package.
PROBE = r"""
import os, pathlib, sys
sys.path.insert(0, sys.argv[2])  # the test launcher, not the package
from pathd_process import PathdProcess
import pathd_client
from pathd.v1 import planner_service_pb2
target = pathlib.Path(sys.argv[1]).resolve()
for module in (pathd_client, planner_service_pb2):
    assert pathlib.Path(module.__file__).resolve().is_relative_to(target), module.__file__
daemon = PathdProcess(os.environ["PATHD_BIN"], ["--map_dir=maps"])
try:
    with pathd_client.PathdClient(daemon.address) as client:
        names = [m.name for m in client.list_maps()]
        plan = client.plan("arena2", (100, 41), (101, 120), planner="astar")
        print("maps:", " ".join(names))
        print("plan found:", plan.found, "cost:", round(plan.cost, 2))
        print("health:", client.health())
finally:
    daemon.stop()
"""


class PipInstallTest(unittest.TestCase):

    def test_pip_install_target_then_call_a_real_pathd(self):
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            # A copy, so the in-tree build's build/ and egg-info stay out of
            # the source folder; the protos come from the tree.
            source = tmp / "python"
            shutil.copytree(SOURCE_DIR / "client" / "python", source,
                            ignore=shutil.ignore_patterns("build", "*.egg-info", "__pycache__"))
            env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
            env["PATHD_PROTO_DIR"] = str(SOURCE_DIR / "proto")
            env["PIP_NO_INDEX"] = "1"  # offline: nothing may be fetched
            target = tmp / "site"
            install = subprocess.run(
                ["/usr/bin/python3", "-m", "pip", "install", "--quiet", "--no-deps",
                 "--no-build-isolation", "--target", str(target), str(source)],
                capture_output=True, text=True, env=env, timeout=300)
            self.assertEqual(install.returncode, 0, install.stdout + install.stderr)
            for generated in ("common_pb2.py", "map_service_pb2_grpc.py",
                              "planner_service_pb2.pyi", "planner_service_pb2_grpc.py"):
                self.assertTrue((target / "pathd" / "v1" / generated).is_file(), generated)
            self.assertTrue((target / "pathd_client" / "py.typed").is_file())

            env["PYTHONPATH"] = str(target)
            run = subprocess.run(
                ["/usr/bin/python3", "-c", PROBE, str(target),
                 str(SOURCE_DIR / "tests" / "testing")],
                capture_output=True, text=True, env=env, cwd=SOURCE_DIR, timeout=120)
            self.assertEqual(run.returncode, 0, run.stdout + run.stderr)
            self.assertIn("arena2", run.stdout.split("\n")[0].split())
            self.assertIn("plan found: True", run.stdout)
            self.assertIn("health: SERVING", run.stdout)


if __name__ == "__main__":
    if "PATHD_BIN" not in os.environ:
        os.environ["PATHD_BIN"] = str(SOURCE_DIR / "build" / "server" / "pathd")
    unittest.main(verbosity=2)
