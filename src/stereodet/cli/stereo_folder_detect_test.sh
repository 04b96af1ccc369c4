#!/bin/sh
# cli.prov.detect_stereo_folder_same_bytes: `detect ssd --stereo DIR` gives the bytes of matching
# every frame in line, for both RGB-H encodings, at match scales 1 and 0.5, from a folder written
# with --encode rgbh and one written with --encode rgbd (they hold the heights differently).
# A tiny model per encoding and scale (1 frame, 1 epoch), score threshold 0 so that every frame
# has boxes to differ in. Prints "same ENCODING SCALE FOLDER" per case.
# Usage: stereo_folder_detect_test.sh STEREODET PROV_DIR WORK_DIR
set -eu
bin=$1 prov=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
for encoding in rgbh-fixed rgbh-learned; do
  for scale in 1 0.5; do
    model=$work/model-$encoding-$scale
    "$bin" train ssd --data "$prov/data" --split train --input "$encoding" --out "$model" \
      --num-disparities 32 --match-scale "$scale" --epochs 1 --width 128 --height 40 \
      --batch-size 1 --threads 1 --quiet
    detect() {
      "$bin" detect ssd --model "$model" --data "$prov/data" --split val --threads 1 \
        --score-threshold 0 --quiet "$@"
    }
    detect --out "$work/inline"
    [ "$(cat "$work"/inline/*.txt | wc -l)" -gt 0 ] || { echo "no detections to compare"; exit 1; }
    for folder in rgbh rgbd; do
      "$bin" stereo --data "$prov/data" --split val --out "$work/stereo-$folder" \
        --encode "$folder" --num-disparities 32 --match-scale "$scale" --quiet
      detect --stereo "$work/stereo-$folder" --out "$work/from-folder"
      for f in "$work"/inline/*.txt; do cmp "$f" "$work/from-folder/$(basename "$f")"; done
      echo "same $encoding $scale $folder"
      rm -rf "$work/stereo-$folder" "$work/from-folder"
    done
    rm -rf "$work/inline"
  done
done
rm -rf "$work"
