#!/bin/bash
# Speed and peak memory of the whole `stereodet eval` process against KITTI's official devkit, side
# by side on one KITTI-val-sized random set (issue 10, section 7; figures in docs/BENCHMARKS.md).
#
#   benchmarks/devkit_speed.sh DEVKIT_SRC BUILD_DIR [WORK_DIR]
#
# DEVKIT_SRC: the devkit's cpp/ folder (devkit_object: evaluate_object.cpp, mail.h), unmodified; it
#             is compiled here into WORK_DIR (never into the source tree), with ${CXX:-g++}
#             ${DEVKIT_CXXFLAGS:--O2} (its own CMakeLists sets no flags at all: DEVKIT_CXXFLAGS=-O0).
# BUILD_DIR:  a stereodet build folder with bin/stereodet and benchmarks/write_eval_set
#             (cmake --build BUILD_DIR --target stereodet write_eval_set).
# WORK_DIR:   scratch folder (default: a new one under /tmp), left in place.
# Environment: FRAMES (3769), SEED (2024), REPEAT (3: stereodet runs per matcher, the one of least
# CPU time is reported; the devkit runs once), STEREODET (default BUILD_DIR/bin/stereodet), THREADS
# (stereodet --threads, default 0 = all).
#
# The set: write_eval_set --frames FRAMES --seed SEED --devkit (labels and detections rounded to two
# decimals as KITTI writes them; the devkit's layout has frames 000000..007517, the frames past the
# set as empty files, which add nothing). Both tools evaluate Car, Pedestrian and Cyclist x Easy,
# Moderate, Hard x 2D / BEV / 3D with R40, R11 and AOS, and write their results (the devkit its stats
# files, and plots only where gnuplot exists; stereodet --out). CPU time = user + sys of the process
# and its children, peak RSS = "Maximum resident set size", both from /usr/bin/time -v.
set -euo pipefail

if [ $# -lt 2 ]; then
  sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'
  exit 2
fi
devkit_src=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
work=${3:-$(mktemp -d /tmp/devkit_speed.XXXXXX)}
mkdir -p "$work"
work=$(cd "$work" && pwd)
frames=${FRAMES:-3769}
seed=${SEED:-2024}
repeat=${REPEAT:-3}
threads=${THREADS:-0}
stereodet=${STEREODET:-$build/bin/stereodet}
writer=$build/benchmarks/write_eval_set
[ -x "$writer" ] || writer=$build/bin/write_eval_set
for f in "$devkit_src/evaluate_object.cpp" "$devkit_src/mail.h" /usr/bin/time "$stereodet" "$writer"; do
  [ -e "$f" ] || { echo "devkit_speed.sh: missing $f" >&2; exit 1; }
done

echo "== building the devkit in $work/devkit_bin"
mkdir -p "$work/devkit_bin"
${CXX:-g++} ${DEVKIT_CXXFLAGS:--O2} -I"$devkit_src" -o "$work/devkit_bin/evaluate_object" "$devkit_src/evaluate_object.cpp" \
  2> "$work/devkit_bin/build.log"

echo "== writing the set ($frames frames, seed $seed)"
set_line=$("$writer" --out "$work/set" --frames "$frames" --seed "$seed" --devkit)
echo "$set_line"

# measure NAME DIR CMD...: runs CMD in DIR under /usr/bin/time -v; prints "cpu_s rss_mb wall_s".
measure() {
  local name=$1 dir=$2
  shift 2
  local log="$work/time_$name.txt"
  (cd "$dir" && /usr/bin/time -v -o "$log" "$@" > "$work/out_$name.txt" 2>&1) ||
    { echo "devkit_speed.sh: $name failed, see $work/out_$name.txt" >&2; exit 1; }
  awk -F': ' '/User time/ {u = $2} /System time/ {s = $2} /Maximum resident/ {m = $2}
              /Elapsed \(wall clock\)/ {n = split($2, t, ":"); w = 0; for (i = 1; i <= n; ++i) w = w * 60 + t[i]}
              END {printf "%.3f %.1f %.2f\n", u + s, m / 1024, w}' "$log"
}

# best NAME DIR CMD...: the least-CPU run of REPEAT.
best() {
  local name=$1 out="" line
  for ((k = 0; k < repeat; ++k)); do
    line=$(measure "$@")
    if [ -z "$out" ] || awk -v a="${line%% *}" -v b="${out%% *}" 'BEGIN {exit !(a < b)}'; then out=$line; fi
  done
  echo "$out"
}

echo "== official devkit (once)"
rm -rf "$work/set/devkit/results/stereodet/plot" "$work/set/devkit/results/stereodet"/stats_*
devkit=$(measure devkit "$work/set/devkit" "$work/devkit_bin/evaluate_object" stereodet)
echo "== stereodet eval --matcher kitti (best of $repeat)"
kitti=$(best kitti "$work" "$stereodet" eval --gt set/label_2 --det set/det --matcher kitti \
  --threads "$threads" --out "$work/sd_kitti")
echo "== stereodet eval --matcher optimal (best of $repeat)"
optimal=$(best optimal "$work" "$stereodet" eval --gt set/label_2 --det set/det --matcher optimal \
  --threads "$threads" --out "$work/sd_optimal")
startup=$(best help "$work" "$stereodet" --help)

read -r d_cpu d_rss d_wall <<< "$devkit"
read -r k_cpu k_rss k_wall <<< "$kitti"
read -r o_cpu o_rss o_wall <<< "$optimal"
read -r h_cpu h_rss h_wall <<< "$startup"
echo
echo "machine: $(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); $(date -u '+%Y-%m-%d %H:%M UTC'); load average $(cut -d' ' -f1-3 /proc/loadavg)"
echo "set: ${set_line#*: }"
printf '%-36s %10s %10s %10s\n' "process" "CPU s" "peak MB" "wall s"
printf '%-36s %10s %10s %10s\n' "official devkit (evaluate_object)" "$d_cpu" "$d_rss" "$d_wall"
printf '%-36s %10s %10s %10s\n' "stereodet eval --matcher kitti" "$k_cpu" "$k_rss" "$k_wall"
printf '%-36s %10s %10s %10s\n' "stereodet eval --matcher optimal" "$o_cpu" "$o_rss" "$o_wall"
printf '%-36s %10s %10s %10s\n' "stereodet --help (start-up only)" "$h_cpu" "$h_rss" "$h_wall"
awk -v d="$d_cpu" -v k="$k_cpu" -v o="$o_cpu" 'BEGIN {
  printf "CPU time, kitti matcher / devkit: 1/%.1f (target: at most 1/100)\n", d / k
  printf "CPU time, optimal / kitti matcher: %.2fx (target: at most 1.5x)\n", o / k }'
echo "peak RSS, kitti matcher: $k_rss MB (target: at most 64 MB)"
echo "work folder: $work"
