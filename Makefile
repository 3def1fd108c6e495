# The front door. Every target first installs missing Debian packages (idempotent).
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
OUT ?= out

.PHONY: deps configure build test run bench clean sanitize sanitize-configure fuzz

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

# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer, in its own
# clang tree (build-sanitize; the benchmarks and the Python module are not built), which also
# holds the libFuzzer targets of `make fuzz`: the instrumented library is compiled once for
# both (fuzz/CMakeLists.txt: coverage counters in the whole library, comparison tracing in
# the readers only; they cost the suite about a quarter of its run time). Tests labelled
# `slow` (the million-step soak, the golden outputs of a Release build) run once, in
# `make test`, not again here. Any report fails the run; a
# sanitized process exits 99, so a test expecting the CLI to fail (status 1 or 2) cannot
# mistake a report for the failure it wanted.
# -O1 with line tables (-g1): ASan's usual optimisation level. With UBSan, GCC compiles a
# file at -O2 -g in twice the time (seif_slam.cpp: 80 s against 39 s), and the build is most
# of this target's time; reports still name file and line.
SANITIZE_OPT ?= -O1 -g1 -DNDEBUG
sanitize: export ASAN_OPTIONS = detect_leaks=1:halt_on_error=1:exitcode=99:print_stacktrace=1:check_initialization_order=1:strict_init_order=1:detect_stack_use_after_return=1
sanitize: export UBSAN_OPTIONS = halt_on_error=1:exitcode=99:print_stacktrace=1
sanitize-configure: deps
	@mkdir -p build-sanitize
	@cmake -S . -B build-sanitize -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$(SANITIZE_OPT)" -DSEIF_SANITIZE=ON -DSEIF_BUILD_FUZZERS=ON \
	  -DSEIF_BUILD_BENCH=OFF $(CMAKE_FLAGS) >build-sanitize/configure.log 2>&1 || { cat build-sanitize/configure.log; exit 1; }
sanitize: sanitize-configure
	@MAKEFLAGS= cmake --build build-sanitize -j $(JOBS) -- --no-print-directory
	@cd build-sanitize && ctest --output-on-failure -j $(JOBS) -LE slow

# libFuzzer targets of fuzz/ (clang, ASan + UBSan), built in build-sanitize (after `make
# sanitize` only they are linked), each run for FUZZ_SECONDS seconds: executions, exec/s, CPU
# seconds and findings per target (scripts/fuzz).
FUZZ_SECONDS ?= 60
fuzz: sanitize-configure
	@FUZZ_SECONDS=$(FUZZ_SECONDS) JOBS=$(JOBS) scripts/fuzz build-sanitize

clean:
	@rm -rf $(BUILD_DIR)
