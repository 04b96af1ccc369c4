#!/bin/sh
# detect ssd end to end: RGB vs RGB-H frames/s in one run, interleaved (docs/BENCHMARKS.md,
# "detect ssd: RGB-H vs RGB"). Each round runs every variant once, in turn, so a change of the
# machine's load hits all of them alike; the ratios are per round, against RGB with the same loop.
#   benchmarks/detect_speed.sh BUILD_DIR DATA_DIR [ROUNDS] [THREADS] [MAX_FRAMES] [STEREO_DIR]
# DATA_DIR: a `stereodet synth` folder (1242 x 375 frames), its val split; the models are the
# committed ones. STEREO_DIR (optional): `stereodet stereo --data DATA_DIR --split val` with the
# default settings, for the RGB-H run that reads its heights (--stereo) instead of matching.
# The rgbh-learned-half variants run a copy of the committed RGB-H model whose model.json records
# "match_scale": 0.5 (matching at 621 x 188, what a new RGB-H training records by default, issue
# 19): the speed does not depend on the weights, and detect uses the recorded setting.
set -eu
build=${1:?build dir}; data=${2:?data dir}; rounds=${3:-3}; threads=${4:-2}; frames=${5:-0}
stereo=${6:-}
bin="$build/bin/stereodet"
repo=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cp -r "$repo/models/ssd-rgbh-learned" "$tmp/ssd-rgbh-learned-half"
/usr/bin/python3 - "$tmp/ssd-rgbh-learned-half/model.json" <<'PY'
import json, sys
path = sys.argv[1]
model = json.load(open(path))
# Absent keys read as their defaults (StereoOptionsFromJson): only the scale is recorded here.
model.setdefault("stereo", {}).setdefault("disparity", {})["match_scale"] = 0.5
json.dump(model, open(path, "w"), indent=2)
PY
run() {  # model variant [flags] -> frames/s
  model=$1; variant=$2; shift 2
  dir="$repo/models/ssd-$model"; [ -d "$dir" ] || dir="$tmp/ssd-$model"
  "$bin" detect ssd --model "$dir" --data "$data" --split val \
      --out "$tmp/det-$model-$variant" --threads "$threads" --max-frames "$frames" "$@" 2>&1 |
    sed -n 's/.* \([0-9.]*\) images\/s.*/\1/p'
}
ratio() { echo "$1 / $2" | bc -l | cut -c1-5; }
echo "round variant frames_per_s ratio_to_rgb"
for r in $(seq 1 "$rounds"); do
  rgb=$(run rgb pipelined); rgbh=$(run rgbh-learned pipelined)
  half=$(run rgbh-learned-half pipelined)
  rgb_seq=$(run rgb sequential --no-pipeline); rgbh_seq=$(run rgbh-learned sequential --no-pipeline)
  half_seq=$(run rgbh-learned-half sequential --no-pipeline)
  echo "$r rgb-pipelined $rgb 1"
  echo "$r rgbh-learned-pipelined $rgbh $(ratio "$rgbh" "$rgb")"
  echo "$r rgbh-learned-half-pipelined $half $(ratio "$half" "$rgb")"
  echo "$r rgb-sequential $rgb_seq 1"
  echo "$r rgbh-learned-sequential $rgbh_seq $(ratio "$rgbh_seq" "$rgb_seq")"
  echo "$r rgbh-learned-half-sequential $half_seq $(ratio "$half_seq" "$rgb_seq")"
  if [ -n "$stereo" ]; then
    rgbh_dir=$(run rgbh-learned stereo-dir --stereo "$stereo")
    echo "$r rgbh-learned-stereo-dir-pipelined $rgbh_dir $(ratio "$rgbh_dir" "$rgb")"
  fi
done
