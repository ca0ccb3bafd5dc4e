#!/usr/bin/env bash
# Installs the Debian packages pathd needs to build and test. Idempotent: when
# every package is already installed it does nothing (no apt-get update).
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build ccache pkg-config
  libgrpc++-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libabsl-dev libspdlog-dev libyaml-cpp-dev
  prometheus-cpp-dev libcurl4-openssl-dev
  libpng-dev
  libisal-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3
  python3-grpcio python3-protobuf
  libcsv-dev
  openssl libssl-dev
  # The loopback scale-out test (tests/e2e/scaleout_test.cc) runs nginx as
  # the test's user with its own config; the package's system service is not
  # used (on a machine without a policy-rc.d, apt starts it on port 80).
  nginx
  # make fuzz: clang, its libFuzzer runtime, llvm-symbolizer for the reports.
  clang libclang-rt-14-dev llvm
)

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
