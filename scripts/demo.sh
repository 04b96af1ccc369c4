#!/usr/bin/env bash
# The main job on synthetic data, end to end:
#   synthetic KITTI-format data -> dataset summary -> stereo features (RGB-H, RGB-D, pseudo-LiDAR,
#   disparity) -> the committed single-shot detectors (models/ssd-rgb, models/ssd-rgbh-learned) ->
#   detections -> evaluation with the KITTI-compatible and the optimal matcher -> the report: figures
#   (SVG, PNG) and one HTML page of every detector's evaluation, overlaid (docs/report.md); then the
#   paper's 3D question: the committed 3D detectors on LiDAR and on stereo point clouds
#   (models/det3d-lidar, models/det3d-stereo), their BEV and 3D AP and localization error in a
#   report of their own, and the two compared by distance beside the stereo depth-error model.
# Without committed models (or with DEMO_TRAIN=1) a smoke-sized detector (a few epochs on a few
# frames) is trained instead; `make models` reproduces the committed ones (docs/models.md).
# Usage: scripts/demo.sh BUILD_DIR DEMO_DIR
#   DEMO_FRAMES=N (default 100: 50 validation frames), DEMO_TRAIN=1, DEMO_EPOCHS=N (smoke
#   training), DEMO_MODELS=DIR
set -euo pipefail
build_dir=${1:-build}
demo_dir=${2:-$build_dir/demo}
frames=${DEMO_FRAMES:-100}
epochs=${DEMO_EPOCHS:-3}
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "demo: $bin not built; run make build" >&2; exit 1; }
mkdir -p "$demo_dir"
# Named after its settings: synth refuses to resume a folder made with other settings (an older demo).
data="$demo_dir/data-seed7-$frames"

step() { printf '\n==> %s\n' "$*"; }

step "Synthetic KITTI-format data set: $frames frames, stereo pairs, LiDAR scans, labels ($data)"
# Seed 7: the committed detectors were trained on seed 1's frames (the same seed gives the same
# frames), so the demo's validation frames must come from another seed.
"$bin" synth --out "$data" --frames "$frames" --seed 7

step "What is in it"
"$bin" info "$data"

step "Stereo features for every frame: RGB-H, RGB-D, pseudo-LiDAR point clouds, disparity ($demo_dir/stereo)"
"$bin" stereo --data "$data" --out "$demo_dir/stereo" --encode rgbh,rgbd,points,disparity --evaluate

step "Pictures of one frame: disparity, depth, height, point cloud from above ($demo_dir/stereo_frame)"
"$bin" stereo frame --data "$data" --id 000000 --out "$demo_dir/stereo_frame"

models_dir=${DEMO_MODELS:-models}
evals=()
if ! "$bin" train ssd --help >/dev/null 2>&1; then
  echo "demo: this build has no LibTorch detectors (STEREODET_BUILD_MODELS=OFF); skipping detection"
else
  detectors=()
  if [[ -z "${DEMO_TRAIN:-}" && -f "$models_dir/ssd-rgb/model.pt" && -f "$models_dir/ssd-rgbh-learned/model.pt" ]]; then
    detectors=("$models_dir/ssd-rgb" "$models_dir/ssd-rgbh-learned")
    step "Committed detectors (trained on 3000 synthetic frames, docs/RESULTS.md): ${detectors[*]}"
  else
    step "Single-shot detector on RGB-H, $epochs epochs on the train split (smoke-sized: DEMO_TRAIN is set or no committed model was found)"
    "$bin" train ssd --data "$data" --split train --input rgbh-learned --out "$demo_dir/ssd-rgbh-learned" \
      --epochs "$epochs" --seed 1 --resume
    detectors=("$demo_dir/ssd-rgbh-learned")
  fi
  for model in "${detectors[@]}"; do
    name=$(basename "$model")
    step "$name: detections on the val split, KITTI format ($demo_dir/detections-$name)"
    "$bin" detect ssd --model "$model" --data "$data" --split val --out "$demo_dir/detections-$name"

    step "$name: KITTI-compatible AP"
    "$bin" eval --gt "$data" --det "$demo_dir/detections-$name" --split val --metrics 2d --matcher kitti

    step "$name: optimal matching, with results.json, curves, per-detection records and the views of the worst frames ($demo_dir/eval-$name)"
    "$bin" eval --gt "$data" --det "$demo_dir/detections-$name" --split val --metrics 2d --matcher optimal \
      --out "$demo_dir/eval-$name" --records --report
    evals+=("$demo_dir/eval-$name")
  done
fi

reports_3d=()
if "$bin" detect det3d --help >/dev/null 2>&1 && [[ -f "$models_dir/det3d-lidar/model.pt" &&
      -f "$models_dir/det3d-stereo/model.pt" ]]; then
  step "The committed 3D detectors, one trained on LiDAR scans and one on stereo point clouds (docs/det3d.md)"
  "$bin" detect det3d --model "$models_dir/det3d-lidar" --data "$data" --split val \
    --out "$demo_dir/detections-det3d-lidar"
  "$bin" detect det3d --model "$models_dir/det3d-stereo" --data "$data" --split val \
    --points "$demo_dir/stereo" --out "$demo_dir/detections-det3d-stereo"
  for input in lidar stereo; do
    step "det3d-$input: Car BEV and 3D AP and the localization error by distance ($demo_dir/eval-det3d-$input)"
    "$bin" eval --gt "$data" --det "$demo_dir/detections-det3d-$input" --split val --classes Car \
      --metrics bev,3d --out "$demo_dir/eval-det3d-$input" --records
  done
  step "The 3D report: LiDAR and stereo overlaid ($demo_dir/report-3d)"
  "$bin" report "$demo_dir/eval-det3d-lidar" "$demo_dir/eval-det3d-stereo" --labels lidar,stereo \
    --out "$demo_dir/report-3d"
  step "LiDAR vs stereo: the depth error of both by distance, beside the stereo model z^2 / (b f) dd ($demo_dir/compare-3d)"
  "$bin" eval compare --gt "$data" --det "$demo_dir/detections-det3d-lidar" \
    --det-b "$demo_dir/detections-det3d-stereo" --split val --classes Car --metrics 3d \
    --out "$demo_dir/compare-3d" --report
  reports_3d=("$demo_dir/report-3d/index.html" "$demo_dir/compare-3d/report/index.html")
fi

if [[ ${#evals[@]} -gt 0 ]]; then
  step "The report: every detector's evaluation overlaid, one colour each ($demo_dir/report)"
  labels=$(for e in "${evals[@]}"; do basename "$e" | sed 's/^eval-//'; done | paste -sd, -)
  "$bin" report "${evals[@]}" --labels "$labels" --out "$demo_dir/report"
  printf '\ndemo: done; everything is under %s\n' "$demo_dir"
  printf 'demo: the report of this run: %s\n' "$(realpath "$demo_dir/report/index.html")"
  for r in "${reports_3d[@]}"; do printf 'demo: %s\n' "$(realpath "$r")"; done
else
  printf '\ndemo: done; everything is under %s\n' "$demo_dir"
  echo "demo: no detector evaluated, so no report (build with LibTorch for the detection steps)"
fi
