#!/bin/sh
# cli.run.*: `stereodet run` over the 3 fresh synthetic frames of the models.detector_data fixture.
#   families: for a model of each family (RGB-H, RGB-D, LiDAR 3D) and both 3D inputs, the KITTI
#     files of `run --kitti-out` are byte for byte those of `detect --batch-size 1`; every JSON
#     line is one frame with its latency; the summary has the stages.
#   sequences: the same frames as two image folders and one calib file give the same files.
#   stop: SIGINT during a --realtime replay ends with exit 0, whole lines only, "interrupted".
#   refusals: a LiDAR model on image folders; a calibration that does not fit; an --out that is
#     not a stream of run's.
# Prints one line per check and "ok". Usage: run_test.sh STEREODET REPO DATA POINTS WORK CHECK
set -eu
bin=$1 repo=$2 data=$3 points=$4 work=$5 check=$6
rm -rf "$work"
mkdir -p "$work"
q=--quiet

lines_ok() {  # FILE N: N lines, each a JSON object with index, objects and latency_ms
  /usr/bin/python3 -c '
import json, sys
lines = open(sys.argv[1]).read().split("\n")
assert lines[-1] == "", "the last line is not whole"
frames = [json.loads(l) for l in lines[:-1]]
assert len(frames) == int(sys.argv[2]), (len(frames), sys.argv[2])
for i, f in enumerate(frames):
    assert f["index"] == i and "latency_ms" in f and "end_to_end" in f["latency_ms"], f
    assert "error" not in f, f["error"]
print(sum(len(f["objects"]) for f in frames))' "$1" "$2"
}

case $check in
families)
  for m in ssd-rgbh-learned rpn-rgbd det3d-lidar det3d-stereo; do
    extra=""
    [ $m = det3d-stereo ] && extra="--points $points"
    "$bin" detect --model "$repo/models/$m" --data "$data" --split val --out "$work/det-$m" \
      --batch-size 1 --threads 2 $q $extra
    # det3d-stereo: detect reads the points folder, run computes the points from the pair with
    # the same settings (those of `stereo --encode points`), frame by frame.
    "$bin" run --model "$repo/models/$m" --data "$data" --split val --out "$work/$m.jsonl" \
      --kitti-out "$work/run-$m" --summary "$work/$m.summary.json" --threads 2 $q
    diff -r -x run.json "$work/det-$m" "$work/run-$m"
    n=$(lines_ok "$work/$m.jsonl" 3)
    grep -q '"tool": "run"' "$work/run-$m/run.json"
    grep -q '"network"' "$work/$m.summary.json"
    echo "same $m ($n objects)"
  done
  ;;
sequences)
  m=ssd-rgbh-learned
  "$bin" detect --model "$repo/models/$m" --data "$data" --split val --out "$work/det" \
    --batch-size 1 --threads 2 $q
  "$bin" run --model "$repo/models/$m" --left "$data/training/image_2" \
    --right "$data/training/image_3" --calib "$data/training/calib/000000.txt" \
    --out "$work/seq.jsonl" --kitti-out "$work/run" --threads 2 $q
  diff -r -x run.json "$work/det" "$work/run"
  echo "same sequences ($(lines_ok "$work/seq.jsonl" 3) objects)"
  ;;
stop)
  # 3 frames at 0.5 frames/s: SIGINT after the first is written, then wait for the exit.
  "$bin" run --model "$repo/models/ssd-rgb" --data "$data" --split val --realtime --fps 0.5 \
    --out "$work/stop.jsonl" --summary "$work/stop.json" --threads 2 $q &
  pid=$!
  for i in $(seq 1 600); do
    [ -s "$work/stop.jsonl" ] && break
    sleep 0.1
  done
  kill -INT $pid
  status=0
  wait $pid || status=$?
  echo "exit $status"
  n=$(wc -l < "$work/stop.jsonl")
  [ "$n" -ge 1 ] && [ "$n" -lt 3 ]
  lines_ok "$work/stop.jsonl" "$n" > /dev/null
  grep -q '"interrupted": true' "$work/stop.json"
  echo "interrupted after $n of 3 frames, whole lines"
  ;;
refusals)
  status=0
  "$bin" run --model "$repo/models/det3d-lidar" --left "$data/training/image_2" $q \
    > /dev/null 2> "$work/err1" || status=$?
  echo "lidar from images: exit $status: $(grep -o 'reads LiDAR scans[^,;]*' "$work/err1")"
  mkdir -p "$work/small/l" "$work/small/r"
  /usr/bin/python3 -c 'import zlib, struct, sys
def png(w, h):
    raw = b"".join(b"\x00" + b"\x80" * (3 * w) for _ in range(h))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")
for side in "lr": open(sys.argv[1] + "/" + side + "/0.png", "wb").write(png(320, 96))' "$work/small"
  status=0
  "$bin" run --model "$repo/models/ssd-rgbh-learned" --left "$work/small/l" \
    --right "$work/small/r" --calib "$data/training/calib/000000.txt" $q \
    > /dev/null 2> "$work/err2" || status=$?
  echo "calibration: exit $status: $(grep -o 'does not fit the images' "$work/err2")"
  echo "someone's notes" > "$work/notes.txt"
  status=0
  "$bin" run --model "$repo/models/ssd-rgb" --data "$data" --split val --out "$work/notes.txt" \
    $q 2> "$work/err3" || status=$?
  echo "foreign --out: exit $status: $(grep -o 'is not a stream `run` wrote' "$work/err3"), $(cat "$work/notes.txt")"
  ;;
esac
echo ok
