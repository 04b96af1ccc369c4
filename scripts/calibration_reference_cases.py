#!/usr/bin/env python3
"""Reference calibrators from scikit-learn and SciPy, for stereodet's test
(`CalibrationFitTest.AgreesWithScikitLearn` reads the files this writes; docs/metrics.md,
"Calibrators").

    scripts/calibration_reference_cases.py --out tests/data/calibration [--seed 37]

Needs scikit-learn and SciPy (Debian: python3-sklearn), which stereodet itself does not: this is a
one-off reference tool, like the Waymo harness. Draws six sets of (score, target) pairs as a
detector makes them (scores in (0, 1) whose chance of being a true positive is a bent function of
the score; two of the sets with scores rounded to two decimals, so that ties occur; 40 to 3000
pairs) and writes
  points.csv: case,score,target
  expected.csv: case,method,probe,probability: each method's calibrated probability at the
    probes 0, 0.025, ..., 1 (and at every tenth fitted score):
    platt: scikit-learn's _sigmoid_calibration (CalibratedClassifierCV(method="sigmoid")'s fit:
      Platt's smoothed targets, BFGS) on the scores' logits;
    isotonic: IsotonicRegression(out_of_bounds="clip");
    temperature: SciPy's bounded scalar minimisation of the negative log likelihood of
      sigmoid(logit / T), to 1e-10 in 1 / T.
"""

import argparse
import csv
import math
import pathlib
import random

import numpy as np
from scipy.optimize import minimize_scalar
from scipy.special import expit
from sklearn.calibration import _sigmoid_calibration
from sklearn.isotonic import IsotonicRegression


def logit(s):
    s = np.clip(np.asarray(s, dtype=np.float64), 1e-7, 1 - 1e-7)
    return np.log(s / (1 - s))


def draw(rng, n, decimals, bend):
    scores, targets = [], []
    for _ in range(n):
        s = rng.betavariate(2, 2)
        if decimals:
            s = round(s, decimals)
        s = min(max(s, 0.005), 0.995)
        p = s ** bend
        scores.append(s)
        targets.append(1 if rng.random() < p else 0)
    return scores, targets


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", required=True, help="the folder to write")
    parser.add_argument("--seed", type=int, default=37)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    cases = [draw(rng, n, d, b) for n, d, b in
             ((40, 0, 1.0), (300, 2, 2.0), (1000, 0, 0.5), (3000, 2, 1.5), (200, 0, 3.0),
              (800, 0, 1.0))]
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "points.csv.tmp", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["case", "score", "target"])
        for k, (scores, targets) in enumerate(cases):
            for s, t in zip(scores, targets):
                w.writerow([k, repr(s), t])
    with open(out / "expected.csv.tmp", "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["case", "method", "probe", "probability"])
        for k, (scores, targets) in enumerate(cases):
            s = np.asarray(scores)
            y = np.asarray(targets)
            x = logit(s)
            probes = sorted(set([i / 40 for i in range(41)] + scores[::10]))
            a, b = _sigmoid_calibration(x, y)  # P = expit(-(a x + b))
            iso = IsotonicRegression(out_of_bounds="clip").fit(s, y)

            def nll(slope):
                z = slope * x
                return float(np.sum(np.logaddexp(0, -z) * y + np.logaddexp(0, z) * (1 - y)))

            slope = minimize_scalar(nll, bounds=(1e-6, 100), method="bounded",
                                    options={"xatol": 1e-10}).x
            for probe in probes:
                xp = logit([probe])[0]
                w.writerow([k, "platt", repr(probe), repr(float(expit(-(a * xp + b))))])
                w.writerow([k, "isotonic", repr(probe), repr(float(iso.predict([probe])[0]))])
                w.writerow([k, "temperature", repr(probe), repr(float(expit(slope * xp)))])
    (out / "points.csv.tmp").replace(out / "points.csv")
    (out / "expected.csv.tmp").replace(out / "expected.csv")
    print(f"{len(cases)} cases, {sum(len(c[0]) for c in cases)} points -> {out}")


if __name__ == "__main__":
    main()
