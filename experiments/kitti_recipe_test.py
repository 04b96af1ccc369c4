#!/usr/bin/env python3
"""The KITTI recipe on a KITTI-layout miniature, so that it cannot rot (issue 39).

    kitti_recipe_test.py REPO BIN_DIR WORK_DIR

Writes a KITTI object layout of 6 synthetic frames at KITTI's size (1242 x 375, LiDAR, no
ImageSets/ in the root, as a KITTI download has none), and its train / val split files in a folder
of their own; then runs exactly what `make kitti-experiment` runs (experiments/kitti.json, --kitti
ROOT) with --kitti-splits (the miniature's ids instead of Chen et al.'s 7481) and --max-epochs 1.
Checks: every model of the recipe is trained (model.pt), detects and is evaluated on the val
frames, table1.md has a row per model and pair, nothing was written into the KITTI root, the
shipped split lists are Chen et al.'s (3712 + 3769 distinct ids, disjoint, 000000..007480 in
all), and the recipe refuses a config without --kitti and a KITTI root without training/, naming
what is missing. Prints one summary line and "ok".
"""
import hashlib
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(sys.argv[1]).resolve()
BIN = Path(sys.argv[2]).resolve()
WORK = Path(sys.argv[3]).resolve()


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def tree_digest(root):
    """Hash of every path and file's bytes under root (what the recipe must not change)."""
    h = hashlib.sha256()
    for p in sorted(root.rglob("*")):
        h.update(str(p.relative_to(root)).encode())
        if p.is_file():
            h.update(p.read_bytes())
    return h.hexdigest()


def experiment(*args):
    return subprocess.run(["/usr/bin/python3", str(REPO / "scripts" / "experiment.py"),
                           "--config", str(REPO / "experiments" / "kitti.json"), "--bin",
                           str(BIN), *args], capture_output=True, text=True)


def main():
    shutil.rmtree(WORK, ignore_errors=True)
    WORK.mkdir(parents=True)
    # The shipped lists: Chen et al.'s split of KITTI's 7481 training frames.
    train = (REPO / "experiments/kitti/ImageSets/train.txt").read_text().split()
    val = (REPO / "experiments/kitti/ImageSets/val.txt").read_text().split()
    if len(set(train)) != 3712 or len(set(val)) != 3769 or set(train) & set(val) or \
            set(train) | set(val) != {f"{i:06d}" for i in range(7481)}:
        fail("experiments/kitti/ImageSets is not the 3712 / 3769 split of 000000..007480")

    # A KITTI download's layout: training/ only; the split files elsewhere.
    synth = WORK / "synth"
    subprocess.run([str(BIN / "stereodet"), "synth", "--out", str(synth), "--frames", "6",
                    "--seed", "5", "--val-fraction", "0.5", "--threads", "2", "--quiet"],
                   check=True)
    kitti = WORK / "kitti"
    kitti.mkdir()
    shutil.move(str(synth / "training"), str(kitti / "training"))
    splits = WORK / "splits"
    shutil.move(str(synth / "ImageSets"), str(splits))
    before = tree_digest(kitti)

    # Refusals, before any step runs.
    p = experiment("--out", str(WORK / "out"))
    if p.returncode == 0 or "needs --kitti ROOT" not in p.stderr:
        fail(f"without --kitti: exit {p.returncode}: {p.stderr}")
    p = experiment("--kitti", str(WORK), "--out", str(WORK / "out"))
    if p.returncode == 0 or "has no training/ folder" not in p.stderr:
        fail(f"a root without training/: exit {p.returncode}: {p.stderr}")

    out = WORK / "out"
    p = experiment("--kitti", str(kitti), "--kitti-splits", str(splits), "--max-epochs", "1",
                   "--out", str(out))
    if p.returncode != 0:
        fail(f"the recipe exited {p.returncode}:\n{p.stdout[-3000:]}\n{p.stderr[-3000:]}")
    config = json.loads((REPO / "experiments" / "kitti.json").read_text())
    names = [m["name"] for m in config["models"]]
    for name in names:
        if not (out / "models" / name / "model.pt").is_file():
            fail(f"{name} was not trained")
        evals = list((out / "runs" / name).glob("*/eval-*/results.json"))
        if not evals:
            fail(f"{name} was not evaluated")
    table = (out / "table1.md").read_text()
    for name in names:
        if name not in table:
            fail(f"table1.md has no row for {name}")
    for a, b in config["pairs"]:
        if f"{a} vs {b}" not in table and f"{b} - {a}" not in table and \
                f"{a} - {b}" not in table and f"{b} vs {a}" not in table:
            fail(f"table1.md has no row for the pair {a}, {b}")
    if tree_digest(kitti) != before:
        fail("the recipe wrote into the KITTI root")
    steps = len(list((out / "steps").glob("*.json")))
    print(f"kitti recipe: {len(names)} models trained, detected and evaluated, {steps} steps, "
          f"the KITTI root untouched")
    print("ok")


if __name__ == "__main__":
    main()
