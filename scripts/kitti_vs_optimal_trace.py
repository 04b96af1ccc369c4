#!/usr/bin/env python3
"""Why a cell's AP_R40 can be lower with the optimal matcher than with the KITTI matcher (issue 36).

    scripts/kitti_vs_optimal_trace.py KITTI_RESULTS OPTIMAL_RESULTS [--class Car] [--metric 3d]
                                      [--difficulty Moderate] [--overlaps strict|loose]

KITTI_RESULTS and OPTIMAL_RESULTS are `stereodet eval --out` folders of the same detections and
labels, one per matcher. For the cell, the KITTI matcher's AP_R40 (its 41 slots) is split into:
  own curve    its own TP/FP curve (one point per devkit threshold) read at the recall points i/40
               exactly (the highest precision at recall >= i/40, as the optimal matcher reads its);
  beyond       slots past the highest recall the detections reach: the devkit keeps the last TP
               score as a threshold, so a slot whose recall point lies beyond every detection's
               recall still holds that threshold's precision;
  below        slots within reach read at a threshold whose recall is a little below i/40 (the
               devkit picks the score whose recall is closest to its running recall step).
own curve + beyond + below = the KITTI matcher's AP_R40. The optimal matcher's AP_R40 is its exact
curve read the same way as "own curve"; optimal >= own curve whenever the maximum matching finds at
least the greedy one's TPs at every score, so a KITTI figure above the optimal one comes from
"beyond" and "below" (where the optimal matcher excuses labels the curve's recall counts differently, its figure
is its own: results.json's is printed). "below" is negative on small sets, where the devkit has
fewer thresholds than recall points (the small-sample cap, docs/metrics.md). Standard library only.
"""
import argparse
import csv
import json
import os
import sys


def cell(folder, cls, metric, difficulty, overlaps):
    with open(os.path.join(folder, "results.json")) as f:
        results = json.load(f)["results"]
    for e in results:
        if (e["class"] == cls and e["metric"] == metric and e["difficulty"] == difficulty
                and e.get("overlaps", "strict") == overlaps and e.get("evaluated", True)):
            with open(os.path.join(folder, e["curve_csv"])) as f:
                curve = [(float(r["recall"]), float(r["precision"])) for r in csv.DictReader(f)
                         if r["recall"] and r["precision"]]
            return e, curve
    sys.exit(f"{folder}: no evaluated {cls} {metric} {difficulty} cell")


def read_at(curve, recall):
    """The highest precision at recall >= `recall` (0 when the curve never gets there)."""
    return max((p for r, p in curve if r >= recall - 1e-12), default=0.0)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("kitti")
    parser.add_argument("optimal")
    parser.add_argument("--class", dest="cls", default="Car")
    parser.add_argument("--metric", default="3d")
    parser.add_argument("--difficulty", default="Moderate")
    parser.add_argument("--overlaps", default="strict", help="strict or loose (eval --overlaps)")
    args = parser.parse_args()
    k, k_curve = cell(args.kitti, args.cls, args.metric, args.difficulty, args.overlaps)
    o, _ = cell(args.optimal, args.cls, args.metric, args.difficulty, args.overlaps)
    if "kitti" not in k:
        sys.exit(f"{args.kitti}: not evaluated with the KITTI matcher (no 41-slot arrays)")
    slots = k["kitti"]["precision"]
    max_recall = max((r for r, _ in k_curve), default=0.0)
    own = sum(read_at(k_curve, i / 40) for i in range(1, 41)) / 40 * 100
    beyond = sum(slots[i] for i in range(1, 41) if i / 40 > max_recall + 1e-12) / 40 * 100
    below = sum(slots[i] - read_at(k_curve, i / 40) for i in range(1, 41)
                if i / 40 <= max_recall + 1e-12) / 40 * 100
    # The split must account for the whole figure (its slots are the ones results.json holds).
    if abs(own + beyond + below - k["ap_r40"]) > 1e-9:
        sys.exit(f"the split does not add up: {own} + {beyond} + {below} vs {k['ap_r40']}")
    print(f"{args.cls} {args.metric} {args.difficulty} ({args.overlaps}): "
          f"{k['num_valid_labels']} labels, "
          f"{len(k['kitti']['thresholds'])} devkit thresholds, highest recall {max_recall:.4f}")
    print(f"  KITTI matcher AP_R40 {k['ap_r40']:.2f} = own curve {own:.2f} + beyond {beyond:.2f} "
          f"+ below {below:.2f}")
    print(f"  optimal matcher AP_R40 {o['ap_r40']:.2f}; optimal - own curve "
          f"{o['ap_r40'] - own:+.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
