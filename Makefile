# stereodet — the two commands a new user needs are `make demo` and `make test`.
BUILD_DIR ?= build
JOBS ?= $(shell nproc)
CMAKE_FLAGS ?=
CTEST_FLAGS ?=
DEMO_DIR ?= $(BUILD_DIR)/demo
SYNTH_DIR ?= data/synth

.PHONY: all deps configure build test demo bench fuzz sanitize clean format format-check tidy models rpn-models ssd-results rpn-results det3d-models det3d-results det3d-let-results experiment kitti-experiment

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

# The committed detectors models/ssd-{rgb,rgbh-fixed,rgbh-learned}, reproduced from seed 1: a
# 4000-frame synthetic set in $(SYNTH_DIR), then three 10-epoch trainings (docs/models.md for the
# time they take; SSD_PARALLEL=3 trains them at once). Resumes where it stopped.
models: deps
	$(MAKE) build
	./scripts/train-ssd-models.sh $(BUILD_DIR) $(SYNTH_DIR) models

# The two-stage detectors models/rpn-{rgb,rgbd} (rgbd mirrored from rgb), seed 1, on the same
# synthetic set (RPN_CONTROL=1 adds the widened-rgb and the continued-rgb controls; docs/models.md
# for the time it takes).
rpn-models: deps
	$(MAKE) build
	./scripts/train-rpn-models.sh $(BUILD_DIR) $(SYNTH_DIR) models

# The 3D detectors models/det3d-{lidar,stereo}, reproduced from seed 1: a 2500-frame synthetic set
# with LiDAR in $(DET3D_DIR) (2000 train, 500 val), its stereo point clouds, two 12-epoch trainings
# (docs/det3d.md; DET3D_PARALLEL=2 trains both at once). Resumes where it stopped.
DET3D_DIR ?= data/synth-det3d
det3d-models: deps
	$(MAKE) build
	./scripts/train-det3d-models.sh $(BUILD_DIR) $(DET3D_DIR) models

# docs/RESULTS.md's table: the committed detectors on the val split, sharp and blurred.
ssd-results: deps
	$(MAKE) build
	./scripts/ssd-results.sh $(BUILD_DIR) $(SYNTH_DIR) models results/ssd

# docs/RESULTS.md's two-stage detector rows: models/rpn-{rgb,rgbd} (and the widened control
# models/rpn-rgb-wide when it is there) the same way; writes results/rpn/table.md.
rpn-results: deps
	$(MAKE) build
	RESULTS_FAMILY=rpn RESULTS_INPUTS="rgb rgbd$$(test -f models/rpn-rgb-wide/model.pt && echo ' rgb-wide')" \
	  ./scripts/ssd-results.sh $(BUILD_DIR) $(SYNTH_DIR) models results/rpn

# docs/RESULTS.md's 3D detector section: models/det3d-{lidar,stereo} on the val split of
# $(DET3D_DIR), 2D / BEV / 3D, strict and loose, both matchers, bootstrap, the LiDAR-vs-stereo
# localization compare; writes results/det3d/table.md.
det3d-results: deps
	$(MAKE) build
	./scripts/det3d-results.sh $(BUILD_DIR) $(DET3D_DIR) models results/det3d

# docs/RESULTS.md's LiDAR-vs-stereo table by distance with LET-3D-AP and its error-analysis table
# (issue 37): the 3D detectors of $(EXPERIMENT_DIR) (make experiment) on the val split and on the
# replication set; writes results/det3d-let{,-rep}/table.md and errors.md.
det3d-let-results: deps
	$(MAKE) build
	./scripts/det3d-let-results.sh $(BUILD_DIR) $(EXPERIMENT_DIR) $(DET3D_DIR) results/det3d-let
	./scripts/det3d-let-results.sh $(BUILD_DIR) $(EXPERIMENT_DIR)/replication $(DET3D_DIR)-rep results/det3d-let-rep

# The paper's Table 1 (docs/experiment.md): data, stereo points, detection with every model of
# $(EXPERIMENT_CONFIG) (absent checkpoints are "missing" rows), sharp and blurred, both matchers,
# bootstrap, paired compares; writes $(EXPERIMENT_DIR)/table1.md and docs/RESULTS.md's generated
# section. Resumes where it stopped. EXPERIMENT_FLAGS=--train retrains (3 seeds for the SSDs);
# EXPERIMENT_FLAGS="--train --workers 2" runs the steps on a local Dask cluster (docs/experiment.md).
EXPERIMENT_CONFIG ?= experiments/table1.json
EXPERIMENT_DIR ?= results/experiment
EXPERIMENT_FLAGS ?=
experiment: deps
	$(MAKE) build
	/usr/bin/python3 scripts/experiment.py --config $(EXPERIMENT_CONFIG) --out $(EXPERIMENT_DIR) \
	  --bin $(BUILD_DIR)/bin --update-docs docs/RESULTS.md $(EXPERIMENT_FLAGS)

# The same study on a real KITTI object download (docs/kitti.md, "The KITTI recipe"): every model
# trained on Chen et al.'s 3712 frames (experiments/kitti/ImageSets), evaluated on their 3769, Table
# 1 in $(KITTI_DIR)/table1.md. KITTI=/path/to/kitti is required (ROOT/training/{image_2,image_3,
# calib,label_2,velodyne}); nothing is written into it. Resumes where it stopped; KITTI_FLAGS adds
# experiment.py flags (--workers N, --scheduler ADDRESS).
KITTI_DIR ?= results/kitti
KITTI_FLAGS ?=
kitti-experiment: deps
	@test -n "$(KITTI)" || { echo "kitti-experiment: give KITTI=/path/to/kitti (docs/kitti.md)" >&2; exit 2; }
	$(MAKE) build
	/usr/bin/python3 scripts/experiment.py --config experiments/kitti.json --kitti $(KITTI) \
	  --out $(KITTI_DIR) --bin $(BUILD_DIR)/bin $(KITTI_FLAGS)

bench: deps
	$(MAKE) build
	./scripts/run-benchmarks.sh $(BUILD_DIR)

# libFuzzer targets for every parser and file format read (clang); FUZZ_SECONDS per target.
FUZZ_SECONDS ?= 600
fuzz:
	STEREODET_DEPS_EXTRA="clang" ./scripts/install-deps.sh
	CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
	  -DSTEREODET_BUILD_FUZZERS=ON -DSTEREODET_BUILD_TESTS=OFF -DSTEREODET_BUILD_BENCHMARKS=OFF \
	  -DSTEREODET_BUILD_MODELS=OFF
	cmake --build build-fuzz -j $(JOBS) --target fuzzers
	./scripts/run-fuzzers.sh build-fuzz $(FUZZ_SECONDS)

# ASan + UBSan build of everything but LibTorch's half of the models (their tests need an
# uninstrumented LibTorch; models_core, torch-free, is in) in $(SANITIZE_DIR), then every test there; any report fails the test that caused it.
# About 14 minutes on one core. CONTRIBUTING.md says when to run it.
SANITIZE_DIR ?= build-sanitize
SANITIZE_ENV = ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:strict_string_checks=1 \
  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  LSAN_OPTIONS=suppressions=$(CURDIR)/scripts/lsan-suppressions.txt:print_suppressions=0
sanitize: deps
	cmake -S . -B $(SANITIZE_DIR) -DCMAKE_BUILD_TYPE=RelWithDebInfo -DSTEREODET_SANITIZE=ON \
	  -DSTEREODET_BUILD_MODELS=OFF -DSTEREODET_BUILD_BENCHMARKS=OFF -DSTEREODET_BUILD_PYTHON=OFF \
	  $(CMAKE_FLAGS)
	cmake --build $(SANITIZE_DIR) -j $(JOBS)
	cd $(SANITIZE_DIR) && $(SANITIZE_ENV) ctest --output-on-failure -j $(JOBS) $(CTEST_FLAGS)

# One pinned clang-format (Debian 12's clang-format-14): another version formats some lines
# differently, and CI checks with this one.
CLANG_FORMAT ?= clang-format-14

format:
	$(CLANG_FORMAT) -i $$(git ls-files '*.h' '*.cc')

# Fails, listing the files, when a tracked C++ file is not as `make format` would write it.
format-check: deps
	@files=$$(git ls-files '*.h' '*.cc'); bad=""; \
	for f in $$files; do $(CLANG_FORMAT) --dry-run --Werror "$$f" >/dev/null 2>&1 || bad="$$bad $$f"; done; \
	if [ -n "$$bad" ]; then echo "format-check: not formatted (run make format):$$bad" >&2; exit 1; fi; \
	echo "format-check: $$(echo $$files | wc -w) files formatted as $(CLANG_FORMAT) writes them"

tidy: configure
	run-clang-tidy -p $(BUILD_DIR) -quiet src/

clean:
	rm -rf $(BUILD_DIR) build-fuzz $(SANITIZE_DIR)
