#!/bin/sh
# cli.detect.calibration: `detect ssd --calibration FILE` writes each Car with sigmoid(2 logit(s))
# of the score s it has without (tests/data/calibration/car_platt.json), every other field the
# same, and lists the file among run.json's inputs; `run --score-calibration FILE --kitti-out`
# the same against its own raw files; a file that is not a calibration is refused before anything
# is written. On the 3 frames of the models.detector_data fixture.
# Usage: detect_calibration_test.sh STEREODET REPO DATA WORK
set -eu
bin=$1 repo=$2 data=$3 work=$4
rm -rf "$work"
mkdir -p "$work"
"$bin" detect ssd --model "$repo/models/ssd-rgb" --data "$data" --split val --out "$work/raw" \
  --quiet
"$bin" detect ssd --model "$repo/models/ssd-rgb" --data "$data" --split val --out "$work/cal" \
  --quiet --calibration "$repo/tests/data/calibration/car_platt.json"
"$bin" run --model "$repo/models/ssd-rgb" --data "$data" --split val --out "$work/run-raw.jsonl" \
  --kitti-out "$work/run-raw" --quiet
"$bin" run --model "$repo/models/ssd-rgb" --data "$data" --split val --out "$work/run-cal.jsonl" \
  --kitti-out "$work/run-cal" --quiet --score-calibration "$repo/tests/data/calibration/car_platt.json"
/usr/bin/python3 - "$work/raw" "$work/cal" "$work/run-raw" "$work/run-cal" <<'PY'
import math, pathlib, sys
n = 0
for raw, cal in ((sys.argv[1], sys.argv[2]), (sys.argv[3], sys.argv[4])):
    raw, cal = pathlib.Path(raw), pathlib.Path(cal)
    for f in sorted(raw.glob("*.txt")):
        lines = zip(f.read_text().splitlines(), (cal / f.name).read_text().splitlines(), strict=True)
        for a, b in lines:
            a, b = a.split(), b.split()
            assert a[:-1] == b[:-1], (f.name, a, b)
            s = float(a[-1])
            want = s if a[0] != "Car" else 1 / (1 + math.exp(-2 * math.log(s / (1 - s))))
            assert abs(float(b[-1]) - want) < 1e-6 * max(1.0, want), (f.name, s, b[-1], want)
            n += 1
assert n > 0
print(f"calibrated {n} objects")
PY
grep -q '"--calibration"' "$work/cal/run.json"
if "$bin" detect ssd --model "$repo/models/ssd-rgb" --data "$data" --split val \
     --out "$work/bad" --quiet --calibration "$repo/tests/data/eval_small/README.md" 2> "$work/err"; then
  echo "a file that is not a calibration was accepted"; exit 1
fi
grep -q "README.md: not JSON" "$work/err"
[ ! -e "$work/bad" ]
echo ok
