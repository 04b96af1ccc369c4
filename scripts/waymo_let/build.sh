#!/bin/bash
# Builds let_harness (let_harness.cc beside this script) against Waymo Open Dataset's own metrics
# code, without bazel, for scripts/let_reference_cases.py (docs/metrics.md, "LET-3D-AP"). Not part
# of stereodet's build: run it by hand, outside the repository.
#
#   scripts/waymo_let/build.sh WAYMO_GIT_DIR OUT_DIR [REV]
#
# WAYMO_GIT_DIR: a clone (or bare mirror) of github.com/waymo-research/waymo-open-dataset; REV its
# revision (HEAD; measured with 99a4cb3ff07e). Needs protoc, libprotobuf-dev, libabsl-dev,
# libgoogle-glog-dev and nlohmann-json3-dev (Debian). Waymo's files are extracted unmodified into
# OUT_DIR/wod; the program is OUT_DIR/let_harness.
set -euo pipefail
MIRROR=$(realpath "${1:?WAYMO_GIT_DIR}")
ROOT=$(realpath -m "${2:?OUT_DIR}")
REV=${3:-HEAD}
HERE=$(dirname "$(realpath "$0")")
JOBS=${JOBS:-2}
mkdir -p "$ROOT"
cd "$ROOT"
rm -rf wod build let_harness
mkdir -p wod build/gen build/obj
P=src/waymo_open_dataset
# (a mirror without one unrelated TensorFlow blob makes git archive print "invalid object" for it;
# the files named here are extracted all the same)
git -C "$MIRROR" archive "$REV" \
  $P/label.proto $P/dataset.proto \
  $P/protos/{metrics,breakdown,keypoint,vector,map}.proto \
  $P/math/{aabox2d.h,box2d.h,box2d.cc,math_util.h,polygon2d.h,polygon2d.cc,segment2d.h,segment2d.cc,vec2d.h} \
  $P/metrics/{iou,matcher,hungarian,metrics_utils,breakdown_generator,detection_metrics}.{h,cc} \
  | tar -x -C wod
git -C "$MIRROR" rev-parse "$REV" > wod/REVISION
INC=wod/src
( cd $INC && protoc -I. --cpp_out="$ROOT/build/gen" \
    waymo_open_dataset/label.proto waymo_open_dataset/dataset.proto \
    waymo_open_dataset/protos/{metrics,breakdown,keypoint,vector,map}.proto )
CXX="nice -n 10 g++ -std=c++17 -O2 -DNDEBUG -I$INC -Ibuild/gen"
SRCS=$(ls build/gen/waymo_open_dataset/*.pb.cc build/gen/waymo_open_dataset/protos/*.pb.cc
       echo $INC/waymo_open_dataset/math/{box2d,polygon2d,segment2d}.cc
       echo $INC/waymo_open_dataset/metrics/{iou,matcher,hungarian,metrics_utils,breakdown_generator,detection_metrics}.cc
       echo "$HERE/let_harness.cc")
printf '%s\n' $SRCS | xargs -P "$JOBS" -I{} sh -c \
  'o=build/obj/$(basename {} .cc).o; '"$CXX"' -c {} -o $o'
nice -n 10 g++ -o let_harness build/obj/*.o \
  -lprotobuf -lglog -lgflags \
  -labsl_str_format_internal -labsl_strings -labsl_strings_internal \
  -labsl_int128 -labsl_throw_delegate -labsl_raw_logging_internal -labsl_base \
  -labsl_spinlock_wait -lpthread
echo "built $ROOT/let_harness from waymo-open-dataset $(cat wod/REVISION)"
