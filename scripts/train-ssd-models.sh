#!/usr/bin/env bash
# Reproduces the committed detectors models/ssd-{rgb,rgbh-fixed,rgbh-learned} from seed 1
# (docs/models.md "Reproducing the checkpoints", docs/RESULTS.md):
#   1. the synthetic data set: 4000 frames, seed 1, 3000 train / 1000 val (no LiDAR: the image
#      detector does not use it, and the images, labels and calibration do not depend on it);
#   2. the three trainings, identical apart from --input: 10 epochs, seed 1, one LibTorch thread
#      each (a fixed thread count makes the weights bit-identical from run to run).
# Every step resumes: rerunning after an interruption continues where it stopped.
# Usage: scripts/train-ssd-models.sh BUILD_DIR [DATA_DIR] [MODELS_DIR]
#   SSD_INPUTS="rgb rgbh-fixed rgbh-learned"  which models
#   SSD_PARALLEL=1   train the models one after the other (default); any other value trains them all
#                    at once (each is one network thread plus a data-loader thread, so three at once
#                    keep both cores of a 2-core machine busy; output then goes to MODELS_DIR/ssd-*.out)
#   SSD_EPOCHS=10    epochs (the committed models: 10)
#   SSD_SEED=1       training seed; seed 1 trains MODELS_DIR/ssd-INPUT (the committed models), any
#                    other seed S MODELS_DIR/ssd-INPUT-seedS (the training-variance checkpoints of
#                    docs/experiment.md)
#   SSD_FORCE=1      retrain a finished model (model.pt without checkpoint.pt, as committed) over it;
#                    without it such a model is left alone and said so
set -euo pipefail
build_dir=${1:-build}
data=${2:-data/synth}
models=${3:-models}
inputs=${SSD_INPUTS:-rgb rgbh-fixed rgbh-learned}
parallel=${SSD_PARALLEL:-1}
epochs=${SSD_EPOCHS:-10}
force=${SSD_FORCE:-0}
seed=${SSD_SEED:-1}
[[ "$seed" =~ ^[0-9]+$ ]] || { echo "train-ssd-models: SSD_SEED must be a whole number, got '$seed'" >&2; exit 1; }
suffix=""
(( seed == 1 )) || suffix="-seed$seed"
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "train-ssd-models: $bin not built; run make build" >&2; exit 1; }
"$bin" train ssd --help >/dev/null 2>&1 ||
  { echo "train-ssd-models: $bin has no LibTorch detectors (STEREODET_BUILD_MODELS=OFF)" >&2; exit 1; }

echo "==> synthetic data set ($data)"
"$bin" synth --out "$data" --frames 4000 --seed 1 --val-fraction 0.25 --no-lidar

train() {
  local input=$1 dir="$models/ssd-$input$suffix" mode=--resume
  # A finished model without its checkpoint (the committed ones) cannot be resumed, and train ssd
  # refuses to train over it silently: retrain it only when asked.
  if [[ -f "$dir/model.pt" && ! -f "$dir/checkpoint.pt" ]]; then
    if [[ "$force" != 1 ]]; then
      echo "train-ssd-models: $dir holds a finished model; left alone (SSD_FORCE=1 retrains it)"
      return 0
    fi
    mode=--force
  fi
  "$bin" train ssd --data "$data" --split train --input "$input" --out "$dir" \
    --epochs "$epochs" --seed "$seed" --threads 1 "$mode"
}

mkdir -p "$models"
pids=()
for input in $inputs; do
  name="ssd-$input$suffix"
  echo "==> training $name, seed $seed ($models/$name; log: $models/$name/train_log.csv)"
  if (( parallel > 1 )); then
    train "$input" > "$models/$name.out" 2>&1 &
    pids+=("$!")
  else
    train "$input"
  fi
done
failed=0
for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
(( failed == 0 )) || { echo "train-ssd-models: a training failed; see $models/ssd-*.out" >&2; exit 1; }
echo "train-ssd-models: done; commit $models/ssd-*$suffix/model.json, model.pt, train_log.csv and run.json"
