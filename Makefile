# The front door. Every target first installs missing Debian packages (idempotent).
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
OUT ?= out

.PHONY: deps configure build test run bench clean

deps:
	@scripts/install-deps

configure: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS) >/dev/null

build: configure
	@MAKEFLAGS= cmake --build $(BUILD_DIR) -j $(JOBS) -- --no-print-directory

# The whole test suite (unit, equivalence, end-to-end, installed-package consumer).
test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS)

# The main job: the paper's experiment on its default input.
run: build
	@scripts/run-main $(BUILD_DIR)/bin/seif $(OUT)

bench: build
	@$(BUILD_DIR)/bin/seif_bench --benchmark_min_time=0.2

clean:
	@rm -rf $(BUILD_DIR)
