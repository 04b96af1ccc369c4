#!/usr/bin/env python3
"""OpenPCDet's kitti_object_eval_python against stereodet.get_official_eval_result, on the same
annotation dicts (issue 12; figures in docs/BENCHMARKS.md).

    NUMBA_ENABLE_CUDASIM=1 PYTHONPATH=BUILD_DIR/python /usr/bin/python3 \\
        benchmarks/openpcdet_speed.py SCRATCH SET_DIR FRAMES [FRAMES ...]

SCRATCH: a folder holding a copy of OpenPCDet's pcdet/datasets/kitti/kitti_object_eval_python/
         (eval.py, rotate_iou.py, __init__.py; unmodified, never committed here), e.g.
         git -C OpenPCDet show HEAD:pcdet/datasets/kitti/kitti_object_eval_python/eval.py > ...
SET_DIR: a write_eval_set folder (label_2/, det/), e.g. benchmarks/python_eval.py's.
FRAMES:  subset sizes (the first N frames). OpenPCDet splits the frames into 100 parts and computes
         the BEV / 3D overlaps of each part's all-pairs in its numba CUDA kernel, which on a CPU runs
         under numba's CUDA simulator (NUMBA_ENABLE_CUDASIM=1, python3-numba): a 3769-frame set is
         100 parts of 37 frames and one of 69, so its time is about 100 T(37) + T(69), and a subset
         of fewer than 100 frames is one part. Each OpenPCDet run is done twice, the second (numba's
         JIT compilation done) reported; stereodet's is the fastest of 5.

Both read the same dicts (stereodet.kitti.read_objects; labels get OpenPCDet's zero scores), and
the script checks that the printouts and the figure dicts are identical.
"""

import os
import sys
import time


def timed(run):
    t, c = time.perf_counter(), time.process_time()
    result = run()
    return time.perf_counter() - t, time.process_time() - c, result


def main():
    if len(sys.argv) < 4:
        print(__doc__)
        return 2
    scratch, root, sizes = sys.argv[1], sys.argv[2], [int(n) for n in sys.argv[3:]]
    sys.path.insert(0, scratch)
    import numpy as np

    import stereodet
    from stereodet import kitti
    import kitti_object_eval_python.rotate_iou as rotate_iou
    # The simulator's threads race on the kernel module's __warningregistry__ (docs/metrics.md,
    # "Verification"); creating it beforehand changes no value.
    rotate_iou.__dict__.setdefault("__warningregistry__", {})
    from kitti_object_eval_python import eval as pcdet_eval

    classes = ["Car", "Pedestrian", "Cyclist"]
    ids = sorted(p[:-4] for p in os.listdir(os.path.join(root, "label_2")))
    gt = [kitti.read_objects(os.path.join(root, "label_2", f"{i}.txt")) for i in ids]
    dt = [kitti.read_objects(os.path.join(root, "det", f"{i}.txt"), "detection") for i in ids]
    for g in gt:
        g["score"] = np.zeros(len(g["name"]))  # as OpenPCDet's get_label_anno
    print(f"{'frames':>7} {'OpenPCDet wall s':>17} {'CPU s':>9} {'stereodet wall s':>17} "
          f"{'CPU s':>9} {'CPU ratio':>10}  identical")
    for n in sizes:
        ours = min((timed(lambda: stereodet.get_official_eval_result(gt[:n], dt[:n], classes))
                    for _ in range(5)), key=lambda r: r[0])
        for _ in range(2):
            theirs = timed(lambda: pcdet_eval.get_official_eval_result(gt[:n], dt[:n], classes))
        same = theirs[2][0] == ours[2][0] and theirs[2][1].keys() == ours[2][1].keys() and all(
            theirs[2][1][k] == ours[2][1][k] for k in ours[2][1])
        print(f"{n:7d} {theirs[0]:17.2f} {theirs[1]:9.2f} {ours[0]:17.4f} {ours[1]:9.4f} "
              f"{theirs[1] / ours[1]:10.0f}  {same}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
