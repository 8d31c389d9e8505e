# Thin wrapper: every real rule lives in CMake.
BUILD_DIR ?= build
BUILD_TYPE ?= Release
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=

.PHONY: all deps configure build test demo bench sanitize format clean

all: build

deps:
	@bash scripts/install-deps.sh

configure: deps
	@cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=$(BUILD_TYPE) $(CMAKE_FLAGS) > $(BUILD_DIR).configure.log 2>&1 \
	  || { cat $(BUILD_DIR).configure.log; exit 1; }

build: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS)

test: build
	@cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) --timeout 300

# The demo needs only the program: tests and benchmarks are left for `make test`.
demo: configure
	@cmake --build $(BUILD_DIR) -j $(JOBS) --target jointlab
	@bash examples/demo.sh $(BUILD_DIR)

# (A build directory configured without them, as CI's, gets them back here.)
bench: CMAKE_FLAGS += -DJOINTLAB_BUILD_BENCHMARKS=ON
bench: build
	@for b in $(BUILD_DIR)/bin/jointlab_bench_*; do echo "== $$b"; $$b; done
	@bash bench/compare_scipy.sh $(BUILD_DIR)

# The whole suite under AddressSanitizer and UBSan (any report fails its test); LeakSanitizer
# ignores only the third-party caches listed in fuzz/lsan.supp.
sanitize:
	@$(MAKE) test BUILD_DIR=build-sanitize BUILD_TYPE=RelWithDebInfo CMAKE_FLAGS=-DJOINTLAB_SANITIZE=ON

format:
	@clang-format -i $$(git ls-files '*.h' '*.cc')

clean:
	@rm -rf $(BUILD_DIR) $(BUILD_DIR).configure.log build-sanitize build-sanitize.configure.log
