#!/usr/bin/python3
"""The Debian package of `make deb` (cmake/packaging.cmake): its files,
control data and systemd unit; installed by dpkg into a temporary root with
its own package database (`dpkg --root`, no root user needed; the
dependencies are the host's, so dpkg is told not to check them there), the
conffile kept through a reinstall and a remove; and the installed daemon
run: with no --map_dir it serves the bundled maps, with the installed config
too, and an explicit --map_dir="" serves none; pathctl from the package
lists them.

The package is built here by CPack from the build directory, the daemon
component only and without dpkg-shlibdeps (12 s of the 13 s cpack takes);
with PATHD_DEB naming a .deb (`make deb-check` passes the one `make deb`
built) that package is checked instead, its Depends line included.

Run by ctest with PATHD_BUILD_DIR; by hand:
    PATHD_BUILD_DIR=build tests/e2e/deb_package_test.py
"""

import os
import pathlib
import re
import subprocess
import sys
import tempfile
import unittest

SOURCE_DIR = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(SOURCE_DIR / "tests" / "testing"))
from pathd_process import PathdProcess  # pylint: disable=wrong-import-position

BUNDLED = ["arena2", "depot", "dstar_example", "warehouse", "wavefront16"]


def run(*command, **kwargs):
    result = subprocess.run([str(c) for c in command], capture_output=True, text=True,
                            timeout=300, **kwargs)
    if result.returncode != 0:
        raise AssertionError(f"{command} exited {result.returncode}:\n"
                             f"{result.stdout}{result.stderr}")
    return result.stdout


class DebPackageTest(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        tmp = pathlib.Path(cls.tmp.name)
        cls.real = "PATHD_DEB" in os.environ
        if cls.real:
            cls.deb = pathlib.Path(os.environ["PATHD_DEB"])
        else:
            build = pathlib.Path(os.environ.get("PATHD_BUILD_DIR", SOURCE_DIR / "build"))
            run("cpack", "-G", "DEB", "--config", build / "CPackConfig.cmake", "-B", tmp / "out",
                "-D", "CPACK_COMPONENTS_ALL=daemon", "-D", "CPACK_DEBIAN_PACKAGE_SHLIBDEPS=OFF")
            cls.deb = next((tmp / "out").glob("pathd_*.deb"))
        cls.root = tmp / "root"
        for folder in ("var/lib/dpkg/info", "var/lib/dpkg/updates"):
            (cls.root / folder).mkdir(parents=True)
        (cls.root / "var/lib/dpkg/status").touch()
        cls.dpkg("-i", cls.deb)

    @classmethod
    def dpkg(cls, *args):
        return run("dpkg", f"--root={cls.root}", "--force-not-root", "--force-depends",
                   "--log=/dev/null", *args)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def test_contents_and_control(self):
        listing = run("dpkg-deb", "--contents", self.deb)
        files = {line.split()[-1] for line in listing.splitlines() if not line.endswith("/")}
        expected = {"./usr/bin/pathd", "./usr/bin/pathctl", "./etc/pathd/pathd.yaml",
                    "./usr/lib/systemd/system/pathd.service",
                    "./usr/share/pathd/maps/arena2.map", "./usr/share/pathd/maps/depot.yaml",
                    "./usr/share/pathd/maps/depot.pgm", "./usr/share/pathd/maps/warehouse.yaml",
                    "./usr/share/pathd/maps/warehouse.pgm",
                    "./usr/share/pathd/maps/dstar_example.map",
                    "./usr/share/pathd/maps/wavefront16.map"}
        self.assertEqual(files, expected)
        self.assertIn("-rwxr-xr-x root/root", next(line for line in listing.splitlines()
                                                    if line.endswith("./usr/bin/pathd")))
        control = run("dpkg-deb", "--field", self.deb, "Package", "Version", "Architecture")
        self.assertEqual(control.split(), ["Package:", "pathd", "Version:", "0.1.0",
                                           "Architecture:", "amd64"])
        with tempfile.TemporaryDirectory() as meta:
            run("dpkg-deb", "--control", self.deb, meta)
            conffiles = pathlib.Path(meta, "conffiles").read_text().split()
        self.assertEqual(conffiles, ["/etc/pathd/pathd.yaml"])
        if self.real:
            depends = run("dpkg-deb", "--field", self.deb, "Depends")
            for library in ("libgrpc++1", "libprotobuf", "libabsl", "libyaml-cpp", "libc6"):
                self.assertIn(library, depends)
            # Every dependency names a package this (Debian) host has
            # installed, or one an installed package provides
            # (libspdlog1.10 provides libspdlog1.10-fmt9).
            present = set()
            for line in run("dpkg-query", "-W",
                            "-f=${db:Status-Abbrev}|${Package}|${Provides}\n").splitlines():
                status, package, provides = line.split("|")
                if status.startswith("ii"):
                    present.add(package)
                    present.update(p.split()[0] for p in provides.split(",") if p.strip())
            for entry in depends.split(","):
                self.assertIn(entry.split()[0], present, entry)

    def test_dpkg_installed_it_and_keeps_the_conffile(self):
        self.assertIn("Status: install ok installed", self.dpkg("-s", "pathd"))
        self.assertIn("/usr/bin/pathd", self.dpkg("-L", "pathd").split())
        config = self.root / "etc/pathd/pathd.yaml"
        original = config.read_text()
        try:
            config.write_text(original + "# edited by the operator\n")
            self.dpkg("-i", self.deb)  # a reinstall keeps the edit
            self.assertTrue(config.read_text().endswith("# edited by the operator\n"))
            self.dpkg("-r", "pathd")  # remove (not purge) keeps it too
            self.assertFalse((self.root / "usr/bin/pathd").exists())
            self.assertTrue(config.exists())
        finally:
            config.write_text(original)
            self.dpkg("-i", self.deb)
        self.assertTrue((self.root / "usr/bin/pathd").exists())

    def test_systemd_unit(self):
        unit = (self.root / "usr/lib/systemd/system/pathd.service").read_text()
        self.assertIn("\nExecStart=/usr/bin/pathd --config=/etc/pathd/pathd.yaml "
                      "--data_dir=${STATE_DIRECTORY}\n", unit)
        for setting in ("DynamicUser=yes", "StateDirectory=pathd", "NoNewPrivileges=yes",
                        "ProtectSystem=strict", "ProtectHome=yes", "PrivateTmp=yes",
                        "RestrictAddressFamilies=AF_INET AF_INET6 AF_UNIX",
                        "SystemCallFilter=@system-service", "#MemoryMax="):
            self.assertRegex(unit, rf"(?m)^{re.escape(setting)}", setting)
        self.assertIn("WantedBy=multi-user.target", unit)

    def serve(self, *flags):
        """The unpacked pathd on a free port (nothing else), with `flags`;
        the map names pathctl from the package lists."""
        daemon = PathdProcess(str(self.root / "usr/bin/pathd"), list(flags))
        try:
            listing = run(self.root / "usr/bin/pathctl", f"--server={daemon.address}",
                          "maps", "list")
        finally:
            daemon.stop()
        return [line.split()[0] for line in listing.splitlines()[1:]]

    def test_pathd_with_no_flags_serves_the_bundled_maps(self):
        self.assertEqual(self.serve(), BUNDLED)
        # The installed config leaves map_dir unset: the same maps.
        self.assertEqual(self.serve(f"--config={self.root}/etc/pathd/pathd.yaml"), BUNDLED)
        # An explicit empty --map_dir still means none.
        self.assertEqual(self.serve("--map_dir="), [])


if __name__ == "__main__":
    unittest.main(verbosity=2)
