#!/usr/bin/env bash
# The main job on synthetic data, end to end, with what exists so far:
#   synthetic KITTI-format data -> dataset summary.
# Usage: scripts/demo.sh BUILD_DIR DEMO_DIR      (DEMO_FRAMES=N to change the data set size)
set -euo pipefail
build_dir=${1:-build}
demo_dir=${2:-$build_dir/demo}
frames=${DEMO_FRAMES:-20}
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "demo: $bin not built; run make build" >&2; exit 1; }
mkdir -p "$demo_dir"

step() { printf '\n==> %s\n' "$*"; }

step "Synthetic KITTI-format data set: $frames frames, stereo pairs, LiDAR scans, labels ($demo_dir/data)"
"$bin" synth --out "$demo_dir/data" --frames "$frames" --seed 1

step "What is in it"
"$bin" info "$demo_dir/data"

printf '\ndemo: done; the data set is in %s/data\n' "$demo_dir"
