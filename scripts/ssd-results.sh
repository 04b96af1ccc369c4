#!/usr/bin/env bash
# The measurements of docs/RESULTS.md for the image detectors: each committed model of a family
# (models/ssd-* or models/rpn-*) on the val split of the synthetic set, sharp and with the
# network's image blurred (sigma 5 px, stereo stays sharp), evaluated in 2D with the
# KITTI-compatible and the optimal matcher; then one Markdown table with the parameter counts and
# the detection speed (whole `detect` process, model loading included).
# Usage: scripts/ssd-results.sh BUILD_DIR [DATA_DIR] [MODELS_DIR] [OUT_DIR]
#   RESULTS_FAMILY=ssd (or rpn)   RESULTS_INPUTS: default "rgb rgbh-fixed rgbh-learned" for ssd,
#   "rgb rgbd" for rpn (add rgb-wide for the widened control)   SSD_BLURS="0 5"
#   SSD_THREADS=0 (all cores)   SSD_TABLE_ONLY=1: only rebuild the table from the results there
# Writes OUT_DIR/FAMILY-INPUT/blurS/{detections/, eval-kitti/, eval-optimal/, detect_seconds.txt}
# and OUT_DIR/table.md.
set -euo pipefail
build_dir=${1:-build}
data=${2:-data/synth}
models=${3:-models}
family=${RESULTS_FAMILY:-ssd}
out=${4:-results/$family}
case "$family" in
  ssd) default_inputs="rgb rgbh-fixed rgbh-learned"; train_target="make models" ;;
  rpn) default_inputs="rgb rgbd"; train_target="make rpn-models" ;;
  *) echo "ssd-results: RESULTS_FAMILY is ssd or rpn, got '$family'" >&2; exit 1 ;;
esac
inputs=${RESULTS_INPUTS:-${SSD_INPUTS:-$default_inputs}}
blurs=${SSD_BLURS:-0 5}
threads=${SSD_THREADS:-0}
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "ssd-results: $bin not built; run make build" >&2; exit 1; }

for input in $inputs; do
  [[ -n "${SSD_TABLE_ONLY:-}" ]] && break
  [[ -f "$models/$family-$input/model.pt" ]] ||
    { echo "ssd-results: $models/$family-$input/model.pt missing; run $train_target" >&2; exit 1; }
  for blur in $blurs; do
    run="$out/$family-$input/blur$blur"
    echo "==> $family-$input, blur sigma $blur px ($run)"
    start=$(date +%s.%N)
    "$bin" detect "$family" --model "$models/$family-$input" --data "$data" --split val \
      --out "$run/detections" --blur-sigma "$blur" --threads "$threads" --quiet
    awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.3f\n", b - a }' > "$run/detect_seconds.txt"
    for matcher in kitti optimal; do
      "$bin" eval --gt "$data" --det "$run/detections" --split val --metrics 2d --matcher "$matcher" \
        --threads "$threads" --out "$run/eval-$matcher" > "$run/eval-$matcher.txt"
    done
  done
done

python3 - "$out" "$family" "$models" $inputs -- $blurs > "$out/table.md.tmp" <<'PY'
import json, os, sys
out, family, models = sys.argv[1:4]
sep = sys.argv.index("--")
inputs, blurs = sys.argv[4:sep], sys.argv[sep + 1:]

def load(input_, blur, matcher):
    with open(f"{out}/{family}-{input_}/blur{blur}/eval-{matcher}/results.json") as f:
        return {(r["class"], r["difficulty"]): r for r in json.load(f)["results"] if r["metric"] == "2d"}

def parameters(input_):
    """The model's parameter count: model.json's weights record, else run.json's (the trainer's)."""
    for name in ("model.json", "run.json"):
        path = f"{models}/{family}-{input_}/{name}"
        if os.path.exists(path):
            with open(path) as f:
                j = json.load(f)
            n = j.get("weights", {}).get("parameters") or j.get("settings", {}).get("parameters")
            if n:
                return f"{n:,}"
    return "n/a"

def speed(input_, blur, frames):
    path = f"{out}/{family}-{input_}/blur{blur}/detect_seconds.txt"
    if not os.path.exists(path) or not frames:
        return "n/a"
    with open(path) as f:
        return f"{frames / float(f.read()):.1f}"

classes = ["Car", "Pedestrian", "Cyclist"]
print("| model | parameters | blur sigma (px) | class | labels (moderate) | AP_R40 KITTI | AP_R11 KITTI "
      "| AP_R40 optimal | Brier over labels (optimal) | detect images/s |")
print("|---|---:|---:|---|---:|---:|---:|---:|---:|---:|")
for blur in blurs:
    for input_ in inputs:
        kitti, optimal = load(input_, blur, "kitti"), load(input_, blur, "optimal")
        with open(f"{out}/{family}-{input_}/blur{blur}/detections/run.json") as f:
            frames = len(json.load(f)["frames"])
        for c in classes:
            k, o = kitti.get((c, "Moderate")), optimal.get((c, "Moderate"))
            if k is None or o is None:
                continue
            # results.json holds AP in percent, like KITTI's tool; the table uses fractions (the paper's).
            print(f"| {family}-{input_} | {parameters(input_)} | {blur} | {c} | {k['num_valid_labels']} | "
                  f"{k['ap_r40'] / 100:.3f} | {k['ap_r11'] / 100:.3f} | {o['ap_r40'] / 100:.3f} | "
                  f"{o['brier']['over_labels']:.3f} | {speed(input_, blur, frames)} |")
PY
mv "$out/table.md.tmp" "$out/table.md"
cat "$out/table.md"
