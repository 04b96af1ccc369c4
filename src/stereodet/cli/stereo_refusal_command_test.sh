#!/bin/sh
# cli.prov.stereo_refusal_command: when `detect ssd` refuses a `--stereo DIR` made with other
# settings than the model's, the command it prints makes a folder that the same run then accepts.
# Runs the printed command as printed (NEW_FOLDER replaced), then the refused run again on its
# output. Prints "detect ok". (`train ssd --stereo DIR` takes the folder's settings: its stereo
# flags exclude --stereo, so it has nothing to refuse.)
# Usage: stereo_refusal_command_test.sh STEREODET PROV_DIR WORK_DIR
set -eu
bin=$1 prov=$2 work=$3
rm -rf "$work"
mkdir -p "$work"

# The `stereodet stereo ...` command between backquotes in the error, with NEW_FOLDER made $2.
printed_command() {
  printf '%s\n' "$1" | sed -n 's/.*`stereodet \(stereo [^`]*\)`.*/\1/p' | sed "s|NEW_FOLDER|$2|"
}

# A model matched at 32 disparities; a folder of the default 128 is refused.
model=$work/model
"$bin" train ssd --data "$prov/data" --split train --input rgbh-fixed --out "$model" \
  --num-disparities 32 --epochs 1 --width 128 --height 40 --batch-size 1 --threads 1 --quiet
"$bin" stereo --data "$prov/data" --split val --out "$work/stereo-default" --quiet
if error=$("$bin" detect ssd --model "$model" --data "$prov/data" --split val --threads 1 \
  --out "$work/det-refused" --stereo "$work/stereo-default" --quiet 2>&1); then
  echo "detect accepted a folder of other settings"; exit 1
fi
command=$(printed_command "$error" "$work/stereo-made")
[ -n "$command" ] || { echo "no command in: $error"; exit 1; }
# shellcheck disable=SC2086  # the printed command is split as a shell would split it
"$bin" $command --quiet
"$bin" detect ssd --model "$model" --data "$prov/data" --split val --threads 1 \
  --out "$work/det-made" --stereo "$work/stereo-made" --quiet
echo "detect ok"
