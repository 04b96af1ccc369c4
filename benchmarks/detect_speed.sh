#!/bin/sh
# detect ssd end to end: RGB vs RGB-H frames/s in one run, interleaved (docs/BENCHMARKS.md,
# "detect ssd: RGB-H vs RGB"). Each round runs every (model, loop) pair once, in turn, so a change
# of the machine's load hits all of them alike; the ratio per round is RGB-H / RGB.
#   benchmarks/detect_speed.sh BUILD_DIR DATA_DIR [ROUNDS] [THREADS] [SPLIT]
# DATA_DIR: a `stereodet synth` folder (1242 x 375 frames); the models are the committed ones.
set -eu
build=${1:?build dir}; data=${2:?data dir}; rounds=${3:-3}; threads=${4:-2}; split=${5:-val}
bin="$build/bin/stereodet"
repo=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
run() {  # model loop -> frames/s
  flag=""; [ "$2" = sequential ] && flag="--no-pipeline"
  "$bin" detect ssd --model "$repo/models/ssd-$1" --data "$data" --split "$split" \
      --out "$tmp/det-$1-$2" --threads "$threads" $flag 2>&1 |
    sed -n 's/.* \([0-9.]*\) images\/s.*/\1/p'
}
echo "round model loop frames_per_s"
for r in $(seq 1 "$rounds"); do
  for loop in pipelined sequential; do
    rgb=$(run rgb $loop); rgbh=$(run rgbh-learned $loop)
    echo "$r rgb $loop $rgb"
    echo "$r rgbh-learned $loop $rgbh"
    echo "$r ratio $loop $(echo "$rgbh / $rgb" | bc -l | cut -c1-5)"
  done
done
