#!/usr/bin/env bash
# The main job on synthetic data, end to end:
#   synthetic KITTI-format data -> dataset summary -> stereo features (RGB-H, RGB-D, pseudo-LiDAR,
#   disparity) -> a small single-shot detector trained on RGB-H -> detections -> evaluation with the
#   KITTI-compatible and the optimal matcher.
# The detector here is a smoke-sized run (a few epochs on a few frames) to show the pipeline; see
# docs/models.md for the real training schedule.
# Usage: scripts/demo.sh BUILD_DIR DEMO_DIR      (DEMO_FRAMES=N, DEMO_EPOCHS=N to change sizes)
set -euo pipefail
build_dir=${1:-build}
demo_dir=${2:-$build_dir/demo}
frames=${DEMO_FRAMES:-20}
epochs=${DEMO_EPOCHS:-3}
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "demo: $bin not built; run make build" >&2; exit 1; }
mkdir -p "$demo_dir"
data="$demo_dir/data"

step() { printf '\n==> %s\n' "$*"; }

step "Synthetic KITTI-format data set: $frames frames, stereo pairs, LiDAR scans, labels ($data)"
"$bin" synth --out "$data" --frames "$frames" --seed 1

step "What is in it"
"$bin" info "$data"

step "Stereo features for every frame: RGB-H, RGB-D, pseudo-LiDAR point clouds, disparity ($demo_dir/stereo)"
"$bin" stereo --data "$data" --out "$demo_dir/stereo" --encode rgbh,rgbd,points,disparity --evaluate

step "Pictures of one frame: disparity, depth, height, point cloud from above ($demo_dir/stereo_frame)"
"$bin" stereo frame --data "$data" --id 000000 --out "$demo_dir/stereo_frame"

if "$bin" train ssd --help >/dev/null 2>&1; then
  step "Single-shot detector on RGB-H, $epochs epochs on the train split (smoke-sized)"
  "$bin" train ssd --data "$data" --split train --input rgbh-learned --out "$demo_dir/ssd-rgbh-learned" \
    --epochs "$epochs" --seed 1 --resume

  step "Detections on the val split, KITTI format ($demo_dir/detections)"
  "$bin" detect ssd --model "$demo_dir/ssd-rgbh-learned" --data "$data" --split val \
    --out "$demo_dir/detections"

  step "Evaluation: KITTI-compatible AP"
  "$bin" eval --gt "$data" --det "$demo_dir/detections" --split val --metrics 2d --matcher kitti

  step "Evaluation: optimal matching, with results.json and curves ($demo_dir/eval)"
  "$bin" eval --gt "$data" --det "$demo_dir/detections" --split val --metrics 2d --matcher optimal \
    --out "$demo_dir/eval"
else
  echo "demo: this build has no LibTorch detectors (STEREODET_BUILD_MODELS=OFF); skipping training"
fi

printf '\ndemo: done; everything is under %s\n' "$demo_dir"
