#!/bin/bash
# CPU time of the whole `stereodet eval` process with everything issue 37 added (LET kinds,
# distance breakdown, naive bins, calibration terms, error analysis) against plain `eval`, side by
# side on one KITTI-val-sized random set (figures in docs/BENCHMARKS.md, "eval with everything").
#
#   benchmarks/eval_all_speed.sh BUILD_DIR [WORK_DIR]
#
# BUILD_DIR: a stereodet build folder with bin/stereodet and benchmarks/write_eval_set
#            (cmake --build BUILD_DIR --target stereodet write_eval_set).
# WORK_DIR:  scratch folder (default: a new one under /tmp), left in place.
# Environment: FRAMES (3769), SEED (2024), ROUNDS (5: each round runs every variant once, in turn,
# so that the machine's load falls on all alike), MATCHER (optimal), STEREODET (default
# BUILD_DIR/bin/stereodet), BASELINE (another stereodet binary, e.g. one built from the commit
# before issue 37, run as the variant "plain (baseline)"; default none), THREADS (default 0).
#
# Variants, each writing its results folder (--out, with --report off):
#   plain:      --metrics 2d,bev,3d (what eval did before issue 37 asked for more, plus the
#               calibration terms every cell now has: LaECE and D-ECE)
#   let:        --metrics 2d,bev,3d,let-bev,let-3d
#   standard:   let + --breakdown distance=0,30,50,inf (issue 37's run: every kind, AP by range)
#   everything: standard + --breakdown occlusion=0,1,2,3 --breakdown-naive
#   errors:     let + --errors (the TIDE-style analysis: up to 8 re-evaluations of every cell)
# CPU time = user + sys of the process (/usr/bin/time); the median of the rounds is printed, and
# each variant's ratio to plain (and to the baseline's plain, with BASELINE), as the ratio of the
# medians and as the median of each round's own ratio (paired: a round's variants run within
# seconds of each other, so a slow spell of the shared machine falls on both sides of its ratio).
set -euo pipefail

if [ $# -lt 1 ]; then
  sed -n '2,26p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
build=$(cd "$1" && pwd)
work=${2:-$(mktemp -d /tmp/eval_all_speed.XXXXXX)}
mkdir -p "$work"
work=$(cd "$work" && pwd)
frames=${FRAMES:-3769}
seed=${SEED:-2024}
rounds=${ROUNDS:-5}
matcher=${MATCHER:-optimal}
threads=${THREADS:-0}
stereodet=${STEREODET:-$build/bin/stereodet}
writer=$build/benchmarks/write_eval_set
[ -x "$writer" ] || writer=$build/bin/write_eval_set
[ -x "$stereodet" ] || { echo "eval_all_speed: $stereodet not built" >&2; exit 1; }
[ -x "$writer" ] || { echo "eval_all_speed: write_eval_set not built" >&2; exit 1; }

set_dir="$work/set"
if [ ! -d "$set_dir/label_2" ]; then
  "$writer" --frames "$frames" --seed "$seed" --out "$set_dir" > /dev/null
fi
common=(--gt "$set_dir/label_2" --det "$set_dir/det" --matcher "$matcher" --threads "$threads")

declare -A times
run() {  # run NAME BINARY ARGS...
  local name=$1 binary=$2
  shift 2
  local out="$work/out-${name// /_}"
  /usr/bin/time -f "%U %S" -o "$work/time" "$binary" eval "${common[@]}" "$@" --out "$out" \
    > /dev/null
  local t
  t=$(awk '{printf "%.3f", $1 + $2}' "$work/time")
  times[$name]+="$t "
}

variants=(plain let standard everything errors)
for ((r = 1; r <= rounds; ++r)); do
  run plain "$stereodet" --metrics 2d,bev,3d
  run let "$stereodet" --metrics 2d,bev,3d,let-bev,let-3d
  run standard "$stereodet" --metrics 2d,bev,3d,let-bev,let-3d --breakdown distance=0,30,50,inf
  run everything "$stereodet" --metrics 2d,bev,3d,let-bev,let-3d \
    --breakdown distance=0,30,50,inf --breakdown occlusion=0,1,2,3 --breakdown-naive
  run errors "$stereodet" --metrics 2d,bev,3d,let-bev,let-3d --errors
  if [ -n "${BASELINE:-}" ]; then
    run "plain (baseline)" "$BASELINE" --metrics 2d,bev,3d
  fi
done

median() { tr ' ' '\n' | grep -v '^$' | sort -g | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }
printf "%s frames (seed %s), matcher %s, %s rounds; CPU seconds (user + sys), median\n" \
  "$frames" "$seed" "$matcher" "$rounds"
plain=$(echo "${times[plain]}" | median)
base=""
[ -n "${BASELINE:-}" ] && base=$(echo "${times["plain (baseline)"]}" | median)
# The median over rounds of a variant's time over another's in the same round.
paired() {  # paired NAME REFERENCE_NAME
  paste -d' ' <(echo "${times[$1]}" | tr ' ' '\n' | grep -v '^$') \
    <(echo "${times[$2]}" | tr ' ' '\n' | grep -v '^$') |
    awk '{printf "%.4f\n", $1 / $2}' | median
}
for name in "plain (baseline)" "${variants[@]}"; do
  [ -n "${times[$name]:-}" ] || continue
  t=$(echo "${times[$name]}" | median)
  printf "  %-18s %6s  x%s plain%s  (rounds: %s)\n" "$name" "$t" \
    "$(awk -v a="$t" -v p="$plain" 'BEGIN {printf "%.2f", a / p}')" \
    "$([ -n "$base" ] && awk -v a="$t" -v p="$base" 'BEGIN {printf ", x%.2f the baseline", a / p}')" \
    "${times[$name]}"
done
echo "Paired (median over rounds of each round's ratio):"
for name in "${variants[@]}"; do
  printf "  %-18s x%.2f plain%s\n" "$name" "$(paired "$name" plain)" \
    "$([ -n "$base" ] && printf ", x%.2f the baseline" "$(paired "$name" "plain (baseline)")")"
done
