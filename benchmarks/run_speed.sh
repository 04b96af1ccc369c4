#!/bin/sh
# stereodet run: frames/s and per-stage latency of committed models over one split, decoded frames
# held in memory (--preload: no file reading or PNG decoding in the timed stream) and from the PNG
# files, interleaved in rounds so that a change of the machine's load hits every model alike; the
# ratio to ssd-rgb is per round and per input kind (docs/BENCHMARKS.md, "stereodet run").
#   benchmarks/run_speed.sh BUILD_DIR DATA_DIR [ROUNDS] [THREADS] [FRAMES] [MODELS...]
# DATA_DIR: a `stereodet synth` folder (its val split). MODELS: names under models/ (default
# ssd-rgb ssd-rgbh-learned rpn-rgb rpn-rgbd det3d-lidar det3d-stereo).
set -eu
build=${1:?build dir}; data=${2:?data dir}; rounds=${3:-3}; threads=${4:-2}; frames=${5:-50}
shift $(( $# < 5 ? $# : 5 ))
models=${*:-"ssd-rgb ssd-rgbh-learned rpn-rgb rpn-rgbd det3d-lidar det3d-stereo"}
bin="$build/bin/stereodet"
repo=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
echo "round input model frames_per_s ratio_to_ssd_rgb p50_ms:read,stereo,encode,network,decode,end_to_end p99_end_to_end_ms"
for r in $(seq 1 "$rounds"); do
  for kind in decoded png; do
    flag=""; [ $kind = decoded ] && flag=--preload
    rgb=""
    for m in $models; do
      "$bin" run --model "$repo/models/$m" --data "$data" --split val --max-frames "$frames" \
        --threads "$threads" --out /dev/null --summary "$tmp/$m.json" --warmup 5 --quiet $flag
      line=$(/usr/bin/python3 -c '
import json, sys
s = json.load(open(sys.argv[1]))
st = s["stages"]
p50 = ",".join("%.1f" % st[k]["p50_ms"] if k in st else "-" for k in
               ["read", "stereo", "encode", "network", "decode", "end_to_end"])
print("%.3f %s %.1f" % (s["frames_per_s"], p50, st["end_to_end"]["p99_ms"]))' "$tmp/$m.json")
      fps=${line%% *}
      [ -z "$rgb" ] && [ "$m" = ssd-rgb ] && rgb=$fps
      ratio=$( [ -n "$rgb" ] && echo "scale=3; $fps / $rgb" | bc || echo "-")
      echo "$r $kind $m $fps $ratio ${line#* }"
    done
  done
done
