#!/usr/bin/env python3
"""D-ECE from netcal's own implementation, for stereodet's test (`ScoreMetricsTest.DeceAgreesWithNetcal`
reads the file this writes; docs/metrics.md, "Calibration").

    scripts/dece_reference_cases.py --netcal NETCAL_DIR --out tests/data/calibration/netcal_dece.csv [--seed 37]

NETCAL_DIR is a checkout of https://github.com/EFS-OpenSource/calibration-framework (the folder
holding the `netcal` package; revision 2a3db8d was used). netcal's package imports PyTorch, Pyro
and other libraries its metrics do not use; they are replaced here by empty stand-in modules so
that netcal.metrics.confidence.ECE(detection=True), which needs only NumPy and SciPy, runs
unmodified. Needs NumPy and SciPy (Debian: python3-scipy); stereodet itself needs none of this.

Draws five sets of detections in a 1242 x 375 image (2D boxes, scores, TP or not, the chance of
a TP rising with the score and with the box size; some boxes reach past the image, so a feature
leaves [0, 1]) and writes, for each set and each of three bin layouts, netcal's D-ECE over the
features (score, centre x / 1242, centre y / 375, width / 1242, height / 375). Rows "det":
case,left,top,right,bottom,score,tp; rows "dece": case,b_score,b_cx,b_cy,b_w,b_h,value.
"""

import argparse
import csv
import pathlib
import random
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import stub_modules  # noqa: E402  (scripts/stub_modules.py)

W, H = 1242.0, 375.0
STUBS = ("torch", "pyro", "tikzplotlib", "tqdm", "tensorboard", "gpytorch")


def draw(rng, n):
    dets = []
    for _ in range(n):
        h = rng.uniform(15, 200)
        w = h * rng.uniform(0.5, 2.5)
        cx = rng.uniform(-0.05, 1.05) * W
        cy = rng.uniform(0.3, 0.8) * H
        score = rng.betavariate(2, 3)
        tp = 1 if rng.random() < score * min(1.0, h / 80) else 0
        dets.append([cx - w / 2, cy - h / 2, cx + w / 2, cy + h / 2, round(score, 3), tp])
    return dets


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--netcal", required=True, help="the folder holding the netcal package")
    parser.add_argument("--out", required=True)
    parser.add_argument("--seed", type=int, default=37)
    args = parser.parse_args()
    stub_modules.install(STUBS)
    sys.path.insert(0, args.netcal)
    import numpy as np
    from netcal.metrics.confidence import ECE

    rng = random.Random(args.seed)
    cases = [draw(rng, n) for n in (60, 300, 1000, 2500, 5000)]
    layouts = [(5, 5, 5, 5, 5), (10, 1, 1, 1, 1), (4, 3, 2, 3, 2)]
    out = pathlib.Path(args.out)
    tmp = out.with_suffix(".tmp")
    with open(tmp, "w", newline="") as f:
        f.write("# D-ECE of netcal (ECE(bins, detection=True).measure; revision 2a3db8d), "
                "scripts/dece_reference_cases.py; image 1242 x 375 px\n")
        w = csv.writer(f, lineterminator="\n")
        for k, dets in enumerate(cases):
            for d in dets:
                w.writerow([k, "det"] + [repr(v) for v in d])
            a = np.asarray(dets, dtype=np.float64)
            features = np.stack([a[:, 4], (a[:, 0] + a[:, 2]) / 2 / W, (a[:, 1] + a[:, 3]) / 2 / H,
                                 (a[:, 2] - a[:, 0]) / W, (a[:, 3] - a[:, 1]) / H], axis=1)
            matched = a[:, 5].astype(int)
            for bins in layouts:
                value = ECE(bins=list(bins), detection=True).measure(features, matched)
                w.writerow([k, "dece"] + list(bins) + [repr(float(value))])
    tmp.replace(out)
    print(f"{len(cases)} cases x {len(layouts)} bin layouts -> {out}")


if __name__ == "__main__":
    main()
