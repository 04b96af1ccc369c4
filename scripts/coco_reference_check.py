#!/usr/bin/env python3
"""Checks `stereodet eval --coco-gt --coco-det` against pycocotools' COCOeval on random sets.

Each seed makes one COCO-shaped ground truth and results file: random boxes of every area range
(and exactly on the range bounds), declared areas that differ from the box's, crowds, "ignore"
flags, ground-truth id 0, images and categories without boxes or without detections, detections
of categories the ground truth lacks, duplicated boxes, tied scores, and images with more than
100 detections of one category. Both evaluate it with pycocotools' default parameters (iouType
bbox); the script compares the 12 summary numbers, the precision, recall and scores arrays
(COCOeval.eval) and the printed summary lines, and reports the largest difference.

pycocotools is not a dependency of the project (Debian 12 has no package): build it from its
sources in a scratch folder and point the script at the folder that holds the `pycocotools`
package (docs/metrics.md, "COCO mode"), e.g.

    STEREODET_PYCOCOTOOLS=/tmp/coco-ref/PythonAPI /usr/bin/python3 scripts/coco_reference_check.py \
        --stereodet build/bin/stereodet --seeds 300

Without pycocotools it says so and exits 0 (77 with --require-reference to fail instead).
Exit status 1 when any case differs; the failing cases are kept in --keep DIR.
"""

import argparse
import contextlib
import copy
import io
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile

import numpy as np


def load_pycocotools(path):
    if path:
        sys.path.insert(0, path)
    try:
        from pycocotools.coco import COCO
        from pycocotools.cocoeval import COCOeval
    except ImportError as e:
        return None, None, str(e)
    return COCO, COCOeval, None


def random_box(rng, size_class=None):
    """[x, y, w, h] in one of the area ranges, or on a range bound, integers or floats."""
    kind = size_class or rng.choice(["small", "medium", "large", "bound", "tiny"])
    if kind == "bound":
        side = rng.choice([32, 96])
        w, h = float(side), float(side)  # area exactly 32^2 or 96^2
    elif kind == "tiny":
        w, h = rng.uniform(0.5, 4), rng.uniform(0.5, 4)
    else:
        lo, hi = {"small": (2, 31), "medium": (33, 95), "large": (97, 300)}[kind]
        w = rng.uniform(lo, hi)
        h = w * rng.uniform(0.6, 1.4)
    x, y = rng.uniform(0, 400), rng.uniform(0, 400)
    box = [x, y, w, h]
    if rng.random() < 0.3:
        box = [float(round(v)) if i < 2 else float(max(1, round(v))) for i, v in enumerate(box)]
        if rng.random() < 0.5:
            box = [int(v) for v in box]  # JSON integers
    return box


def jitter(rng, box, amount):
    x, y, w, h = box
    return [x + rng.uniform(-amount, amount) * w, y + rng.uniform(-amount, amount) * h,
            w * (1 + rng.uniform(-amount, amount)), h * (1 + rng.uniform(-amount, amount))]


def make_case(seed):
    rng = random.Random(seed)
    big = seed % 10 == 9  # every tenth case: more categories, so np.mean sums > 8192 values
    num_images = rng.randint(0, 8) if not big else rng.randint(20, 60)
    num_categories = rng.randint(1, 5) if not big else rng.randint(9, 20)
    image_ids = rng.sample(range(1, 10 * num_images + 10), num_images)
    category_ids = sorted(rng.sample(range(1, 100), num_categories))
    images = [{"id": i, "file_name": f"{i}.jpg"} for i in image_ids]
    if image_ids and rng.random() < 0.2:
        images.append({"id": image_ids[0]})  # listed twice: one image
    categories = [{"id": c, "name": f"c{c}"} for c in category_ids]
    annotations, dets = [], []
    next_id = 0 if rng.random() < 0.15 else 1  # sometimes a ground truth of id 0
    score_step = rng.choice([None, None, 0.1, 0.25])  # quantized scores: ties

    def score():
        s = rng.random()
        return round(s / score_step) * score_step if score_step else s

    for image in image_ids:
        if rng.random() < 0.15:
            continue  # an image without anything
        for category in category_ids:
            if rng.random() < 0.3:
                continue
            n_gt = rng.choice([0, 1, 1, 2, 3, 5, 8])
            crowd_p = rng.choice([0.0, 0.1, 0.3])
            boxes = []
            for _ in range(n_gt):
                box = random_box(rng)
                crowd = rng.random() < crowd_p
                if crowd:
                    box = [box[0], box[1], box[2] * 2, box[3] * 2]
                area = box[2] * box[3]
                r = rng.random()
                if r < 0.3:
                    area *= rng.uniform(0.4, 1.0)  # a segment's area, smaller than its box
                elif r < 0.4:
                    area = rng.choice([1024, 9216, 1024.0, 9216.0])  # on a bound
                ann = {"id": next_id, "image_id": image, "category_id": category, "bbox": box,
                       "area": area,
                       "iscrowd": (bool(crowd) if rng.random() < 0.1 else int(crowd))}
                if rng.random() < 0.1:
                    ann["ignore"] = rng.choice([0, 1])
                annotations.append(ann)
                boxes.append(box)
                next_id += 1
            # Detections: jittered copies of the boxes (some duplicated), then false positives.
            for box in boxes:
                for _ in range(rng.choice([0, 1, 1, 1, 2, 3])):
                    d = jitter(rng, box, rng.choice([0.0, 0.02, 0.05, 0.1, 0.2, 0.4]))
                    dets.append({"image_id": image, "category_id": category, "bbox": d,
                                 "score": score()})
                    if rng.random() < 0.1:
                        dets.append(copy.deepcopy(dets[-1]))  # an exact duplicate
            for _ in range(rng.choice([0, 0, 1, 2, 5])):
                dets.append({"image_id": image, "category_id": category, "bbox": random_box(rng),
                             "score": score()})
            if rng.random() < 0.05:
                # More than maxDets = 100 detections of one category in one image.
                base = boxes[0] if boxes else random_box(rng)
                for _ in range(rng.randint(95, 130)):
                    dets.append({"image_id": image, "category_id": category,
                                 "bbox": jitter(rng, base, 0.3), "score": score()})
    if image_ids and rng.random() < 0.2:
        # Detections of a category the ground truth does not have: left out by both.
        dets.append({"image_id": rng.choice(image_ids), "category_id": 1000,
                     "bbox": random_box(rng), "score": score()})
    if image_ids and rng.random() < 0.2:
        # Ground truth of a category the file does not list: left out by both.
        annotations.append({"id": 10**6 + seed, "image_id": image_ids[0], "category_id": 999,
                            "bbox": random_box(rng), "area": 100.0, "iscrowd": 0})
    rng.shuffle(dets)
    for d in dets:
        if rng.random() < 0.1:
            d["id"] = rng.randint(1, 50)  # loadRes replaces result ids: so must we ignore them
    gt = {"info": {}, "images": images, "categories": categories, "annotations": annotations}
    return gt, dets


def run_pycocotools(COCO, COCOeval, gt, dets):
    """COCOeval's stats, arrays and printed summary lines; None when pycocotools cannot run."""
    with contextlib.redirect_stdout(io.StringIO()):
        coco_gt = COCO()
        coco_gt.dataset = copy.deepcopy(gt)
        coco_gt.createIndex()
        coco_dt = coco_gt.loadRes(copy.deepcopy(dets))
        e = COCOeval(coco_gt, coco_dt, "bbox")
        e.evaluate()
        e.accumulate()
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        e.summarize()
    lines = [l for l in printed.getvalue().splitlines() if l.startswith(" Average")]
    return {"stats": np.asarray(e.stats, dtype=np.float64), "precision": e.eval["precision"],
            "recall": e.eval["recall"], "scores": e.eval["scores"], "lines": lines}


def run_stereodet(binary, gt, dets, work):
    gt_path, det_path, out = (os.path.join(work, n) for n in ("gt.json", "det.json", "eval"))
    with open(gt_path, "w") as f:
        json.dump(gt, f)
    with open(det_path, "w") as f:
        json.dump(dets, f)
    proc = subprocess.run([binary, "eval", "--coco-gt", gt_path, "--coco-det", det_path,
                           "--out", out, "--threads", "1"], capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"stereodet failed ({proc.returncode}): {proc.stderr.strip()}")
    with open(os.path.join(out, "results.json")) as f:
        results = json.load(f)
    return {"stats": np.array(list(results["stats"].values()), dtype=np.float64),
            "precision": np.load(os.path.join(out, "precision.npy")),
            "recall": np.load(os.path.join(out, "recall.npy")),
            "scores": np.load(os.path.join(out, "scores.npy")),
            "lines": [l for l in proc.stdout.splitlines() if l.startswith(" Average")]}


def max_difference(a, b):
    if a.shape != b.shape:
        return float("inf")
    return float(np.max(np.abs(a - b))) if a.size else 0.0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--stereodet", default="build/bin/stereodet", help="the front end")
    parser.add_argument("--pycocotools", default=os.environ.get("STEREODET_PYCOCOTOOLS", ""),
                        help="folder holding the pycocotools package (default: "
                        "$STEREODET_PYCOCOTOOLS, else the Python path)")
    parser.add_argument("--seeds", type=int, default=200, help="number of random cases")
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--keep", default="", help="copy the inputs of failing cases here")
    parser.add_argument("--require-reference", action="store_true",
                        help="exit 77 instead of 0 when pycocotools is not available")
    args = parser.parse_args()

    COCO, COCOeval, problem = load_pycocotools(args.pycocotools)
    if COCO is None:
        print(f"skipped: pycocotools is not importable ({problem}); build it from its sources "
              "and give its folder with --pycocotools or STEREODET_PYCOCOTOOLS")
        return 77 if args.require_reference else 0

    keys = ["stats", "precision", "recall", "scores"]
    worst = {k: 0.0 for k in keys}
    failures, identical, sizes = [], 0, [0, 0, 0]
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        gt, dets = make_case(seed)
        if not dets:
            dets = [{"image_id": gt["images"][0]["id"] if gt["images"] else 0, "category_id": 1,
                     "bbox": [0, 0, 1, 1], "score": 0.5}]
            if not gt["images"]:
                gt["images"] = [{"id": 0}]  # pycocotools' loadRes fails on an empty list
        sizes[0] += len(gt["images"])
        sizes[1] += len(gt["annotations"])
        sizes[2] += len(dets)
        reference = run_pycocotools(COCO, COCOeval, gt, dets)
        with tempfile.TemporaryDirectory(prefix="coco_check_") as work:
            ours = run_stereodet(args.stereodet, gt, dets, work)
            diffs = {k: max_difference(reference[k], ours[k]) for k in keys}
            same_lines = reference["lines"] == ours["lines"]
            exact = all(np.array_equal(reference[k], ours[k]) for k in keys)
            for k in keys:
                worst[k] = max(worst[k], diffs[k])
            identical += exact
            if not exact or not same_lines:
                failures.append(seed)
                print(f"seed {seed}: differs: " +
                      ", ".join(f"{k} {diffs[k]:.3g}" for k in keys) +
                      ("" if same_lines else "; printed summary differs"))
                if args.keep:
                    dest = os.path.join(args.keep, f"seed{seed}")
                    os.makedirs(dest, exist_ok=True)
                    for name in ("gt.json", "det.json"):
                        shutil.copy(os.path.join(work, name), dest)
    print(f"{args.seeds} cases (seeds {args.first_seed}..{args.first_seed + args.seeds - 1}; "
          f"{sizes[0]} images, {sizes[1]} ground truths, {sizes[2]} detections): "
          f"{identical} bit-identical in stats, precision, recall and scores; "
          f"{args.seeds - len(failures)} with the same printed summary")
    print("max |difference|: " + ", ".join(f"{k} {worst[k]:.3g}" for k in keys))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
