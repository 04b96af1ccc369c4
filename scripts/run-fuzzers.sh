#!/usr/bin/env bash
# Runs the libFuzzer targets of the parsers (fuzz/CMakeLists.txt lists them) and merges new inputs
# into the checked-in corpora.
#
#   scripts/run-fuzzers.sh BUILD_DIR [SECONDS] [NAME...]
#
# BUILD_DIR holds fuzz/<NAME>_fuzzer (built by `make fuzz`, or
# `cmake --build BUILD_DIR --target fuzzers`); SECONDS (default 600) is the run time of each fuzzer;
# NAMEs default to every fuzzer built in BUILD_DIR/fuzz/. Each fuzzer starts from fuzz/corpus/NAME/
# and, after its run, the inputs that add coverage are merged into that folder (libFuzzer -merge=1),
# named by their SHA-1. With FUZZ_MINIMIZE=1 those SHA-1-named files are rebuilt as a minimal set covering the same
# features; hand-written seeds (any other name, e.g. kitti_000000.txt) are always kept.
# Crashes are written to BUILD_DIR/fuzz/artifacts/ and make the script fail.
# Extra libFuzzer flags may be passed in FUZZ_FLAGS (e.g. FUZZ_FLAGS="-jobs=2 -workers=2").
set -euo pipefail

if [[ $# -lt 1 ]]; then
  sed -n '2,14p' "$0" >&2
  exit 2
fi
build_dir=$1
seconds=${2:-600}
shift $(( $# >= 2 ? 2 : 1 ))
names=("$@")
if [[ ${#names[@]} -eq 0 ]]; then
  for fuzzer in "$build_dir"/fuzz/*_fuzzer; do
    [[ -x $fuzzer ]] && names+=("$(basename "$fuzzer" _fuzzer)")
  done
fi
[[ ${#names[@]} -gt 0 ]] || { echo "run-fuzzers: no fuzzer in $build_dir/fuzz/" >&2; exit 1; }

repo=$(cd "$(dirname "$0")/.." && pwd)
artifacts="$build_dir/fuzz/artifacts"
mkdir -p "$artifacts"
status=0
for name in "${names[@]}"; do
  fuzzer="$build_dir/fuzz/${name}_fuzzer"
  corpus="$repo/fuzz/corpus/$name"
  if [[ ! -x $fuzzer ]]; then
    echo "run-fuzzers: $fuzzer not found; build it with: cmake --build $build_dir --target fuzzers" >&2
    exit 1
  fi
  mkdir -p "$corpus"
  # Short inputs fuzz faster and keep the corpus small; a calib file needs about 1.3 kB, a JSON
  # file or a small PNG a few.
  max_len=512
  case $name in calib | run_manifest | model_json) max_len=2048 ;; disparity) max_len=4096 ;; esac
  dict=()
  [[ -f $repo/fuzz/$name.dict ]] && dict=(-dict="$repo/fuzz/$name.dict")
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  echo "== $name: fuzzing for ${seconds}s from $(ls "$corpus" | wc -l) corpus files"
  # New inputs go to $work; the checked-in corpus is only read during the run.
  # shellcheck disable=SC2086
  if ! "$fuzzer" "$work" "$corpus" -max_total_time="$seconds" -max_len="$max_len" -timeout=10 \
      -rss_limit_mb=2048 -print_final_stats=1 "${dict[@]}" \
      -artifact_prefix="$artifacts/$name-" ${FUZZ_FLAGS:-} 2>&1 | tee "$build_dir/fuzz/$name.log" |
      grep -E '^(#[0-9]+.*(DONE|pulse)|stat::|==[0-9]+==ERROR|SUMMARY|.*_fuzzer: )'; then
    :
  fi
  if grep -qE '==[0-9]+==ERROR|^SUMMARY|deadly signal|Test unit written' "$build_dir/fuzz/$name.log"; then
    echo "run-fuzzers: $name found a crash; see $build_dir/fuzz/$name.log and $artifacts/" >&2
    status=1
  fi
  if [[ ${FUZZ_MINIMIZE:-0} == 1 ]]; then
    found=$(mktemp -d)
    find "$corpus" -maxdepth 1 -type f -regextype posix-extended -regex '.*/[0-9a-f]{40}' \
      -exec mv {} "$found"/ \;
    # The seeds go first, so the merge keeps only what they do not already cover.
    "$fuzzer" -merge=1 -max_len="$max_len" "$corpus" "$found" "$work" >/dev/null 2>&1
    rm -rf "$found"
  else
    "$fuzzer" -merge=1 -max_len="$max_len" "$corpus" "$work" >/dev/null 2>&1
  fi
  echo "== $name: corpus now $(ls "$corpus" | wc -l) files"
  rm -rf "$work"
  trap - EXIT
done
exit $status
