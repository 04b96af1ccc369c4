# stereodet — the two commands a new user needs are `make demo` and `make test`.
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
CTEST_FLAGS ?=
DEMO_DIR ?= $(BUILD_DIR)/demo

.PHONY: all deps configure build test demo bench fuzz clean format tidy

all: build

deps:
	./scripts/install-deps.sh

configure:
	cmake -S . -B $(BUILD_DIR) -DCMAKE_BUILD_TYPE=Release $(CMAKE_FLAGS)

build: configure
	cmake --build $(BUILD_DIR) -j $(JOBS)

# deps + build + every test; ends with ctest's summary.
test: deps
	$(MAKE) build
	cd $(BUILD_DIR) && ctest --output-on-failure -j $(JOBS) $(CTEST_FLAGS)

# deps + build + the main job on synthetic data.
demo: deps
	$(MAKE) build
	./scripts/demo.sh $(BUILD_DIR) $(DEMO_DIR)

bench: deps
	$(MAKE) build
	./scripts/run-benchmarks.sh $(BUILD_DIR)

# libFuzzer targets for the KITTI parsers (clang); FUZZ_SECONDS per target.
FUZZ_SECONDS ?= 600
fuzz:
	STEREODET_DEPS_EXTRA="clang" ./scripts/install-deps.sh
	CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DSTEREODET_BUILD_FUZZERS=ON -DSTEREODET_BUILD_TESTS=OFF -DSTEREODET_BUILD_BENCHMARKS=OFF \
	  -DSTEREODET_BUILD_MODELS=OFF
	cmake --build build-fuzz -j $(JOBS) --target fuzzers
	./scripts/run-fuzzers.sh build-fuzz $(FUZZ_SECONDS)

format:
	clang-format -i $$(git ls-files '*.h' '*.cc')

tidy: configure
	run-clang-tidy -p $(BUILD_DIR) -quiet src/

clean:
	rm -rf $(BUILD_DIR) build-fuzz
