#!/usr/bin/env python3
"""LET-3D-AP's per-pair values from Waymo Open Dataset's own implementation, for stereodet's test
(docs/metrics.md, "LET-3D-AP"; `LetTest.WaymoReferenceCases` reads the file this writes).

    scripts/let_reference_cases.py --harness /tmp/waymo-ref/let_harness --out tests/data/let/waymo_cases.csv [--cases 400] [--seed 36]

Draws random label / detection pairs in KITTI's rectified camera frame (x right, y down, z
forward; a label 2-75 m away, its detection moved along and across the line of sight, resized and
turned, or drawn anywhere near it) with a random sensor position near the origin, converts each
pair to Waymo's vehicle frame (x forward, y left, z up; box centres; heading = -rotation_y - pi/2),
runs the harness (a program linked against Waymo's metrics code: its ComputeLetIoU, range-aligned,
for 3D and BEV boxes, and ComputeLongitudinalAffinity, tolerance 10 % of the range, at least 0.5 m)
and writes one CSV row per pair: the KITTI-frame boxes (h, w, l, x, y, z, rotation_y of the bottom
centre, as a label file has them), the sensor, and Waymo's three values. The harness is not part of
stereodet: docs/metrics.md says how it was built from Waymo's repository.
"""

import argparse
import csv
import json
import math
import pathlib
import random
import subprocess
import tempfile


def to_waymo(box):
    """KITTI camera-frame box (h, w, l, x, y, z bottom centre, ry) -> Waymo [cx, cy, cz, length,
    width, height, heading] in the vehicle frame, its centre the box's geometric centre."""
    h, w, l, x, y, z, ry = box
    cy_cam = y - h / 2
    return [z, -x, -cy_cam, l, w, h, -ry - math.pi / 2]


def draw(rng):
    r = rng.uniform(2, 75)
    bearing = rng.uniform(-0.6, 0.6)
    label = [rng.uniform(1.2, 2.0), rng.uniform(1.4, 2.0), rng.uniform(3.2, 5.0),
             r * math.sin(bearing), rng.uniform(1.0, 2.2), r * math.cos(bearing),
             rng.uniform(-math.pi, math.pi)]
    h, w, l, x, y, z, ry = label
    kind = rng.random()
    centre = [x, y - h / 2, z]
    norm = math.sqrt(sum(c * c for c in centre))
    if kind < 0.7:  # along the line of sight (depth error), a little across, resized, turned
        e = rng.uniform(-0.2, 0.2) * norm
        centre = [c + e * c / norm for c in centre]
        centre[0] += rng.gauss(0, 0.2)
        centre[2] += rng.gauss(0, 0.2)
        dims = [d * rng.uniform(0.85, 1.15) for d in (h, w, l)]
        turn = ry + rng.gauss(0, 0.15)
    elif kind < 0.85:  # exactly the label, or on its line of sight only
        e = rng.choice([0.0, rng.uniform(-0.3, 0.3) * norm])
        centre = [c + e * c / norm for c in centre]
        dims, turn = [h, w, l], ry
    else:  # anywhere near it
        centre = [c + rng.uniform(-3, 3) for c in centre]
        dims = [rng.uniform(1.2, 2.0), rng.uniform(1.4, 2.0), rng.uniform(3.2, 5.0)]
        turn = rng.uniform(-math.pi, math.pi)
    detection = [dims[0], dims[1], dims[2], centre[0], centre[1] + dims[0] / 2, centre[2], turn]
    sensor = [rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)] \
        if rng.random() < 0.5 else [0.0, 0.0, 0.0]
    return label, detection, sensor


def run_harness(harness, pairs, box_type):
    """Waymo's LET-IoU and affinity of each pair, one frame per pair (the sensor differs)."""
    out = []
    with tempfile.TemporaryDirectory() as tmp:
        # One harness run per sensor position (the LET config is per run).
        by_sensor = {}
        for i, (label, det, sensor) in enumerate(pairs):
            by_sensor.setdefault(tuple(sensor), []).append(i)
        values = [None] * len(pairs)
        for sensor, indices in by_sensor.items():
            s = [sensor[2], -sensor[0], -sensor[1]]  # camera frame -> vehicle frame
            frames = [{"gts": [to_waymo(pairs[i][0])], "pds": [to_waymo(pairs[i][1]) + [0.5]]}
                      for i in indices]
            inp = pathlib.Path(tmp) / "in.json"
            res = pathlib.Path(tmp) / "out.json"
            inp.write_text(json.dumps({"box_type": box_type, "iou_threshold": 0.5,
                                       "let": {"enabled": True, "percentage": 0.1,
                                               "min_meter": 0.5, "sensor": s, "align": "range"},
                                       "matcher": "hungarian", "frames": frames}))
            subprocess.run([harness, str(inp), str(res)], check=True, stdout=subprocess.DEVNULL)
            got = json.loads(res.read_text())
            for k, i in enumerate(indices):
                values[i] = (got["let_iou"][k][0][0], got["affinity"][k][0][0])
        out = values
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--harness", required=True, help="the let_harness program")
    parser.add_argument("--out", required=True, help="the CSV to write")
    parser.add_argument("--cases", type=int, default=400)
    parser.add_argument("--seed", type=int, default=36)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    pairs = [draw(rng) for _ in range(args.cases)]
    three_d = run_harness(args.harness, pairs, "3d")
    bev = run_harness(args.harness, pairs, "bev")
    out = pathlib.Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(".tmp")
    with open(tmp, "w", newline="") as f:
        f.write("# LET-3D-AP per-pair values from Waymo Open Dataset's metrics code (ComputeLetIoU, "
                "range-aligned; ComputeLongitudinalAffinity, 10 %, >= 0.5 m), "
                "scripts/let_reference_cases.py; KITTI camera frame, m, rad\n")
        w = csv.writer(f)
        w.writerow(["label_h", "label_w", "label_l", "label_x", "label_y", "label_z", "label_ry",
                    "det_h", "det_w", "det_l", "det_x", "det_y", "det_z", "det_ry",
                    "sensor_x", "sensor_y", "sensor_z", "let_iou_3d", "let_iou_bev", "affinity"])
        for (label, det, sensor), (iou3d, aff), (ioubev, aff_bev) in zip(pairs, three_d, bev):
            assert aff == aff_bev
            w.writerow([repr(v) for v in label + det + sensor] + [repr(iou3d), repr(ioubev),
                                                                   repr(aff)])
    tmp.replace(out)
    matched = sum(1 for (i3, a), _ in zip(three_d, bev) if a > 0 and i3 >= 0.5)
    print(f"{len(pairs)} pairs -> {out} ({matched} with affinity > 0 and 3D LET-IoU >= 0.5)")


if __name__ == "__main__":
    main()
