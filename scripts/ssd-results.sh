#!/usr/bin/env bash
# The measurements of docs/RESULTS.md: each committed detector (models/ssd-*) on the val split of the
# synthetic set, sharp and with the network's image blurred (sigma 5 px, stereo stays sharp),
# evaluated in 2D with the KITTI-compatible and the optimal matcher; then one Markdown table.
# Usage: scripts/ssd-results.sh BUILD_DIR [DATA_DIR] [MODELS_DIR] [OUT_DIR]
#   SSD_INPUTS="rgb rgbh-fixed rgbh-learned"   SSD_BLURS="0 5"   SSD_THREADS=0 (all cores)
#   SSD_TABLE_ONLY=1: only rebuild the table from the results already there
# Writes OUT_DIR/MODEL/blurS/{detections/, eval-kitti/, eval-optimal/} and OUT_DIR/table.md.
set -euo pipefail
build_dir=${1:-build}
data=${2:-data/synth}
models=${3:-models}
out=${4:-results/ssd}
inputs=${SSD_INPUTS:-rgb rgbh-fixed rgbh-learned}
blurs=${SSD_BLURS:-0 5}
threads=${SSD_THREADS:-0}
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "ssd-results: $bin not built; run make build" >&2; exit 1; }

for input in $inputs; do
  [[ -n "${SSD_TABLE_ONLY:-}" ]] && break
  [[ -f "$models/ssd-$input/model.pt" ]] ||
    { echo "ssd-results: $models/ssd-$input/model.pt missing; run make models" >&2; exit 1; }
  for blur in $blurs; do
    run="$out/ssd-$input/blur$blur"
    echo "==> ssd-$input, blur sigma $blur px ($run)"
    "$bin" detect ssd --model "$models/ssd-$input" --data "$data" --split val --out "$run/detections" \
      --blur-sigma "$blur" --threads "$threads" --quiet
    for matcher in kitti optimal; do
      "$bin" eval --gt "$data" --det "$run/detections" --split val --metrics 2d --matcher "$matcher" \
        --threads "$threads" --out "$run/eval-$matcher" > "$run/eval-$matcher.txt"
    done
  done
done

python3 - "$out" $inputs -- $blurs > "$out/table.md.tmp" <<'PY'
import json, sys
out = sys.argv[1]
sep = sys.argv.index("--")
inputs, blurs = sys.argv[2:sep], sys.argv[sep + 1:]

def load(input_, blur, matcher):
    with open(f"{out}/ssd-{input_}/blur{blur}/eval-{matcher}/results.json") as f:
        return {(r["class"], r["difficulty"]): r for r in json.load(f)["results"] if r["metric"] == "2d"}

classes = ["Car", "Pedestrian", "Cyclist"]
print("| model | blur sigma (px) | class | labels (moderate) | AP_R40 KITTI | AP_R11 KITTI | AP_R40 optimal "
      "| Brier over labels (optimal) |")
print("|---|---:|---|---:|---:|---:|---:|---:|")
for blur in blurs:
    for input_ in inputs:
        kitti, optimal = load(input_, blur, "kitti"), load(input_, blur, "optimal")
        for c in classes:
            k, o = kitti.get((c, "Moderate")), optimal.get((c, "Moderate"))
            if k is None or o is None:
                continue
            # results.json holds AP in percent, like KITTI's tool; the table uses fractions (the paper's).
            print(f"| ssd-{input_} | {blur} | {c} | {k['num_valid_labels']} | {k['ap_r40'] / 100:.3f} | "
                  f"{k['ap_r11'] / 100:.3f} | {o['ap_r40'] / 100:.3f} | {o['brier']['over_labels']:.3f} |")
PY
mv "$out/table.md.tmp" "$out/table.md"
cat "$out/table.md"
