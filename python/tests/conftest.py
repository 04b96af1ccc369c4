"""Shared fixtures of the Python tests.

ctest runs each file as `python3 -m pytest FILE` from the checkout with PYTHONPATH=build/python and
STEREODET_BUILD_DIR set (python/CMakeLists.txt); by hand:
    PYTHONPATH=build/python /usr/bin/python3 -m pytest python/tests
"""

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"


def build_dir() -> Path:
    return Path(os.environ.get("STEREODET_BUILD_DIR", REPO / "build")).resolve()


@pytest.fixture(scope="session")
def build() -> Path:
    return build_dir()


@pytest.fixture(scope="session")
def cli(build):
    """Runs build/bin/stereodet with the given arguments; returns the CompletedProcess."""
    binary = build / "bin" / "stereodet"
    if not binary.exists():
        pytest.fail(f"{binary} is not built (cmake --build build)")

    def run(*args, check=True):
        result = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        if check and result.returncode != 0:
            raise AssertionError(f"stereodet {' '.join(map(str, args))} failed:\n{result.stderr}")
        return result

    return run


@pytest.fixture(scope="session")
def data() -> Path:
    return DATA


def random_annos(num_frames: int, seed: int):
    """KITTI-like labels and noisy detections of them (plus false positives) as annotation dicts:
    cars, pedestrians, cyclists, vans and DontCare regions, 2D boxes that fit the 3D ones roughly,
    numbers rounded to 2 decimals as KITTI writes them. Returns (gt_annos, dt_annos)."""
    import numpy as np

    rng = np.random.default_rng(seed)
    kinds = {"Car": (1.5, 1.6, 3.9), "Van": (2.2, 1.9, 5.0), "Pedestrian": (1.75, 0.6, 0.8),
             "Cyclist": (1.7, 0.6, 1.8)}
    names = list(kinds)
    gt, dt = [], []
    for _ in range(num_frames):
        n = rng.integers(0, 9)
        name = rng.choice(names + ["DontCare"], size=n, p=[0.5, 0.1, 0.2, 0.1, 0.1])
        z = rng.uniform(5, 60, n)
        x = rng.uniform(-15, 15, n)
        y = rng.uniform(1.4, 1.9, n)
        hwl = np.array([kinds.get(k, (1.5, 1.6, 3.9)) for k in name]).reshape(-1, 3)
        hwl = hwl * rng.uniform(0.9, 1.1, (n, 3))
        ry = rng.uniform(-np.pi, np.pi, n)
        u = 610 + 720 * x / z
        v = 175 + 720 * (y - hwl[:, 0] / 2) / z
        half_w = 720 * np.maximum(hwl[:, 1], hwl[:, 2]) / z / 2 + 2
        half_h = 720 * hwl[:, 0] / z / 2
        bbox = np.stack([u - half_w, v - half_h, u + half_w, v + half_h], axis=1)
        labels = {
            "name": name,
            "truncated": np.round(rng.choice([0.0, 0.0, 0.0, 0.3, 0.6], n), 2),
            "occluded": rng.choice([0, 0, 1, 2, 3], n),
            "alpha": np.round(ry - np.arctan2(x, z), 2),
            "bbox": np.round(bbox, 2),
            "dimensions": np.round(hwl[:, [2, 0, 1]], 2),
            "location": np.round(np.stack([x, y, z], axis=1), 2),
            "rotation_y": np.round(ry, 2),
        }
        dont = name == "DontCare"
        for key, value in (("truncated", -1.0), ("occluded", -1), ("alpha", -10.0),
                           ("rotation_y", -10.0)):
            labels[key][dont] = value
        labels["dimensions"][dont] = -1.0
        labels["location"][dont] = -1000.0
        gt.append(labels)
        # Detections: most real objects once (some twice), jittered, plus false positives.
        keep = np.flatnonzero(~dont & (rng.uniform(size=n) < 0.85))
        keep = np.concatenate([keep, keep[rng.uniform(size=len(keep)) < 0.3]])
        m = len(keep)
        fp = rng.integers(0, 3)
        det = {key: value[keep] for key, value in labels.items()}
        det["bbox"] = det["bbox"] + rng.normal(0, 3, (m, 4))
        det["location"] = det["location"] * (1 + rng.normal(0, 0.02, (m, 3)))
        det["dimensions"] = det["dimensions"] * (1 + rng.normal(0, 0.05, (m, 3)))
        det["rotation_y"] = det["rotation_y"] + rng.normal(0, 0.1, m)
        det["alpha"] = det["alpha"] + rng.normal(0, 0.1, m)
        for key, value in det.items():
            if key != "name" and value.dtype.kind == "f":
                det[key] = np.round(value, 2)
        extra = {
            "name": rng.choice(["Car", "Pedestrian", "Cyclist"], fp),
            "truncated": np.zeros(fp), "occluded": np.zeros(fp, dtype=int),
            "alpha": np.round(rng.uniform(-3, 3, fp), 2),
            "bbox": np.round(np.sort(rng.uniform(0, 1200, (fp, 2)), axis=1)[:, [0, 0, 1, 1]]
                             * [1, 0.2, 1, 0.3], 2),
            "dimensions": np.round(rng.uniform(0.5, 4, (fp, 3)), 2),
            "location": np.round(np.c_[rng.uniform(-10, 10, fp), np.full(fp, 1.6),
                                       rng.uniform(5, 50, fp)], 2),
            "rotation_y": np.round(rng.uniform(-3, 3, fp), 2),
        }
        det = {key: np.concatenate([det[key], extra[key]]) for key in det}
        det["score"] = np.round(rng.uniform(0.05, 1, len(det["name"])), 2)
        dt.append(det)
    return gt, dt


def write_folders(root, gt_annos, dt_annos):
    """Writes annotation lists as label_2/ and det/ folders of KITTI files (frame ids 000000...)."""
    from stereodet import kitti

    (root / "label_2").mkdir(parents=True)
    (root / "det").mkdir()
    for i, (g, d) in enumerate(zip(gt_annos, dt_annos)):
        kitti.write_objects(root / "label_2" / f"{i:06d}.txt", g, "label")
        kitti.write_objects(root / "det" / f"{i:06d}.txt", d, "detection")
    return root / "label_2", root / "det"
