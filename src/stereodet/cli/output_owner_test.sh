#!/bin/sh
# cli.prov.output_owners: every command that writes a folder, pointed with --out at the folder of
# every other command, at a trained model, at a KITTI download (no synth_settings.txt) and its
# training/ folder, and at a folder of someone's files, exits 1 naming what it found, and leaves
# that folder exactly as it was (every file's bytes, no file added or removed). Then each command
# replaces or resumes its own folder. Prints one "refused CMD -> FOLDER" line per case and "ok".
# Usage: output_owner_test.sh STEREODET PROV_DIR WORK_DIR
set -eu
bin=$1 prov=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
q=--quiet

# The folders, each made by its own command (the model and data by the prov fixtures).
mkdir -p "$work/kitti"
cp -r "$prov/data/training" "$prov/data/ImageSets" "$work/kitti/"  # a download: no marker
mkdir -p "$work/home" && echo precious > "$work/home/thesis.tex"
cp -r "$prov/model" "$work/model"
# Each command's own folder; run again at the end, each replaces or resumes its own.
own_folders() {
  "$bin" detect ssd --model "$work/model" --data "$prov/data" --split val --out "$work/detect" \
    --threads 1 $q
  "$bin" eval --gt "$prov/data" --split val --det "$work/detect" --out "$work/eval" > /dev/null
  "$bin" report "$work/eval" --out "$work/report" > /dev/null
  "$bin" stereo --data "$prov/data" --split val --out "$work/stereo" --encode points \
    --num-disparities 32 $q
  "$bin" synth --out "$work/synth" --frames 1 --width 160 --height 48 --seed 3 --threads 1 $q \
    > /dev/null
}
own_folders
for k in 0 1; do
  "$bin" detect ssd --model "$work/model" --data "$prov/data" --split "$prov/data/ImageSets/trainval.txt" \
    --shard $k/2 --batch-size 1 --out "$work/shard$k" --threads 1 $q
done

snapshot() {  # every file under $1 with its bytes' hash, hidden ones included
  (cd "$1" && find . -type f -exec md5sum {} + | LC_ALL=C sort)
}

# The command $2... with every argument OUT replaced by the folder $1.
run_into() {
  target=$1
  shift
  for a in "$@"; do
    shift
    if [ "$a" = OUT ]; then set -- "$@" "$target"; else set -- "$@" "$a"; fi
  done
  "$bin" "$@"
}

# CMD_NAME then the command with OUT where --out goes.
try() {
  name=$1
  shift
  for target in detect eval report stereo synth model kitti kitti/training home; do
    case "$name:$target" in
      detect*:detect | eval:eval | report:report | stereo:stereo | synth:synth | train:model) continue ;;
    esac
    before=$(snapshot "$work/$target")
    set +e
    out=$(run_into "$work/$target" "$@" 2>&1)
    code=$?
    set -e
    [ "$code" -eq 1 ] || { echo "$name -> $target: exit $code, not 1: $out"; exit 1; }
    echo "$out" | grep -q "replaces or writes into only a folder that" ||
      echo "$out" | grep -q "is inside the input\|is the input\|holds the input" ||
      { echo "$name -> $target: not an ownership error: $out"; exit 1; }
    [ "$(snapshot "$work/$target")" = "$before" ] || { echo "$name -> $target: changed"; exit 1; }
    echo "refused $name -> $target"
  done
}

try "detect ssd" detect ssd --model "$work/model" --data "$prov/data" --split val --out OUT \
  --threads 1 $q
try "detect merge" detect merge "$work/shard0" "$work/shard1" --out OUT $q
try train train ssd --data "$prov/data" --split train --input rgb --out OUT --epochs 1 \
  --width 128 --height 40 --batch-size 1 --threads 1 --force $q
try stereo stereo --data "$prov/data" --split val --out OUT --encode points --num-disparities 32 $q
try synth synth --out OUT --frames 1 --width 160 --height 48 --seed 3 --threads 1 $q
try eval eval --gt "$prov/data" --split val --det "$work/detect" --out OUT
try report report "$work/eval" --out OUT

# Each command replaces or resumes its own folder.
own_folders
rm -rf "$work"
echo ok
