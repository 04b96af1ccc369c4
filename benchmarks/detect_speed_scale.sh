#!/bin/sh
# detect ssd end to end at the two match scales (docs/BENCHMARKS.md, "Matching at the network's
# scale"): RGB, the committed RGB-H model (matching at full size) and a copy of it whose model.json
# records "match_scale": 0.5, pipelined (the default), images/s and process CPU time, every variant
# once per round, in turn. Short: ROUNDS x 3 runs of FRAMES frames.
#   benchmarks/detect_speed_scale.sh BUILD_DIR DATA_DIR [THREADS] [FRAMES] [ROUNDS]
set -eu
build=${1:?build dir}; data=${2:?data dir}; threads=${3:-2}; frames=${4:-24}; rounds=${5:-3}
bin="$build/bin/stereodet"
repo=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d); trap 'rm -rf "$tmp"' EXIT
cp -r "$repo/models/ssd-rgbh-learned" "$tmp/half"
/usr/bin/python3 - "$tmp/half/model.json" <<'PY'
import json, sys
path = sys.argv[1]
model = json.load(open(path))
model.setdefault("stereo", {}).setdefault("disparity", {})["match_scale"] = 0.5
json.dump(model, open(path, "w"), indent=2)
PY
echo "round variant threads images_per_s cpu_user_s cpu_sys_s"
for r in $(seq 1 "$rounds"); do
  for v in rgb rgbh half; do
    case $v in
      rgb) m="$repo/models/ssd-rgb" ;;
      rgbh) m="$repo/models/ssd-rgbh-learned" ;;
      half) m="$tmp/half" ;;
    esac
    rm -rf "$tmp/det"
    /usr/bin/time -f "cpu %U %S" "$bin" detect ssd --model "$m" --data "$data" --split val \
        --out "$tmp/det" --threads "$threads" --max-frames "$frames" 2>&1 |
      sed -n "s/.* \([0-9.]*\) images\/s.*/\1/p; s/^cpu \(.*\)/\1/p" | tr '\n' ' ' |
      sed "s/^/$r $v $threads /"
    echo
  done
done
