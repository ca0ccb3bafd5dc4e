#!/usr/bin/env bash
# Installs the Debian packages pathd needs, as root or through sudo.
#   scripts/setup.sh [serve]  build and run pathd and pathctl (make serve,
#                             docker/Dockerfile)
#   scripts/setup.sh test     that, plus what the tests, benchmarks, sanitizer
#                             and fuzz builds and the thread-safety check need
#                             (make test, test-tsan, test-asan, fuzz,
#                             check-thread-safety)
# Idempotent: when every package of the set is already installed it does
# nothing (no apt-get update).
set -euo pipefail

SERVE_PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libabsl-dev libspdlog-dev libyaml-cpp-dev
  prometheus-cpp-dev libcurl4-openssl-dev
  # libcivetweb-dev: the HTTP/JSON API and viewer (server/http/); the same
  # civetweb prometheus-cpp serves /metrics with.
  libcivetweb-dev
  libpng-dev
  libisal-dev
  libcsv-dev
  # libssl-dev: pathd's token hashing and PEM checks; openssl: the tool that
  # makes the TLS certificates and auth tokens docs/security.md describes.
  openssl libssl-dev
  # libcgal-dev: the navigation mesh's constrained Delaunay triangulation
  # (core/geometry/navmesh.cc; header-only, brings GMP and MPFR).
  libcgal-dev
  # libompl-dev: Dubins and Reeds-Shepp curves for the kinematic planners
  # (core/kinematics); Eigen comes with it and serves their geometry.
  libompl-dev libeigen3-dev
)

TEST_PACKAGES=(
  libgtest-dev libgmock-dev libbenchmark-dev
  # The Python client and its tests (client/python, tests/client), the crash
  # test (tests/e2e/crash_test.py).
  python3 python3-grpcio python3-protobuf
  # The loopback scale-out test (tests/e2e/scaleout_test.cc) runs nginx as
  # the test's user with its own config; the package's system service is not
  # used (on a machine without a policy-rc.d, apt starts it on port 80).
  nginx
  # The viewer's browser test (tests/e2e/viewer_browser_test.py): headless
  # Chromium, driven over the DevTools protocol with python3-websocket.
  chromium python3-websocket
  # make fuzz: clang, its libFuzzer runtime, llvm-symbolizer for the reports;
  # make check-thread-safety: clang's -Wthread-safety.
  clang libclang-rt-14-dev llvm
)

case "${1:-serve}" in
  serve) PACKAGES=("${SERVE_PACKAGES[@]}") ;;
  test) PACKAGES=("${SERVE_PACKAGES[@]}" "${TEST_PACKAGES[@]}") ;;
  *)
    echo "usage: $0 [serve|test]" >&2
    exit 2
    ;;
esac

missing=()
for pkg in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$pkg")
  fi
done

if [ "${#missing[@]}" -eq 0 ]; then
  exit 0
fi

echo "setup: installing missing packages: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  SUDO="sudo"
fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
