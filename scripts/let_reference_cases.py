#!/usr/bin/env python3
"""LET-3D-AP's per-pair values from Waymo Open Dataset's own implementation, for stereodet's test
(docs/metrics.md, "LET-3D-AP"; `LetTest.WaymoReferenceCases` reads the file this writes).

    scripts/let_reference_cases.py --harness /tmp/waymo-ref/let_harness --out tests/data/let/waymo_cases.csv [--cases 400] [--seed 36]
    scripts/let_reference_cases.py --harness /tmp/waymo-ref/let_harness --frames-out tests/data/let/waymo_frames.csv [--frames 150] [--seed 36]

Draws random label / detection pairs in KITTI's rectified camera frame (x right, y down, z
forward; a label 2-75 m away, its detection moved along and across the line of sight, resized and
turned, or drawn anywhere near it) with a random sensor position near the origin, converts each
pair to Waymo's vehicle frame (x forward, y left, z up; box centres; heading = -rotation_y - pi/2),
runs the harness (a program linked against Waymo's metrics code: its ComputeLetIoU, range-aligned,
for 3D and BEV boxes, and ComputeLongitudinalAffinity, tolerance 10 % of the range, at least 0.5 m)
and writes one CSV row per pair: the KITTI-frame boxes (h, w, l, x, y, z, rotation_y of the bottom
centre, as a label file has them), the sensor, and Waymo's three values. The harness is not part of
stereodet: docs/metrics.md says how it was built from Waymo's repository.

With --frames-out, whole frames instead (`LetTest.WaymoReferenceFrames`): 1-4 cars per frame, 2-60
m away and apart from each other as parked and passing cars are, each detected (85 %) with a
depth error along its line of sight up to 20 % of its range, a little lateral noise, resized and
turned; a second detection of it (25 %); and 0-2 detections of nothing. Scores on a 0.05 grid. The
sensor at the camera frame's origin. The harness runs Waymo's whole metric (Hungarian matcher, IoU
threshold 0.5, LET enabled) at score cutoffs 0, 0.05, ..., 0.95 for 3D and BEV boxes, and the file
gets every object (rows "label" / "det") and then every cutoff's TP, FP, FN and sum of
longitudinal affinities (rows "counts").
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


def draw_frame(rng):
    """One frame's labels and detections (KITTI camera-frame boxes; detections with a score)."""
    labels = []
    while len(labels) < rng.randint(1, 4):
        r, bearing = rng.uniform(2, 60), rng.uniform(-0.6, 0.6)
        x, z = r * math.sin(bearing), r * math.cos(bearing)
        if any(math.hypot(x - l[3], z - l[5]) < 7 for l in labels):
            continue  # cars do not overlap: at least 7 m between centres
        labels.append([rng.uniform(1.2, 2.0), rng.uniform(1.4, 2.0), rng.uniform(3.2, 5.0),
                       x, rng.uniform(1.0, 2.2), z, rng.uniform(-math.pi, math.pi)])
    dets = []

    def detect(label):
        h, w, l, x, y, z, ry = label
        centre = [x, y - h / 2, z]
        norm = math.sqrt(sum(c * c for c in centre))
        e = rng.uniform(-0.2, 0.2) * norm
        centre = [c + e * c / norm for c in centre]
        centre[0] += rng.gauss(0, 0.1)
        centre[2] += rng.gauss(0, 0.1)
        dims = [d * rng.uniform(0.9, 1.1) for d in (h, w, l)]
        return [dims[0], dims[1], dims[2], centre[0], centre[1] + dims[0] / 2, centre[2],
                ry + rng.gauss(0, 0.1)]

    for label in labels:
        if rng.random() < 0.85:
            dets.append(detect(label))
            if rng.random() < 0.25:
                dets.append(detect(label))
    for _ in range(rng.randint(0, 2)):
        r, bearing = rng.uniform(2, 60), rng.uniform(-0.6, 0.6)
        dets.append([rng.uniform(1.2, 2.0), rng.uniform(1.4, 2.0), rng.uniform(3.2, 5.0),
                     r * math.sin(bearing), rng.uniform(1.0, 2.2), r * math.cos(bearing),
                     rng.uniform(-math.pi, math.pi)])
    dets = [d + [round(rng.randint(1, 19) * 0.05, 2)] for d in dets]
    return labels, dets


CUTOFFS = [round(0.05 * k, 2) for k in range(20)]


def run_frames(harness, frames, box_type):
    """Waymo's TP, FP, FN and sum of affinities at each of CUTOFFS over all frames."""
    with tempfile.TemporaryDirectory() as tmp:
        inp = pathlib.Path(tmp) / "in.json"
        res = pathlib.Path(tmp) / "out.json"
        inp.write_text(json.dumps({
            "box_type": box_type, "iou_threshold": 0.5, "score_cutoffs": CUTOFFS,
            "let": {"enabled": True, "percentage": 0.1, "min_meter": 0.5,
                    "sensor": [0.0, 0.0, 0.0], "align": "range"},
            "matcher": "hungarian",
            "frames": [{"gts": [to_waymo(l) for l in labels],
                        "pds": [to_waymo(d[:7]) + [d[7]] for d in dets]}
                       for labels, dets in frames]}))
        subprocess.run([harness, str(inp), str(res)], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
        return json.loads(res.read_text())["cutoffs"]


def write_frames(harness, path, num_frames, seed):
    rng = random.Random(seed)
    frames = [draw_frame(rng) for _ in range(num_frames)]
    counts = {box_type: run_frames(harness, frames, box_type) for box_type in ("3d", "bev")}
    out = pathlib.Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(".tmp")
    with open(tmp, "w", newline="") as f:
        f.write("# LET-3D-AP on whole frames from Waymo Open Dataset's metrics code (Hungarian "
                "matcher, IoU >= 0.5, LET 10 %, >= 0.5 m, sensor at the origin), "
                "scripts/let_reference_cases.py --frames-out; KITTI camera frame, m, rad. Rows "
                "label/det: frame,role,h,w,l,x,y,z,ry,score; rows counts: "
                "box_type,counts,cutoff,tp,fp,fn,sum_affinity\n")
        w = csv.writer(f, lineterminator="\n")
        for k, (labels, dets) in enumerate(frames):
            for label in labels:
                w.writerow([k, "label"] + [repr(v) for v in label] + [""])
            for det in dets:
                w.writerow([k, "det"] + [repr(v) for v in det])
        for box_type, rows in counts.items():
            for row in rows:
                w.writerow([box_type, "counts", repr(row["score_cutoff"]), row["num_tps"],
                            row["num_fps"], row["num_fns"],
                            repr(row["sum_longitudinal_affinity"])])
    tmp.replace(out)
    labels = sum(len(l) for l, _ in frames)
    dets = sum(len(d) for _, d in frames)
    first = counts["3d"][0]
    print(f"{num_frames} frames, {labels} labels, {dets} detections -> {out} (3D at cutoff 0: "
          f"TP {first['num_tps']} FP {first['num_fps']} FN {first['num_fns']})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--harness", required=True, help="the let_harness program")
    parser.add_argument("--out", help="the per-pair CSV to write")
    parser.add_argument("--cases", type=int, default=400)
    parser.add_argument("--frames-out", help="the whole-frame CSV to write instead")
    parser.add_argument("--frames", type=int, default=150)
    parser.add_argument("--seed", type=int, default=36)
    args = parser.parse_args()
    if (args.out is None) == (args.frames_out is None):
        parser.error("give one of --out (pairs) and --frames-out (frames)")
    if args.frames_out:
        write_frames(args.harness, args.frames_out, args.frames, args.seed)
        return
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
        w = csv.writer(f, lineterminator="\n")
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
