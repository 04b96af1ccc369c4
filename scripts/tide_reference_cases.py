#!/usr/bin/env python3
"""TIDE's own error analysis on small random 2D cases, for stereodet's test
(`ErrorAnalysisTest.AgreesWithTideWhereTheDefinitionsCoincide` reads the file this writes;
docs/metrics.md, "Error analysis (TIDE)").

    scripts/tide_reference_cases.py --tide TIDE_DIR [--pycocotools COCOAPI_DIR] \\
        --out tests/data/tide/tide_reference.csv [--seed 7] [--cases 40]

TIDE_DIR is a checkout of https://github.com/dbolya/tide (the folder holding the `tidecv`
package; v1.0.1, commit 49a5d2a, was used). TIDE imports OpenCV, pandas, seaborn and matplotlib
for its plots and image display; they are replaced here by empty stand-in modules (the
classification and the AP computation use none of them), so TIDERun, its fix_errors and
APDataObject.get_ap run unmodified. Box IoU comes from pycocotools.mask.iou: COCOAPI_DIR is the
folder holding a built `pycocotools` package (Debian 12 has none; build it from
https://github.com/cocodataset/cocoapi (commit 8c9bcc3 was used) with `python3 setup.py
build_ext --inplace` in PythonAPI/: Cython and NumPy are Debian packages). Without --pycocotools, a NumPy-free port of
maskApi.c's bbIou (the only function TIDE's box mode calls, float64 like the C) stands in; the
file's header says which was used. Needs NumPy; stereodet itself needs none of this.

Each case: 2-5 images (KITTI-sized, 1242 x 375), 1-6 labels each of class Car (1) or Pedestrian
(2), the labels of an image pairwise disjoint (so a detection can have IoU >= 0.5 with one label
at most), and detections: a jittered copy of most labels (tight or loose), sometimes a second one
(a duplicate), sometimes one of the other class (a class confusion), and a few boxes anywhere.
Integer pixel boxes, every box at least 30 px tall (valid at KITTI's Moderate), distinct scores
within a case, no IoU within 1e-9 of 0.5 or 0.1 (where TIDE's `<=` and the matchers' tests
differ). TIDE is run with its defaults (pos_threshold 0.5, background_threshold 0.1, bbox).

Rows (LF line ends):
  gt,case,image,index,class,left,top,right,bottom,missed      (missed: TIDE's MissedError)
  det,case,image,index,class,left,top,right,bottom,score,type,fixed
      type: tp, or TIDE's error (cls, loc, both, dupe, bkg); fixed: 1 when the error's fix makes
      it a TP (TIDE's BestGTMatch winner)
  ap,case,class,which,value
      TIDE's per-class AP (APDataObject.get_ap, 101 recall points, percent) as is (which = base),
      with only one error type fixed (cls, loc, both, dupe, bkg, missed: TIDERun.fix_errors with
      that type's condition; TIDE averages these over classes for its dAPs, and clamps the
      difference at 0, which is not done here), and for the special errors (fp: FalsePositiveError
      transform; fn: every false negative removed).
Indices are 0-based, in the order the rows come (file order of the frames the test builds).
"""

import argparse
import csv
import os
import pathlib
import random
import sys
import types

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import stub_modules  # noqa: E402  (scripts/stub_modules.py)

W, H = 1242, 375
STUBS = ("cv2", "pandas", "seaborn")
CLASSES = {1: "Car", 2: "Pedestrian"}


def bb_iou(dt, gt, iscrowd):
    """maskApi.c's bbIou for [x, y, w, h] boxes: iou[d][g], float64 as the C."""
    if len(dt) == 0 or len(gt) == 0:
        return []
    out = [[0.0] * len(gt) for _ in dt]
    for g, G in enumerate(gt):
        G = [float(v) for v in G]
        ga = G[2] * G[3]
        crowd = bool(iscrowd[g]) if iscrowd is not None else False
        for d, D in enumerate(dt):
            D = [float(v) for v in D]
            da = D[2] * D[3]
            w = min(D[2] + D[0], G[2] + G[0]) - max(D[0], G[0])
            if w <= 0:
                continue
            h = min(D[3] + D[1], G[3] + G[1]) - max(D[1], G[1])
            if h <= 0:
                continue
            i = w * h
            u = da if crowd else da + ga - i
            out[d][g] = i / u
    import numpy as np

    return np.array(out, dtype=np.float64)


def install_pycocotools_port():
    pkg = types.ModuleType("pycocotools")
    pkg.__path__ = []
    mask = types.ModuleType("pycocotools.mask")
    mask.iou = bb_iou
    pkg.mask = mask
    sys.modules["pycocotools"] = pkg
    sys.modules["pycocotools.mask"] = mask


def disjoint(a, b):
    """[x, y, w, h] boxes that share no area."""
    return (min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]) <= 0
            or min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]) <= 0)


def jitter(rng, box, loose):
    x, y, w, h = box
    s = rng.uniform(0.15, 0.55) if loose else rng.uniform(0.0, 0.15)
    nw = max(10, round(w * rng.uniform(1 - s / 2, 1 + s / 2)))
    nh = max(30, round(h * rng.uniform(1 - s / 2, 1 + s / 2)))
    nx = round(x + (w - nw) / 2 + rng.uniform(-s, s) * w)
    ny = round(y + (h - nh) / 2 + rng.uniform(-s, s) * h)
    return [nx, ny, nw, nh]


def draw_case(rng):
    images = []
    for _ in range(rng.randint(2, 5)):
        labels = []
        for _ in range(rng.randint(1, 6)):
            for _try in range(100):
                w, h = rng.randint(40, 160), rng.randint(45, 150)
                box = [rng.randint(0, W - w), rng.randint(0, H - h), w, h]
                if all(disjoint(box, b) for _, b in labels):
                    labels.append((rng.choice((1, 1, 2)), box))
                    break
        dets = []
        for cls, box in labels:
            if rng.random() < 0.8:
                dets.append([cls, jitter(rng, box, rng.random() < 0.35)])
            if rng.random() < 0.25:
                dets.append([cls, jitter(rng, box, rng.random() < 0.5)])
            if rng.random() < 0.15:
                dets.append([3 - cls, jitter(rng, box, rng.random() < 0.4)])
        for _ in range(rng.randint(0, 2)):
            w, h = rng.randint(30, 160), rng.randint(30, 150)
            dets.append([rng.choice((1, 2)), [rng.randint(0, W - w), rng.randint(0, H - h), w, h]])
        rng.shuffle(dets)
        images.append((labels, dets))
    # Distinct scores within the case.
    scores = rng.sample(range(1, 1000000), sum(len(d) for _, d in images))
    k = 0
    for _, dets in images:
        for d in dets:
            d.append(scores[k] / 1000000)
            k += 1
    return images


def acceptable(images, iou):
    for labels, dets in images:
        for _, box, _score in dets:
            if box[3] < 30 or box[2] <= 0:
                return False
        if not labels or not dets:
            continue
        m = iou([d[1] for d in dets], [b for _, b in labels], [False] * len(labels))
        for row in m:
            for v in row:
                if abs(v - 0.5) < 1e-9 or abs(v - 0.1) < 1e-9:
                    return False
    return True


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--tide", required=True, help="the folder holding the tidecv package")
    parser.add_argument("--pycocotools", help="the folder holding a built pycocotools package")
    parser.add_argument("--out", required=True)
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--cases", type=int, default=40)
    args = parser.parse_args()

    stubs = list(STUBS)
    try:
        import matplotlib  # noqa: F401  (TIDE's plots; the real one if it is there)

        os.environ.setdefault("MPLBACKEND", "Agg")
    except ImportError:
        stubs.append("matplotlib")
    stub_modules.install(stubs)
    if args.pycocotools:
        sys.path.insert(0, args.pycocotools)
        iou_source = "pycocotools.mask.iou (built from cocoapi)"
    else:
        install_pycocotools_port()
        iou_source = "a port of maskApi.c's bbIou (no pycocotools given)"
    sys.path.insert(0, args.tide)
    from pycocotools import mask as mask_utils
    from tidecv.data import Data
    from tidecv.errors.main_errors import (BackgroundError, BoxError, ClassError, DuplicateError,
                                           FalsePositiveError, MissedError, OtherError)
    from tidecv.quantify import TIDERun

    names = {ClassError: "cls", BoxError: "loc", OtherError: "both", DuplicateError: "dupe",
             BackgroundError: "bkg", MissedError: "missed"}
    rng = random.Random(args.seed)
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(".tmp")
    with open(tmp, "w", newline="") as f:
        f.write("# TIDE v1.0.1 (dbolya/tide 49a5d2a) TIDERun, pos 0.5, bg 0.1, bbox; IoU: "
                f"{iou_source}; scripts/tide_reference_cases.py --seed {args.seed}\n")
        w = csv.writer(f, lineterminator="\n")
        case = 0
        while case < args.cases:
            images = draw_case(rng)
            if not acceptable(images, mask_utils.iou):
                continue
            gt, pred = Data("gt"), Data("pred")
            gt_index, pred_index = {}, {}
            for img, (labels, dets) in enumerate(images):
                for i, (cls, box) in enumerate(labels):
                    gt_index[len(gt.annotations)] = (img, i)
                    gt.add_ground_truth(img, cls, box=list(box))
                for j, (cls, box, score) in enumerate(dets):
                    pred_index[len(pred.annotations)] = (img, j)
                    pred.add_detection(img, cls, score, box=list(box))
            run = TIDERun(gt, pred, 0.5, 0.1, "bbox", gt.max_dets, True)
            det_type, missed = {}, set()
            for e in run.errors:
                if isinstance(e, MissedError):
                    missed.add(gt_index[e.gt["_id"]])
                    continue
                key = pred_index[e.pred["_id"]]
                assert key not in det_type, key
                det_type[key] = (names[type(e)], 1 if e.fixed[1] is not None else 0)
            for p in pred.annotations:
                key = pred_index[p["_id"]]
                if p["used"] is True:
                    assert key not in det_type, key
                    det_type[key] = ("tp", 0)
                assert key in det_type, key
            for img, (labels, dets) in enumerate(images):
                for i, (cls, (x, y, bw, bh)) in enumerate(labels):
                    w.writerow(["gt", case, img, i, CLASSES[cls], x, y, x + bw, y + bh,
                                1 if (img, i) in missed else 0])
                for j, (cls, (x, y, bw, bh), score) in enumerate(dets):
                    t, fixed = det_type[(img, j)]
                    w.writerow(["det", case, img, j, CLASSES[cls], x, y, x + bw, y + bh,
                                repr(score), t, fixed])

            def per_class(ap_data, which):
                for cid, name in CLASSES.items():
                    w.writerow(["ap", case, name, which, repr(float(ap_data.objs[cid].get_ap()))])

            per_class(run.ap_data, "base")
            for err, name in names.items():
                per_class(run.fix_errors(lambda e, t=err: isinstance(e, t)), name)
            per_class(run.fix_errors(transform=FalsePositiveError.fix), "fp")
            per_class(run.fix_errors(false_neg_dict=run.false_negatives), "fn")
            case += 1
    tmp.replace(out)
    print(f"{args.cases} cases -> {out}")


if __name__ == "__main__":
    main()
