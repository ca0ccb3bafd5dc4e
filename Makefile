# The commands of the README's quick start, plus a few conveniences
# (docs/testing.md, "Builds", says what each builds and installs).
#   make serve  - install what serving needs (scripts/setup.sh serve), build
#                 pathd and pathctl only, write the 16384^2 map once
#                 (HUGE_SIDE), run pathd on 127.0.0.1:50051
#   make build-serve - the same without running pathd
#   make test   - install what the tests need too (scripts/setup.sh test),
#                 build everything, run every test with ctest
#   make build  - the same without running the tests
#   make test-tsan - the tests labelled tsan (the concurrency test) built with
#                 ThreadSanitizer in $(TSAN_BUILD_DIR); any report fails
#   make test-asan - every test built with AddressSanitizer + UBSan in
#                 $(ASAN_BUILD_DIR); any report fails
#   make fuzz   - the libFuzzer targets (clang, $(FUZZ_BUILD_DIR)), each for
#                 FUZZ_SECONDS
#   make check-thread-safety - core/, server/ and client/ through clang's
#                 -Wthread-safety -Werror, syntax only; any warning fails
#   make install - build pathd, pathctl and the C++ client and install them
#                 under PREFIX (/usr/local; DESTDIR honoured; docs/install.md)
#   make deb    - the Debian packages pathd and pathd-dev by CPack in
#                 $(BUILD_DIR)/packages (scripts/setup.sh package)
#   make deb-check - make deb, then tests/e2e/deb_package_test.py on the
#                 package it built (its Depends line included)
# ccache is picked by CMakeLists.txt (PATHD_CCACHE), not here, so every
# configure of a build directory agrees and a second build rebuilds nothing.
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
ADDRESS ?= 127.0.0.1:50051
HTTP_ADDRESS ?= 127.0.0.1:8080
CMAKE_CONFIGURE = cmake -S . -G Ninja

.PHONY: setup-serve setup-test configure configure-test build-serve serve serve-maps \
        build test bench clean format test-tsan test-asan fuzz check-thread-safety \
        setup-package install deb deb-check

setup-serve:
	@bash scripts/setup.sh serve

setup-test:
	@bash scripts/setup.sh test

# Tests are configured when GoogleTest is installed (PATHD_BUILD_TESTS=AUTO,
# or whatever an earlier configure of $(BUILD_DIR) chose); serving never
# needs them.
configure: setup-serve
	@$(CMAKE_CONFIGURE) -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) >/dev/null

configure-test: setup-test
	@$(CMAKE_CONFIGURE) -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) -DPATHD_BUILD_TESTS=ON >/dev/null

build-serve: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target pathd pathctl map_tile

# `make serve` serves the bundled maps plus one huge map, huge$(HUGE_SIDE)
# (HUGE_SIDE x HUGE_SIDE cells mirror-tiled from maps/arena2.map by
# tools/map_tile; docs/performance.md, "Huge maps"), from
# $(SERVE_MAP_DIR): the bundled maps are copied there (a --map_dir file
# must lie inside the directory), the huge one is written once and kept.
# HUGE_SIDE= (empty) serves the bundled maps alone (a huge map of another
# side written earlier is deleted from $(SERVE_MAP_DIR)).
HUGE_SIDE ?= 16384
SERVE_MAP_DIR ?= $(BUILD_DIR)/serve_maps

$(SERVE_MAP_DIR)/huge$(HUGE_SIDE).yaml: | build-serve
	@mkdir -p $(SERVE_MAP_DIR)
	$(BUILD_DIR)/tools/map_tile --source=maps/arena2.map --side=$(HUGE_SIDE) --out=$@

serve-maps: build-serve $(if $(HUGE_SIDE),$(SERVE_MAP_DIR)/huge$(HUGE_SIDE).yaml)
	@mkdir -p $(SERVE_MAP_DIR)
	@find $(SERVE_MAP_DIR) -maxdepth 1 -name 'huge*' ! -name 'huge$(HUGE_SIDE).*' -delete
	@cp -p maps/*.map maps/*.yaml maps/*.pgm $(SERVE_MAP_DIR)/

serve: serve-maps
	exec $(BUILD_DIR)/server/pathd --address=$(ADDRESS) --map_dir=$(SERVE_MAP_DIR) --http_address=$(HTTP_ADDRESS)

build: configure-test
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

bench: configure-test
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target pathd_bench control_bench
	$(BUILD_DIR)/tests/bench/pathd_bench --movingai_dir=../shared/benchmarks/movingai

clean:
	rm -rf $(BUILD_DIR) $(TSAN_BUILD_DIR) $(ASAN_BUILD_DIR) $(FUZZ_BUILD_DIR)

format:
	clang-format -i $$(git ls-files '*.h' '*.cc')

# Abseil's lock annotations (ABSL_GUARDED_BY, ABSL_EXCLUSIVE_LOCKS_REQUIRED,
# ...) are only checked by clang: every core/, server/ and client/ source of
# $(BUILD_DIR)'s compile database is compiled with -fsyntax-only
# -Wthread-safety -Werror (scripts/check_thread_safety.py). It needs the
# generated protobuf headers (protoc only, nothing compiled).
check-thread-safety: setup-test configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target pathd_proto_generated
	python3 scripts/check_thread_safety.py $(BUILD_DIR) --jobs $(JOBS)

# ThreadSanitizer: its own build directory, only the targets of the tests
# labelled tsan (tests/*/CMakeLists.txt), which ctest runs with the
# TSAN_OPTIONS set in CMakeLists.txt (halt_on_error, tests/tsan/tsan.supp).
TSAN_BUILD_DIR ?= build-tsan
TSAN_TARGETS ?= concurrency_test navigate_control_test navigate_fleet_test

test-tsan: setup-test
	@$(CMAKE_CONFIGURE) -B $(TSAN_BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPATHD_TSAN=ON >/dev/null
	@cmake --build $(TSAN_BUILD_DIR) -j $(JOBS) --target $(TSAN_TARGETS)
	cd $(TSAN_BUILD_DIR) && ctest --output-on-failure -L tsan

# AddressSanitizer + UndefinedBehaviorSanitizer: its own build directory,
# every test. The options reach the processes the tests start too (e2e runs
# the real pathd and pathctl). The Moving AI conformance suite checks every
# ASAN_CONFORMANCE_STRIDE-th scenario of every map (each planner still runs
# on the first scenario of each map and every stride*own-stride-th after it):
# in full it takes 40 minutes uninstrumented, and the planners' code paths do
# not change from one scenario to the next. The geometric sweep likewise runs
# 10 scenarios a map and leaves out the structures whose builds dominate it
# (the visibility graph, 13 s on one maze uninstrumented, and the per-goal
# shortest path maps); geometric_planners_test runs every geometric planner
# under the sanitizers on its thousands of small maps. The crash test kills
# pathd 6 + 20 times instead of 12 + 40 (still at every checkpoint step).
ASAN_BUILD_DIR ?= build-asan
ASAN_CONFORMANCE_STRIDE ?= 50
ASAN_ENV := ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:abort_on_error=1 \
  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/asan/lsan.supp:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  PATHD_CONFORMANCE_STRIDE=$(ASAN_CONFORMANCE_STRIDE) \
  PATHD_GEOMETRIC_SCENARIOS=10 PATHD_GEOMETRIC_PLANNERS=navmesh,minimal_construct \
  PATHD_FLEET_CASES=8 PATHD_LOCAL_CASES=100 PATHD_MAPF_CASES=100 PATHD_EXECUTION_CASES=40 PATHD_HPA_CASES=6 PATHD_SIM_CASES=10 \
  PATHD_NATURE_CASES=20 PATHD_JPS_PLUS_CASES=3 PATHD_RADIX_CASES=50 \
  PATHD_CRASH_KILLS=6 PATHD_CRASH_CHECKPOINT_KILLS=20

test-asan: setup-test
	@$(CMAKE_CONFIGURE) -B $(ASAN_BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPATHD_ASAN=ON >/dev/null
	@cmake --build $(ASAN_BUILD_DIR) -j $(JOBS)
	cd $(ASAN_BUILD_DIR) && $(ASAN_ENV) ctest --output-on-failure -j $(JOBS)

# libFuzzer: clang in its own build directory (tests/fuzz/CMakeLists.txt),
# then tests/fuzz/run_fuzzers.sh runs each target for FUZZ_SECONDS (all of
# them, or FUZZ_TARGETS="a b") and fails when one found a crash.
FUZZ_BUILD_DIR ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?=

fuzz: setup-test
	@$(CMAKE_CONFIGURE) -B $(FUZZ_BUILD_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DPATHD_FUZZ=ON >/dev/null
	@cmake --build $(FUZZ_BUILD_DIR) -j $(JOBS) --target pathd_fuzzers
	tests/fuzz/run_fuzzers.sh $(FUZZ_BUILD_DIR) $(FUZZ_SECONDS) $(FUZZ_TARGETS)

# Install and package (cmake/install.cmake, cmake/packaging.cmake): only the
# installed targets are built (CMAKE_SKIP_INSTALL_ALL_DEPENDENCY), tests or not.
PREFIX ?= /usr/local
INSTALL_TARGETS := pathd pathctl pathd_client pathd_proto

setup-package:
	@bash scripts/setup.sh package

install: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target $(INSTALL_TARGETS)
	cmake --install $(BUILD_DIR) --prefix $(PREFIX)

deb: setup-package configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target $(INSTALL_TARGETS)
	cd $(BUILD_DIR) && cpack -G DEB
	@ls -1 $(BUILD_DIR)/packages/*.deb

deb-check: deb
	PATHD_DEB=$$(ls -t $(BUILD_DIR)/packages/pathd_*_*.deb | head -1) \
	  /usr/bin/python3 tests/e2e/deb_package_test.py
