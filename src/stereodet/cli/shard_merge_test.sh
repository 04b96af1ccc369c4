#!/bin/sh
# cli.eval.shard_merge: `eval --shard` twice (out of order) and `eval merge` give the summary.csv
# of one run byte for byte. Usage: shard_merge_test.sh STEREODET EVAL_SMALL_DIR WORK_DIR
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
rm -rf "$work"
