# The commands of the README's quick start, plus a few conveniences.
#   make serve  - install what is missing, build, run pathd on 127.0.0.1:50051
#   make test   - install what is missing, build, run every test with ctest
#   make test-tsan - the tests labelled tsan (the concurrency test) built with
#                 ThreadSanitizer in $(TSAN_BUILD_DIR); any report fails
#   make test-asan - every test built with AddressSanitizer + UBSan in
#                 $(ASAN_BUILD_DIR); any report fails
#   make fuzz   - the libFuzzer targets (clang, $(FUZZ_BUILD_DIR)), each for
#                 FUZZ_SECONDS
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
ADDRESS ?= 127.0.0.1:50051
CMAKE_LAUNCHER := $(shell command -v ccache >/dev/null 2>&1 && echo -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)

.PHONY: setup configure build serve test bench clean format test-tsan

setup:
	@bash scripts/setup.sh

configure: setup
	@cmake -S . -B $(BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_LAUNCHER) >/dev/null

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

serve: build
	exec $(BUILD_DIR)/server/pathd --address=$(ADDRESS) --map_dir=maps

test: build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

bench: build
	$(BUILD_DIR)/tests/bench/pathd_bench --movingai_dir=../shared/benchmarks/movingai

clean:
	rm -rf $(BUILD_DIR) $(TSAN_BUILD_DIR) $(ASAN_BUILD_DIR) $(FUZZ_BUILD_DIR)

format:
	clang-format -i $$(git ls-files '*.h' '*.cc')

# ThreadSanitizer: its own build directory, only the targets of the tests
# labelled tsan (tests/*/CMakeLists.txt), which ctest runs with the
# TSAN_OPTIONS set in CMakeLists.txt (halt_on_error, tests/tsan/tsan.supp).
TSAN_BUILD_DIR ?= build-tsan
TSAN_TARGETS ?= concurrency_test

test-tsan: setup
	@cmake -S . -B $(TSAN_BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPATHD_TSAN=ON $(CMAKE_LAUNCHER) >/dev/null
	@cmake --build $(TSAN_BUILD_DIR) -j $(JOBS) --target $(TSAN_TARGETS)
	cd $(TSAN_BUILD_DIR) && ctest --output-on-failure -L tsan

# AddressSanitizer + UndefinedBehaviorSanitizer: its own build directory,
# every test. The options reach the processes the tests start too (e2e runs
# the real pathd and pathctl). The Moving AI conformance suite checks every
# ASAN_CONFORMANCE_STRIDE-th scenario of every map (each planner still runs
# on the first scenario of each map and every stride*own-stride-th after it):
# in full it takes 40 minutes uninstrumented, and the planners' code paths do
# not change from one scenario to the next.
ASAN_BUILD_DIR ?= build-asan
ASAN_CONFORMANCE_STRIDE ?= 50
ASAN_ENV := ASAN_OPTIONS=detect_leaks=1:strict_string_checks=1:detect_stack_use_after_return=1:check_initialization_order=1:abort_on_error=1 \
  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/asan/lsan.supp:print_suppressions=0 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  PATHD_CONFORMANCE_STRIDE=$(ASAN_CONFORMANCE_STRIDE)

.PHONY: test-asan fuzz

test-asan: setup
	@cmake -S . -B $(ASAN_BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPATHD_ASAN=ON $(CMAKE_LAUNCHER) >/dev/null
	@cmake --build $(ASAN_BUILD_DIR) -j $(JOBS)
	cd $(ASAN_BUILD_DIR) && $(ASAN_ENV) ctest --output-on-failure -j $(JOBS)

# libFuzzer: clang in its own build directory (tests/fuzz/CMakeLists.txt),
# then tests/fuzz/run_fuzzers.sh runs each target for FUZZ_SECONDS (all of
# them, or FUZZ_TARGETS="a b") and fails when one found a crash.
FUZZ_BUILD_DIR ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?=

fuzz: setup
	@cmake -S . -B $(FUZZ_BUILD_DIR) -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DPATHD_FUZZ=ON $(CMAKE_LAUNCHER) >/dev/null
	@cmake --build $(FUZZ_BUILD_DIR) -j $(JOBS) --target pathd_fuzzers
	tests/fuzz/run_fuzzers.sh $(FUZZ_BUILD_DIR) $(FUZZ_SECONDS) $(FUZZ_TARGETS)
