#!/usr/bin/env bash
# Trains the two-stage detectors models/rpn-{rgb,rgbd} (and the widened-rgb control
# models/rpn-rgb-wide) from seed 1 (or RPN_SEED) on the SSD's synthetic data set (docs/models.md "Two-stage
# detector"):
#   1. the synthetic data set: 4000 frames, seed 1, 3000 train / 1000 val, no LiDAR (the same call
#      as train-ssd-models.sh, so an existing set is reused);
#   2. rpn-rgb; then rpn-rgbd, its image branch, RPN and box head mirrored from rpn-rgb
#      (--init-from, the paper's pretrained weights: none can be downloaded here);
#   3. with RPN_CONTROL=1, the controls of docs/RESULTS.md: rpn-rgb-wide, rgb with the image
#      branch widened to the rgbd model's parameter count (--image-width 39: 3.29 M vs 3.26 M
#      parameters), and rpn-rgb-continued, rpn-rgb trained on as long as rgbd was (--init-from
#      rpn-rgb, the same schedule), so that both branches of the comparison saw 2 x RPN_EPOCHS.
# Every training resumes (--resume): rerunning after an interruption continues where it stopped.
# Usage: scripts/train-rpn-models.sh BUILD_DIR [DATA_DIR] [MODELS_DIR]
#   RPN_EPOCHS=6         epochs (the committed rpn-rgb: 6)
#   RPN_SEED=1           training seed; seed 1 trains MODELS_DIR/rpn-NAME (the committed models),
#                        any other seed S MODELS_DIR/rpn-NAME-seedS, each initialised from the
#                        rpn-rgb of its own seed (the training variance of docs/experiment.md)
#   RPN_THREADS=1        LibTorch threads (fixed: the weights are bit-identical for a fixed count;
#                        more threads than free cores is much slower: OpenMP spins at barriers)
#   RPN_MAX_FRAMES=0     only the first N training frames (0 = all)
#   RPN_IMAGE_WIDTH=32   image (and geometry) branch width; RPN_CONTROL_WIDTH=39 the control's
#   RPN_SYNTH_FRAMES=4000, RPN_SYNTH_ARGS=""   the data set (tiny runs: fewer, smaller frames)
#   RPN_ARGS=""          more flags for every `train rpn` (e.g. --width 64 --height 32)
#   RPN_FORCE=1          retrain a finished model (model.pt without checkpoint.pt) over it
#   RPN_PARALLEL=1       train one after the other (default); 2 trains in two waves of two at once,
#                        one core each: rpn-rgb beside rpn-rgb-wide (it needs no other model), then
#                        rpn-rgbd beside rpn-rgb-continued (both start from rpn-rgb); without
#                        RPN_CONTROL=1 it changes nothing. Output then goes to MODELS_DIR/rpn-*.out
set -euo pipefail
build_dir=${1:-build}
data=${2:-data/synth}
models=${3:-models}
epochs=${RPN_EPOCHS:-6}
threads=${RPN_THREADS:-1}
max_frames=${RPN_MAX_FRAMES:-0}
image_width=${RPN_IMAGE_WIDTH:-32}
control_width=${RPN_CONTROL_WIDTH:-39}
synth_frames=${RPN_SYNTH_FRAMES:-4000}
read -r -a synth_args <<< "${RPN_SYNTH_ARGS:-}"
read -r -a extra <<< "${RPN_ARGS:-}"
force=${RPN_FORCE:-0}
parallel=${RPN_PARALLEL:-1}
[[ "$parallel" =~ ^[0-9]+$ ]] || { echo "train-rpn-models: RPN_PARALLEL must be a whole number, got '$parallel'" >&2; exit 1; }
control=${RPN_CONTROL:-0}
seed=${RPN_SEED:-1}
[[ "$seed" =~ ^[0-9]+$ ]] || { echo "train-rpn-models: RPN_SEED must be a whole number, got '$seed'" >&2; exit 1; }
suffix=""
(( seed == 1 )) || suffix="-seed$seed"
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "train-rpn-models: $bin not built; run make build" >&2; exit 1; }
"$bin" train rpn --help >/dev/null 2>&1 ||
  { echo "train-rpn-models: $bin has no LibTorch detectors (STEREODET_BUILD_MODELS=OFF)" >&2; exit 1; }

echo "==> synthetic data set ($data)"
"$bin" synth --out "$data" --frames "$synth_frames" --seed 1 --val-fraction 0.25 --no-lidar \
  "${synth_args[@]}"

train() {  # NAME INPUT FLAGS...
  local name=$1 input=$2 dir="$models/$1" mode=--resume
  shift 2
  if [[ -f "$dir/model.pt" && ! -f "$dir/checkpoint.pt" ]]; then
    if [[ "$force" != 1 ]]; then
      echo "train-rpn-models: $dir holds a finished model; left alone (RPN_FORCE=1 retrains it)"
      return 0
    fi
    mode=--force
  fi
  echo "==> training $name ($dir; log: $dir/train_log.csv)"
  "$bin" train rpn --data "$data" --split train --input "$input" --out "$dir" \
    --epochs "$epochs" --seed "$seed" --threads "$threads" --max-frames "$max_frames" "$mode" \
    "${extra[@]}" "$@"
}

# One wave of trainings: each argument is a quoted "NAME INPUT FLAGS..." line. One after the other,
# or with RPN_PARALLEL > 1 all at once (each is one LibTorch thread), output in MODELS_DIR/NAME.out.
wave() {
  local spec pids=() names=() failed=0 i
  for spec in "$@"; do
    read -r -a args <<< "$spec"
    if (( parallel > 1 && $# > 1 )); then
      echo "==> training ${args[0]} in the background (output: $models/${args[0]}.out)"
      train "${args[@]}" > "$models/${args[0]}.out" 2>&1 &
      pids+=("$!")
      names+=("${args[0]}")
    else
      train "${args[@]}"
    fi
  done
  for i in "${!pids[@]}"; do
    wait "${pids[$i]}" || { echo "train-rpn-models: ${names[$i]} failed; see $models/${names[$i]}.out" >&2; failed=1; }
  done
  return "$failed"
}

# The waves pass each training as one line split at blanks: a models folder with one cannot be named.
[[ "$models" != *[[:space:]]* ]] || { echo "train-rpn-models: MODELS_DIR '$models' holds a blank" >&2; exit 1; }
mkdir -p "$models"
rgb="rpn-rgb$suffix rgb --image-width $image_width"
rgbd="rpn-rgbd$suffix rgbd --image-width $image_width --geometry-width $image_width --init-from $models/rpn-rgb$suffix"
wide="rpn-rgb-wide$suffix rgb --image-width $control_width"
continued="rpn-rgb-continued$suffix rgb --image-width $image_width --init-from $models/rpn-rgb$suffix"
if [[ "$control" == 1 ]]; then
  wave "$rgb" "$wide"
  wave "$rgbd" "$continued"
else
  wave "$rgb"
  wave "$rgbd"
fi
echo "train-rpn-models: done; the models are in $models/rpn-*"
