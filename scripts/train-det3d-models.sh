#!/usr/bin/env bash
# Reproduces the 3D detectors models/det3d-{lidar,stereo} from seed 1 (or DET3D_SEED) (docs/det3d.md
# "Reproducing the checkpoints"):
#   1. the synthetic data set with LiDAR scans: DET3D_FRAMES frames, seed 1, a DET3D_VAL_FRACTION
#      share in val (default 2500 frames: 2000 train, 500 val);
#   2. the stereo point clouds of every frame (`stereo --encode points`, default settings) into
#      DATA/stereo_points;
#   3. the two trainings, identical apart from --input (the stereo model's GT database holds stereo
#      objects only): DET3D_EPOCHS epochs, seed 1, one LibTorch thread each (a fixed thread count
#      makes the weights bit-identical from run to run, and on a loaded 2-core machine two threads
#      were 13x slower a step than one: docs/BENCHMARKS.md).
# Every step resumes: rerunning after an interruption continues where it stopped.
# Usage: scripts/train-det3d-models.sh BUILD_DIR [DATA_DIR] [MODELS_DIR]
#   DET3D_INPUTS="lidar stereo"  which models
#   DET3D_FRAMES=2500            frames of the synthetic set (train + val)
#   DET3D_VAL_FRACTION=0.2       share of them in val
#   DET3D_EPOCHS=12              epochs
#   DET3D_SEED=1                 training seed; seed 1 trains MODELS_DIR/det3d-INPUT (the committed
#                                models), any other seed S MODELS_DIR/det3d-INPUT-seedS on the same
#                                data (the training variance of docs/experiment.md)
#   DET3D_PARALLEL=1             train one after the other (default); 2 trains both at once, one
#                                core each (output then goes to MODELS_DIR/det3d-*.out)
#   DET3D_FORCE=1                retrain a finished model (model.pt without checkpoint.pt, as
#                                committed) over it; without it such a model is left alone
#   DET3D_EXTRA="..."            more `train det3d` flags (e.g. "--width 16" or "--max-frames 8")
set -euo pipefail
build_dir=${1:-build}
data=${2:-data/synth-det3d}
models=${3:-models}
inputs=${DET3D_INPUTS:-lidar stereo}
frames=${DET3D_FRAMES:-2500}
val_fraction=${DET3D_VAL_FRACTION:-0.2}
epochs=${DET3D_EPOCHS:-12}
seed=${DET3D_SEED:-1}
[[ "$seed" =~ ^[0-9]+$ ]] || { echo "train-det3d-models: DET3D_SEED must be a whole number, got '$seed'" >&2; exit 1; }
suffix=""
(( seed == 1 )) || suffix="-seed$seed"
parallel=${DET3D_PARALLEL:-1}
force=${DET3D_FORCE:-0}
extra=${DET3D_EXTRA:-}
bin="$build_dir/bin/stereodet"
points="$data/stereo_points"
[[ -x "$bin" ]] || { echo "train-det3d-models: $bin not built; run make build" >&2; exit 1; }
"$bin" train det3d --help >/dev/null 2>&1 ||
  { echo "train-det3d-models: $bin has no LibTorch detectors (STEREODET_BUILD_MODELS=OFF)" >&2; exit 1; }

echo "==> synthetic data set with LiDAR ($data, $frames frames)"
"$bin" synth --out "$data" --frames "$frames" --seed 1 --val-fraction "$val_fraction"

if [[ " $inputs " == *" stereo "* ]]; then
  for split in train val; do
    echo "==> stereo point clouds, $split ($points)"
    "$bin" stereo --data "$data" --split "$split" --encode points --out "$points"
  done
fi

train() {
  local input=$1 dir="$models/det3d-$input$suffix" mode=--resume
  # A finished model without its checkpoint (a committed one) cannot be resumed, and train det3d
  # refuses to train over it silently: retrain it only when asked.
  if [[ -f "$dir/model.pt" && ! -f "$dir/checkpoint.pt" ]]; then
    if [[ "$force" != 1 ]]; then
      echo "train-det3d-models: $dir holds a finished model; left alone (DET3D_FORCE=1 retrains it)"
      return 0
    fi
    mode=--force
  fi
  local stereo_flags=()
  [[ "$input" == stereo ]] && stereo_flags=(--points "$points")
  # shellcheck disable=SC2086  # DET3D_EXTRA is a list of flags
  "$bin" train det3d --data "$data" --split train --input "$input" "${stereo_flags[@]}" \
    --out "$dir" --epochs "$epochs" --seed "$seed" --threads 1 "$mode" $extra
}

mkdir -p "$models"
pids=()
for input in $inputs; do
  echo "==> training det3d-$input$suffix ($models/det3d-$input$suffix; log: $models/det3d-$input$suffix/train_log.csv)"
  if (( parallel > 1 )); then
    train "$input" > "$models/det3d-$input$suffix.out" 2>&1 &
    pids+=("$!")
  else
    train "$input"
  fi
done
failed=0
for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
(( failed == 0 )) ||
  { echo "train-det3d-models: a training failed; see $models/det3d-*.out" >&2; exit 1; }
echo "train-det3d-models: done; commit $models/det3d-*/model.json and model.pt"
