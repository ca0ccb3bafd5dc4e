#!/usr/bin/python3
"""The installed C++ client package: `cmake --install BUILD --prefix P
--component dev`, then examples/cpp_client -- a project outside the tree
that knows only find_package(pathd) -- configured and built against P, and
run against a real pathd serving maps/.

Run by ctest with PATHD_BIN, PATHD_BUILD_DIR (the build directory to
install from) and PATHD_WORK_DIR (a fixed directory, so ccache recognises
the consumer's compile on the next run; emptied first); by hand:
    PATHD_BIN=build/server/pathd PATHD_BUILD_DIR=build \\
        PATHD_WORK_DIR=/tmp/cpp_client tests/client/cpp_client_package_test.py
"""

import os
import pathlib
import shutil
import subprocess
import sys
import unittest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(SOURCE_DIR / "tests" / "testing"))
from pathd_process import PathdProcess  # pylint: disable=wrong-import-position


def run(*command, **kwargs):
    return subprocess.run([str(c) for c in command], capture_output=True, text=True,
                          timeout=600, **kwargs)


class CppClientPackageTest(unittest.TestCase):

    def test_find_package_consumer_builds_and_lists_maps(self):
        build = pathlib.Path(os.environ.get("PATHD_BUILD_DIR", SOURCE_DIR / "build"))
        work = pathlib.Path(os.environ.get("PATHD_WORK_DIR", build / "cpp_client_package"))
        shutil.rmtree(work, ignore_errors=True)
        prefix, consumer = work / "prefix", work / "build"

        install = run("cmake", "--install", build, "--prefix", prefix, "--component", "dev")
        self.assertEqual(install.returncode, 0, install.stdout + install.stderr)
        for path in ("include/pathd/client/client.h",
                     "include/pathd/pathd/v1/planner_service.grpc.pb.h",
                     "include/pathd/grpc/health/v1/health.grpc.pb.h",
                     "lib/cmake/pathd/pathdConfig.cmake", "lib/libpathd_client.a",
                     "lib/libpathd_proto.a", "share/pathd/proto/pathd/v1/common.proto"):
            self.assertTrue((prefix / path).is_file(), path)
        # Minimal and honest: nothing of the daemon or of pathd::core.
        self.assertFalse((prefix / "bin").exists())
        self.assertFalse(any(prefix.glob("lib/*core*")))
        self.assertFalse((prefix / "include/pathd/core").exists())

        configure = ["cmake", "-S", SOURCE_DIR / "examples" / "cpp_client", "-B", consumer,
                     "-G", "Ninja", "-DCMAKE_BUILD_TYPE=Release",
                     f"-DCMAKE_PREFIX_PATH={prefix}"]
        ccache = shutil.which("ccache")
        if ccache:
            configure.append(f"-DCMAKE_CXX_COMPILER_LAUNCHER={ccache}")
        configured = run(*configure)
        self.assertEqual(configured.returncode, 0, configured.stdout + configured.stderr)
        built = run("cmake", "--build", consumer)
        self.assertEqual(built.returncode, 0, built.stdout + built.stderr)
        # The consumer's compile saw the installed headers, not the tree's.
        commands = (consumer / "build.ninja").read_text()
        self.assertIn(f"-isystem {prefix}/include/pathd", commands)
        self.assertNotIn(str(SOURCE_DIR / "client"), commands)

        daemon = PathdProcess(os.environ.get("PATHD_BIN", str(build / "server" / "pathd")),
                              ["--map_dir=maps"])
        try:
            listed = run(consumer / "list_maps", daemon.address)
        finally:
            daemon.stop()
        self.assertEqual(listed.returncode, 0, listed.stdout + listed.stderr)
        lines = listed.stdout.splitlines()
        self.assertEqual(lines[0], f"5 map(s) on {daemon.address}")
        self.assertEqual([line.split()[0] for line in lines[1:6]],
                         ["arena2", "depot", "dstar_example", "warehouse", "wavefront16"])
        self.assertIn("arena2 281x209 resolution 1 version 1", lines)
        self.assertRegex(lines[6], r"^plan on arena2: found yes, \d+ cells, cost [\d.]+$")


if __name__ == "__main__":
    unittest.main(verbosity=2)
