#!/bin/sh
# cli.detect.shard_merge: `detect ssd|det3d|rpn --shard` twice (out of order) and `detect merge` give
# the detection folder of one run: every ID.txt byte for byte, run.json but its command line; a
# merge with a shard missing is refused naming it. One shard of one (`--shard 0/1`, what
# stereodet.scale runs when the frames fit in one task) merges the same.
# Usage: detect_shard_test.sh STEREODET PROV_DIR WORK_DIR
set -eu
bin=$1 prov=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
printf '000000\n000001\n' > "$work/all.txt"
same_run() {  # one run's folder $1 against the merge $2
  for f in "$1"/*.txt; do cmp "$f" "$2/$(basename "$f")"; done
  for d in "$1" "$2"; do
    [ "$(ls "$d" | wc -l)" -eq 3 ] || { echo "$d: not two frames and run.json"; exit 1; }
  done
  grep -v '"command_line"' "$1/run.json" > "$work/a.json"
  grep -v '"command_line"' "$2/run.json" > "$work/b.json"
  cmp "$work/a.json" "$work/b.json"
}
for family in ssd det3d rpn; do
  model=$prov/model
  [ "$family" = det3d ] && model=$prov/det3d_model
  [ "$family" = rpn ] && model=$prov/rpn_model
  detect() {
    "$bin" detect "$family" --model "$model" --data "$prov/data" --split "$work/all.txt" \
      --threads 1 --batch-size 1 --score-threshold 0 --quiet "$@"
  }
  detect --out "$work/$family-one"
  detect --shard 1/2 --out "$work/$family-s1"
  detect --shard 0/2 --out "$work/$family-s0"
  "$bin" detect merge "$work/$family-s1" "$work/$family-s0" --out "$work/$family-merged" --quiet
  same_run "$work/$family-one" "$work/$family-merged"
  echo "$family identical"
  detect --shard 0/1 --out "$work/$family-only"
  "$bin" detect merge "$work/$family-only" --out "$work/$family-merged-one" --quiet
  same_run "$work/$family-one" "$work/$family-merged-one"
  echo "$family one shard identical"
done
"$bin" detect merge "$work/ssd-s0" --out "$work/refused" 2>&1 || echo "exit=$?"
rm -rf "$work"
