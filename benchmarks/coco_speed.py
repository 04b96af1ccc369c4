#!/usr/bin/env python3
"""Times `stereodet eval --coco-gt --coco-det` against pycocotools' COCOeval on one synthetic set.

The set has COCO val2017's shape (defaults: 5000 images, 80 categories, about 36k ground truths,
100 detections per image; issue 38): per image a few categories, boxes of every area range in
COCO's proportions, declared areas smaller than the boxes (as a segment's), 1% crowds, and
detections that are jittered copies of the boxes, duplicates and false positives, with scores
higher for the better ones. Both programs run in their own process, one after the other, on the
same files; the script reports each one's CPU time (user + system) and peak resident memory from
wait4(), the time each spends reading and evaluating, and checks that the 12 printed numbers are
identical. Each stereodet command runs --repeat times (5), the median CPU run reported. Also times the optimal matcher (`--matcher optimal`) and the operating-point metrics
(`--coco-brier`) against the greedy evaluation, one thread each. Writes the markdown rows for
docs/BENCHMARKS.md.

    STEREODET_PYCOCOTOOLS=/tmp/coco-ref/PythonAPI /usr/bin/python3 benchmarks/coco_speed.py \
        --stereodet build/bin/stereodet --work /tmp/coco-speed
"""

import argparse
import datetime
import json
import multiprocessing
import os
import platform
import random
import subprocess
import sys
import time

PYCOCOTOOLS_RUN = r"""
import contextlib, io, sys, time
sys.path.insert(0, sys.argv[1]) if sys.argv[1] else None
from pycocotools.coco import COCO
from pycocotools.cocoeval import COCOeval
t0 = time.process_time()
with contextlib.redirect_stdout(io.StringIO()):
    gt = COCO(sys.argv[2])
    dt = gt.loadRes(sys.argv[3])
t1 = time.process_time()
with contextlib.redirect_stdout(io.StringIO()):
    e = COCOeval(gt, dt, 'bbox')
    e.evaluate()
    e.accumulate()
e.summarize()
t2 = time.process_time()
print(f"read_cpu_s {t1 - t0:.3f}")
print(f"eval_cpu_s {t2 - t1:.3f}")
"""


def make_set(args):
    rng = random.Random(args.seed)
    categories = [{"id": c, "name": f"c{c}"} for c in range(1, args.categories + 1)]
    images, annotations, dets = [], [], []
    gt_per_image = args.gt / args.images
    next_id = 1
    for image in range(1, args.images + 1):
        images.append({"id": image, "width": 640, "height": 480, "file_name": f"{image}.jpg"})
        present = rng.sample(range(1, args.categories + 1), rng.randint(1, 6))
        boxes = []
        for _ in range(max(0, round(rng.expovariate(1 / gt_per_image)))):
            # COCO's mix: about 41% small, 34% medium, 24% large.
            side = rng.choice([rng.uniform(4, 32), rng.uniform(4, 32), rng.uniform(32, 96),
                               rng.uniform(32, 96), rng.uniform(96, 400)])
            w, h = side * rng.uniform(0.6, 1.4), side * rng.uniform(0.6, 1.4)
            box = [rng.uniform(0, 640 - min(w, 600)), rng.uniform(0, 480 - min(h, 440)), w, h]
            category = rng.choice(present)
            crowd = rng.random() < 0.01
            annotations.append({"id": next_id, "image_id": image, "category_id": category,
                                "bbox": [round(v, 2) for v in box],
                                "area": round(w * h * rng.uniform(0.5, 0.9), 2),
                                "iscrowd": int(crowd)})
            boxes.append((box, category))
            next_id += 1
        image_dets = []
        for box, category in boxes:
            for _ in range(rng.choice([1, 1, 2, 3])):
                a = rng.choice([0.02, 0.05, 0.1, 0.2])
                x, y, w, h = box
                d = [x + rng.uniform(-a, a) * w, y + rng.uniform(-a, a) * h,
                     w * (1 + rng.uniform(-a, a)), h * (1 + rng.uniform(-a, a))]
                image_dets.append((d, category, rng.uniform(0.3, 1.0) * (1 - a)))
        while len(image_dets) < args.dets_per_image:
            side = rng.uniform(8, 200)
            d = [rng.uniform(0, 600), rng.uniform(0, 440), side * rng.uniform(0.6, 1.4),
                 side * rng.uniform(0.6, 1.4)]
            category = rng.choice(present) if rng.random() < 0.7 else rng.randint(1, args.categories)
            image_dets.append((d, category, rng.uniform(0.0, 0.6)))
        for d, category, score in image_dets[:args.dets_per_image]:
            dets.append({"image_id": image, "category_id": category,
                         "bbox": [round(v, 2) for v in d], "score": round(score, 5)})
    gt = {"info": {}, "images": images, "categories": categories, "annotations": annotations}
    return gt, dets


def run_with_rusage(command):
    """Runs `command`; returns (stdout, wall s, CPU s, peak RSS MiB) of that child alone (wait4)."""
    start = time.monotonic()
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    out = proc.stdout.read().decode()
    err = proc.stderr.read().decode()
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    wall = time.monotonic() - start
    if proc.returncode:
        raise RuntimeError(f"{' '.join(command[:2])} failed ({proc.returncode}): {err.strip()}")
    return out, wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024


def write_set(args, gt_path, det_path):
    gt, dets = make_set(args)
    with open(gt_path, "w") as f:
        json.dump(gt, f)
    with open(det_path, "w") as f:
        json.dump(dets, f)
    print(f"set: {len(gt['images'])} images, {len(gt['categories'])} categories, "
          f"{len(gt['annotations'])} ground truths, {len(dets)} detections; "
          f"{os.path.getsize(gt_path) / 2**20:.1f} + {os.path.getsize(det_path) / 2**20:.1f} MiB",
          flush=True)


def run_median(command, repeat):
    """run_with_rusage `repeat` times; the run of median CPU (these VMs are shared: single runs of
    the same command differ by up to 1.6x)."""
    runs = sorted((run_with_rusage(command) for _ in range(repeat)), key=lambda r: r[2])
    return runs[len(runs) // 2]


def summary_lines(text):
    return [l for l in text.splitlines() if l.startswith(" Average")]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--stereodet", default="build/bin/stereodet")
    parser.add_argument("--pycocotools", default=os.environ.get("STEREODET_PYCOCOTOOLS", ""))
    parser.add_argument("--python", default="/usr/bin/python3", help="runs pycocotools")
    parser.add_argument("--work", default="/tmp/stereodet-coco-speed", help="where the set goes")
    parser.add_argument("--images", type=int, default=5000)
    parser.add_argument("--categories", type=int, default=80)
    parser.add_argument("--gt", type=int, default=36000, help="ground truths, about")
    parser.add_argument("--dets-per-image", type=int, default=100)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--repeat", type=int, default=5,
                        help="runs of each stereodet command; the median CPU one is reported")
    args = parser.parse_args()

    os.makedirs(args.work, exist_ok=True)
    gt_path, det_path = (os.path.join(args.work, n) for n in ("gt.json", "det.json"))
    # The set is made in a child process: a program this script starts is forked from it, and
    # the fork's pages count in the program's peak RSS (wait4's ru_maxrss survives exec), so the
    # script must stay small (making the set here reported 252 MiB for a run of 85).
    maker = multiprocessing.Process(target=write_set, args=(args, gt_path, det_path))
    maker.start()
    maker.join()
    if maker.exitcode != 0:
        raise RuntimeError(f"making the set failed ({maker.exitcode})")

    rows = []
    ours = {}
    for threads in (1, 0):
        out, wall, cpu, rss = run_median(
            [args.stereodet, "eval", "--coco-gt", gt_path, "--coco-det", det_path,
             "--threads", str(threads)], args.repeat)
        tail = [l for l in out.splitlines() if "evaluated in" in l][0]
        ours[threads] = (out, wall, cpu, rss, tail)
        label = "stereodet, 1 thread" if threads == 1 else "stereodet, all threads"
        rows.append((label, wall, cpu, rss, tail.split("; ")[1]))
    # The optimal matcher against the greedy one (target: within 2x), and what the operating-point
    # metrics (--coco-brier) add to each; one thread, the evaluation's own wall time compared.
    evaluated = {}
    for label, extra in (("greedy", []), ("optimal", ["--matcher", "optimal"]),
                         ("greedy --coco-brier", ["--coco-brier"]),
                         ("optimal --coco-brier", ["--matcher", "optimal", "--coco-brier"])):
        out, wall, cpu, rss = run_median(
            [args.stereodet, "eval", "--coco-gt", gt_path, "--coco-det", det_path,
             "--threads", "1"] + extra, args.repeat)
        tail = [l for l in out.splitlines() if "evaluated in" in l][0]
        evaluated[label] = float(tail.split("evaluated in ")[1].split(" s")[0])
        if extra:
            rows.append((f"stereodet {' '.join(extra)}, 1 thread", wall, cpu, rss,
                         tail.split("; ")[1]))
    print("evaluation alone, 1 thread (s): " +
          ", ".join(f"{k} {v:.3f}" for k, v in evaluated.items()))
    print(f"optimal / greedy: {evaluated['optimal'] / evaluated['greedy']:.2f}x; with --coco-brier "
          f"{evaluated['optimal --coco-brier'] / evaluated['greedy --coco-brier']:.2f}x")
    reference = None
    try:
        out, wall, cpu, rss = run_with_rusage(
            [args.python, "-c", PYCOCOTOOLS_RUN, args.pycocotools, gt_path, det_path])
        reference = out
        times = dict(l.split() for l in out.splitlines() if l.split()[:1] and
                     l.split()[0].endswith("_cpu_s"))
        rows.append(("pycocotools 2.0", wall, cpu, rss,
                     f"read {float(times['read_cpu_s']):.2f} s, evaluate + accumulate + "
                     f"summarize {float(times['eval_cpu_s']):.2f} s CPU"))
    except RuntimeError as e:
        print(f"pycocotools not run: {e}")

    print("| program | wall s | CPU s | peak RSS MiB | of which |")
    print("|---|---|---|---|---|")
    for label, wall, cpu, rss, detail in rows:
        print(f"| {label} | {wall:.2f} | {cpu:.2f} | {rss:.0f} | {detail} |")
    if reference is not None:
        same = summary_lines(reference) == summary_lines(ours[1][0]) == summary_lines(ours[0][0])
        print(f"12 printed numbers identical: {'yes' if same else 'NO'}")
        print(f"CPU ratio pycocotools / stereodet (1 thread): {rows[-1][2] / rows[0][2]:.1f}x")
        for line in summary_lines(ours[1][0]):
            print(line)
        if not same:
            return 1
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
          f"{datetime.date.today().isoformat()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
