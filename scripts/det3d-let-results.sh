#!/usr/bin/env bash
# LiDAR against stereo points by distance, with KITTI's overlaps and with LET-3D-AP's (issue 37;
# docs/RESULTS.md, "By distance, forgiving depth"): for each seed pair of `make experiment`'s 3D
# detectors (det3d-lidar-seedS vs det3d-stereo-seedS, the same seed's detections on the val split),
# `eval compare` with paired bootstrap intervals of every cell and every distance bin, in BEV, 3D,
# LET-BEV and LET-3D, at KITTI's strict (Car 0.7) and loose (Car 0.5) overlaps, optimal matcher,
# Car Moderate; each model alone too (`eval`, for LET-APL and the labels per bin); then one Markdown
# table of the means over the seeds; and each model's TIDE-style error analysis (`eval --errors`,
# BEV, 3D, LET-3D at the strict overlaps), a second table: where each model's AP goes.
# Usage: scripts/det3d-let-results.sh BUILD_DIR [EXPERIMENT_DIR] [DATA_DIR] [OUT_DIR]
#   LET_SEEDS="1 2 3"   LET_BOOTSTRAP=1000   LET_BINS=0,15,30,50,inf
#   LET_TABLE_ONLY=1: only rebuild the table from the results already there
# Writes OUT_DIR/seedS-SET/ (compare.csv, bootstrap.csv, bootstrap_breakdown.csv),
# OUT_DIR/eval-INPUT-seedS/ and OUT_DIR/errors-INPUT-seedS/ (results.json, ...), OUT_DIR/table.md
# and OUT_DIR/errors.md. A folder of a run that completed is kept (delete it to run it again).
set -euo pipefail
build_dir=${1:-build}
experiment=${2:-results/experiment}
data=${3:-data/synth-det3d}
out=${4:-results/det3d-let}
seeds=${LET_SEEDS:-1 2 3}
boot=${LET_BOOTSTRAP:-1000}
bins=${LET_BINS:-0,15,30,50,inf}
bin="$build_dir/bin/stereodet"
[[ -x "$bin" ]] || { echo "det3d-let-results: $bin not built; run make build" >&2; exit 1; }

if [[ -z "${LET_TABLE_ONLY:-}" ]]; then
  for seed in $seeds; do
    for input in lidar stereo; do
      dets="$experiment/runs/det3d-$input-seed$seed/blur0/detections"
      [[ -d "$dets" ]] ||
        { echo "det3d-let-results: $dets missing; run make experiment" >&2; exit 1; }
    done
    for input in lidar stereo; do
      run="$out/eval-$input-seed$seed"
      [[ -f "$run/results.json" ]] && continue
      echo "==> det3d-$input-seed$seed alone ($run)"
      "$bin" eval --gt "$data" --split val --det "$experiment/runs/det3d-$input-seed$seed/blur0/detections" \
        --classes Car --metrics bev,3d,let-bev,let-3d --difficulties moderate --matcher optimal \
        --overlaps strict,loose --breakdown "distance=$bins" --out "$run" > /dev/null
    done
    for input in lidar stereo; do
      run="$out/errors-$input-seed$seed"
      [[ -f "$run/errors.csv" ]] && continue
      echo "==> det3d-$input-seed$seed error analysis ($run)"
      "$bin" eval --gt "$data" --split val --det "$experiment/runs/det3d-$input-seed$seed/blur0/detections" \
        --classes Car --metrics bev,3d,let-3d --difficulties moderate --matcher optimal --errors \
        --out "$run" > /dev/null
    done
    for set in strict loose; do
      run="$out/seed$seed-$set"
      if [[ -f "$run/bootstrap_breakdown.csv" ]]; then
        echo "==> $run (kept)"
        continue
      fi
      echo "==> seed $seed, $set overlaps ($run)"
      "$bin" eval compare --gt "$data" --split val \
        --det "$experiment/runs/det3d-lidar-seed$seed/blur0/detections" \
        --det-b "$experiment/runs/det3d-stereo-seed$seed/blur0/detections" \
        --classes Car --metrics bev,3d,let-bev,let-3d --difficulties moderate \
        --matcher optimal --overlaps "$set" --bootstrap "$boot" --breakdown "distance=$bins" \
        --out "$run" > /dev/null
    done
  done
fi

/usr/bin/python3 - "$out" $seeds <<'EOF'
import csv
import json
import math
import pathlib
import statistics
import sys

out = pathlib.Path(sys.argv[1])
seeds = sys.argv[2:]
rows = {}  # (set, metric, bin) -> seed -> row
for seed in seeds:
    for overlap_set in ("strict", "loose"):
        run = out / f"seed{seed}-{overlap_set}"
        for name, binned in (("bootstrap.csv", False), ("bootstrap_breakdown.csv", True)):
            with open(run / name) as f:
                for r in csv.DictReader(f):
                    if r["measure"] != "ap_r40":
                        continue
                    where = "all" if not binned else \
                        f"[{r['lower']}, {r['upper'] or 'inf'})"
                    rows.setdefault((overlap_set, r["metric"], where), {})[seed] = r


def mean(values):
    return statistics.fmean(values)


def write_table(name, lines):
    """OUT/NAME (written to a temporary file, then renamed) and standard output."""
    text = "\n".join(lines) + "\n"
    tmp = out / f"{name}.tmp"
    tmp.write_text(text)
    tmp.replace(out / name)
    print(text, end="")


# LET-APL and the labels of every (set, metric, bin) of each model alone: (input, seed) -> ...
alone = {}
for seed in seeds:
    for model in ("lidar", "stereo"):
        results = json.loads((out / f"eval-{model}-seed{seed}" / "results.json").read_text())
        for cell in results["results"]:
            if not cell.get("evaluated"):
                continue
            key = (cell["overlaps"], cell["metric"])
            alone[(model, seed) + key + ("all",)] = (cell.get("apl_r40"), cell["num_valid_labels"])
            for b in cell.get("breakdown", []):
                upper = "inf" if b["upper"] is None else f"{b['upper']:g}"
                where = f"[{b['lower']:g}, {upper})"
                alone[(model, seed) + key + (where,)] = (b.get("apl_r40"), b["num_valid_labels"])


def apl(model, overlap_set, metric, where):
    values = [alone.get((model, seed, overlap_set, metric, where), (None, 0))[0] for seed in seeds]
    if any(v is None or math.isnan(v) for v in values):
        return "-"
    return f"{mean(values) / 100:.3f}"


lines = [
    "| IoU | overlap | distance (m) | labels | LiDAR AP_R40 | stereo AP_R40 | LiDAR - stereo | "
    "seed pairs whose 95 % interval excludes 0 | LiDAR APL | stereo APL |",
    "|---:|---|---|---:|---:|---:|---:|---:|---:|---:|"]
order = {"bev": 0, "let-bev": 1, "3d": 2, "let-3d": 3}
def bin_key(where):
    return (-1.0,) if where == "all" else (float(where[1:].split(",")[0]),)
for (overlap_set, metric, where) in sorted(
        rows, key=lambda k: (k[0] != "strict", order[k[1]], bin_key(k[2]))):
    by_seed = rows[(overlap_set, metric, where)]
    if len(by_seed) != len(seeds):
        continue
    a = [float(r["a"]) / 100 for r in by_seed.values()]
    b = [float(r["b"]) / 100 for r in by_seed.values()]
    d = [float(r["a_minus_b"]) / 100 for r in by_seed.values()]
    excl = sum(1 for r in by_seed.values()
               if float(r["a_minus_b_lower"]) > 0 or float(r["a_minus_b_upper"]) < 0)
    iou = "0.7" if overlap_set == "strict" else "0.5"
    labels = alone.get(("lidar", seeds[0], overlap_set, metric, where), (None, "?"))[1]
    lines.append(f"| {iou} | {metric.upper()} | {where} | {labels} | {mean(a):.3f} | "
                 f"{mean(b):.3f} | {mean(d):+.3f} | {excl} of {len(seeds)} | "
                 f"{apl('lidar', overlap_set, metric, where)} | "
                 f"{apl('stereo', overlap_set, metric, where)} |")
write_table("table.md", lines)

# Where each model's AP goes (TIDE; docs/metrics.md "Error analysis"): per model and overlap kind,
# the means over the seeds of the AP as is, the points each error type's fix gains and the counts.
types = ("loc", "bkg", "missed", "both", "cls", "dupe")
lines = ["| model | overlap | AP_R40 | dAP loc | dAP bkg | dAP missed | dAP both, cls, dupe | "
         "dAP every FP | dAP every FN | Loc FPs | Bkg FPs | missed labels |",
         "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
for model in ("lidar", "stereo"):
    for metric in ("bev", "3d", "let-3d"):
        cells = []
        for seed in seeds:
            results = json.loads((out / f"errors-{model}-seed{seed}" / "results.json").read_text())
            cells += [c["errors"] for c in results["results"]
                      if c["metric"] == metric and "errors" in c]
        if len(cells) != len(seeds):
            continue
        d = {t: mean([c["delta_ap_r40"][t] for c in cells]) / 100 for t in types}
        n = {t: mean([c["count"][t] for c in cells]) for t in types}
        lines.append(
            f"| det3d-{model} | {metric.upper()} | {mean([c['ap_r40'] for c in cells]) / 100:.3f} | "
            f"{d['loc']:+.3f} | {d['bkg']:+.3f} | {d['missed']:+.3f} | "
            f"{d['both'] + d['cls'] + d['dupe']:+.3f} | "
            f"{mean([c['special']['fp_r40'] for c in cells]) / 100:+.3f} | "
            f"{mean([c['special']['fn_r40'] for c in cells]) / 100:+.3f} | "
            f"{n['loc']:.0f} | {n['bkg']:.0f} | {n['missed']:.0f} |")
print()
write_table("errors.md", lines)
EOF
