#!/bin/sh
# cli.eval.shard_merge: `eval --shard` twice (out of order) and `eval merge` give the summary.csv
# of one run byte for byte, and `eval sweep --shards` the sweep of one run; so does one shard of
# one (`--shard 0/1`, what stereodet.scale runs when the frames fit in one task).
# Usage: shard_merge_test.sh STEREODET EVAL_SMALL_DIR WORK_DIR
set -eu
bin=$1 data=$2 work=$3
rm -rf "$work"
eval_car() { "$bin" eval --gt "$data" --det "$data/det" --metrics 2d --classes Car "$@"; }
eval_car --out "$work/whole" > /dev/null
eval_car --shard 1/2 --out "$work/s1" > /dev/null
eval_car --shard 0/2 --out "$work/s0" > /dev/null
"$bin" eval merge "$work/s1" "$work/s0" --out "$work/merged" --metrics 2d --classes Car
cmp "$work/whole/summary.csv" "$work/merged/summary.csv"
echo summary-identical
eval_car --shard 0/1 --out "$work/only" > /dev/null
"$bin" eval merge "$work/only" --out "$work/merged-one" --metrics 2d --classes Car > /dev/null
cmp "$work/whole/summary.csv" "$work/merged-one/summary.csv"
echo one-shard-identical
sweep() { "$bin" eval sweep --filter min-area --to 400 --step 100 --metrics 2d --classes Car "$@"; }
sweep --gt "$data" --det "$data/det" --out "$work/sweep-whole" > /dev/null
sweep --shards "$work/s1" "$work/s0" --out "$work/sweep-shards" > /dev/null
cmp "$work/sweep-whole/sweep.csv" "$work/sweep-shards/sweep.csv"
[ "$(wc -l < "$work/sweep-whole/sweep.csv")" -gt 5 ]
echo sweep-identical
rm -rf "$work"
