#!/usr/bin/env python3
"""Compiles core/, server/ and client/ with clang's -Wthread-safety -Werror.

Syntax-only (no code generation, no linking): every translation unit of those
folders in BUILD_DIR's compile database is re-run through clang++ with
-fsyntax-only, so Abseil's lock annotations (ABSL_GUARDED_BY,
ABSL_EXCLUSIVE_LOCKS_REQUIRED, ...) are checked; gcc ignores them. Any
warning fails the check. The build directory only has to be configured and
have its protoc outputs generated (`make check-thread-safety` does both).

  scripts/check_thread_safety.py [BUILD_DIR] [--jobs N] [--clang clang++]
                                 [--only PATH ...]
"""

import argparse
import concurrent.futures
import json
import os
import shlex
import shutil
import subprocess
import sys
import time

CHECKED_FOLDERS = ("core", "server", "client")
# Flags of the gcc build that do not carry over to a syntax-only clang run:
# output, dependency files, and the build's own warning set (this check is
# about -Wthread-safety, with -Werror so any warning clang reports fails it).
DROP_WITH_VALUE = {"-o", "-MF", "-MT", "-MQ"}
DROP = {"-c", "-MD", "-MMD"}


def clang_command(entry, clang):
    args = entry.get("arguments") or shlex.split(entry["command"])
    # Skip a launcher (ccache) and the compiler itself.
    if os.path.basename(args[0]) in ("ccache", "sccache"):
        args = args[1:]
    args = args[1:]
    out = [clang]
    skip = False
    for arg in args:
        if skip:
            skip = False
            continue
        if arg in DROP_WITH_VALUE:
            skip = True
            continue
        if arg in DROP or arg.startswith("-W") or arg == "-w":
            continue
        if os.path.abspath(os.path.join(entry["directory"], arg)) == entry["file"]:
            continue
        out.append(arg)
    return out + ["-fsyntax-only", "-Wthread-safety", "-Werror", entry["file"]]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("build_dir", nargs="?", default="build")
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    parser.add_argument("--clang", default="clang++")
    parser.add_argument("--only", nargs="+", default=[], metavar="PATH",
                        help="check only these files or folders (relative to the source root)")
    opts = parser.parse_args()

    if shutil.which(opts.clang) is None:
        sys.exit(f"check_thread_safety: {opts.clang} not found "
                 "(scripts/setup.sh test installs clang)")
    source_root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    database = os.path.join(opts.build_dir, "compile_commands.json")
    try:
        with open(database) as f:
            entries = json.load(f)
    except OSError as e:
        sys.exit(f"check_thread_safety: cannot read {database}: {e.strerror} "
                 "(configure the build directory first)")

    roots = tuple(os.path.join(source_root, d) + os.sep for d in CHECKED_FOLDERS)
    only = tuple(os.path.join(source_root, p) for p in opts.only)
    seen = set()
    units = []
    for entry in entries:
        path = os.path.abspath(os.path.join(entry["directory"], entry["file"]))
        if not path.startswith(roots) or path in seen:
            continue
        if only and not any(path == p or path.startswith(p.rstrip(os.sep) + os.sep)
                            for p in only):
            continue
        seen.add(path)
        entry = dict(entry, file=path)
        units.append((path, entry["directory"], clang_command(entry, opts.clang)))
    if not units:
        sys.exit(f"check_thread_safety: no core/, server/ or client/ sources to check in {database}")

    def run(unit):
        path, directory, cmd = unit
        proc = subprocess.run(cmd, cwd=directory, capture_output=True, text=True)
        return path, proc.returncode, proc.stderr

    start = time.monotonic()
    failed = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=opts.jobs) as pool:
        for path, code, stderr in pool.map(run, sorted(units)):
            if code != 0 or stderr.strip():
                failed.append(os.path.relpath(path, source_root))
                sys.stderr.write(stderr)
    elapsed = time.monotonic() - start
    if failed:
        print(f"check_thread_safety: {len(failed)} of {len(units)} files have "
              f"warnings: {' '.join(failed)}", file=sys.stderr)
        return 1
    print(f"check_thread_safety: {len(units)} files of {', '.join(CHECKED_FOLDERS)} "
          f"clean under clang -Wthread-safety -Werror ({elapsed:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
