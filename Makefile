# The commands of the README's quick start, plus a few conveniences.
#   make serve  - install what is missing, build, run pathd on 127.0.0.1:50051
#   make test   - install what is missing, build, run every test with ctest
#   make test-tsan - the tests labelled tsan (the concurrency test) built with
#                 ThreadSanitizer in $(TSAN_BUILD_DIR); any report fails
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
	rm -rf $(BUILD_DIR) $(TSAN_BUILD_DIR)

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
