#!/usr/bin/env bash
# The main job on synthetic data, end to end, with what exists so far.
#   scripts/demo.sh BUILD_DIR DEMO_DIR
set -euo pipefail
build_dir=${1:-build}
demo_dir=${2:-$build_dir/demo}
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "demo: $bin not built; run make build" >&2; exit 1; }
mkdir -p "$demo_dir"

step() { printf '\n==> %s\n' "$*"; }

step "Dataset summary of the checked-in KITTI sample (tests/data/kitti_mini)"
"$bin" info tests/data/kitti_mini
