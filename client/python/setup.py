"""Build step of the pathd-client package (pyproject.toml holds the rest):
generates the pathd.v1 gRPC stubs into the build tree with protoc and
grpc_python_plugin, the tools the CMake build uses (client/python/
CMakeLists.txt), so the wheel holds pathd_client and pathd/v1/*_pb2*.py.

The .proto files are found in $PATHD_PROTO_DIR, else ./proto (an sdist
carries them there), else ../../proto (this folder inside the pathd tree).
"""

import os
import pathlib
import shutil
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py
from setuptools.command.sdist import sdist

HERE = pathlib.Path(__file__).resolve().parent
PROTOS = ["pathd/v1/common.proto", "pathd/v1/map_service.proto",
          "pathd/v1/planner_service.proto"]


def proto_root() -> pathlib.Path:
    candidates = [os.environ.get("PATHD_PROTO_DIR"), HERE / "proto", HERE.parent.parent / "proto"]
    for candidate in candidates:
        if candidate and (pathlib.Path(candidate) / PROTOS[0]).is_file():
            return pathlib.Path(candidate)
    raise SystemExit("pathd-client: no proto/pathd/v1 found (looked in $PATHD_PROTO_DIR, "
                     f"{HERE / 'proto'}, {HERE.parent.parent / 'proto'})")


def tool(name: str, package: str) -> str:
    path = shutil.which(name)
    if not path:
        raise SystemExit(f"pathd-client: building needs {name} (Debian: apt install {package}; "
                         "scripts/setup.sh serve installs it)")
    return path


class BuildPyWithStubs(build_py):
    """build_py, then protoc's Python messages (+ .pyi stubs) and
    grpc_python_plugin's service stubs into the build tree."""

    def run(self):
        super().run()
        root = proto_root()
        out = pathlib.Path(self.build_lib)
        (out / "pathd" / "v1").mkdir(parents=True, exist_ok=True)
        protoc = tool("protoc", "protobuf-compiler")
        plugin = tool("grpc_python_plugin", "protobuf-compiler-grpc")
        subprocess.run([protoc, f"-I{root}", f"--python_out={out}", f"--pyi_out={out}",
                        f"--grpc_python_out={out}",
                        f"--plugin=protoc-gen-grpc_python={plugin}",
                        *[str(root / p) for p in PROTOS]], check=True)
        # Regular packages, so no other `pathd` directory on sys.path merges in.
        for package in ("pathd", "pathd/v1"):
            (out / package / "__init__.py").touch()


class SdistWithProtos(sdist):
    """An sdist that builds anywhere: the .proto files go into ./proto."""

    def make_release_tree(self, base_dir, files):
        super().make_release_tree(base_dir, files)
        root = proto_root()
        for proto in PROTOS:
            target = pathlib.Path(base_dir) / "proto" / proto
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(root / proto, target)


setup(cmdclass={"build_py": BuildPyWithStubs, "sdist": SdistWithProtos})
