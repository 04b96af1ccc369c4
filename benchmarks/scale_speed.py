"""stereodet.scale throughput (docs/BENCHMARKS.md "Scale", docs/scale.md): stereo encoding and
evaluation on a local Dask cluster of 1 and 2 workers against one process, and the overhead per
task.

    PYTHONPATH=build/python /usr/bin/python3 benchmarks/scale_speed.py [--build build]
        [--stereo-frames 48] [--eval-frames 20000] [--repeats 2] [--work /tmp/stereodet-scale-speed]

What it runs (wall-clock seconds of each, best of --repeats, the configurations interleaved so
that a change of load hits all of them):
- stereo: `stereodet stereo` (BM, RGB-H) of --stereo-frames synthetic 621 x 188 frames: one
  process with --threads 1 and --threads 2, then `stereodet.scale stereo` in 4 tasks of
  --threads 1 on 1 and on 2 workers (each task a subprocess; a fresh output folder every time).
- eval: `stereodet eval` (kitti matcher) of --eval-frames random frames (write_eval_set): one
  process with --threads 1 and 2, then `stereodet.scale eval` in 4 tasks of --threads 1 on 1 and
  2 workers, as subprocesses and in process (--in-process), plus its `eval merge` (serial, timed
  apart).
- overhead per task: on 1 worker, 12 stereo frames as 12 one-frame tasks against one 12-frame
  task: (T12 - T1) / 11.
- T0: the start of each LocalCluster.
Prints one Markdown table. Needs Debian python3-distributed, and the build's stereodet,
stereodet-vision and write_eval_set.
"""

import argparse
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

from stereodet import scale


def timed(fn):
    start = time.monotonic()
    fn()
    return time.monotonic() - start


def run(argv):
    subprocess.run([str(a) for a in argv], check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.PIPE)


def fresh(path: Path) -> Path:
    shutil.rmtree(path, ignore_errors=True)
    return path


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--build", default="build", type=Path)
    p.add_argument("--stereo-frames", type=int, default=48)
    p.add_argument("--eval-frames", type=int, default=20000)
    p.add_argument("--repeats", type=int, default=2)
    p.add_argument("--work", default="/tmp/stereodet-scale-speed", type=Path)
    args = p.parse_args()
    from distributed import Client, LocalCluster

    bin_dir = scale.find_bin_dir(str(args.build / "bin"))
    load_before = os.getloadavg()[0]
    work = fresh(args.work)
    work.mkdir(parents=True)
    data, evalset = work / "data", work / "evalset"
    run([bin_dir / "stereodet-vision", "synth", "--out", data, "--frames", args.stereo_frames,
         "--width", 621, "--height", 188, "--no-lidar", "--seed", 1, "--quiet"])
    run([args.build / "benchmarks" / "write_eval_set", "--out", evalset, "--frames",
         args.eval_frames])
    gt, det = evalset, evalset / "det"
    sf, ef = args.stereo_frames, args.eval_frames
    best = {}

    def note(key, seconds):
        best[key] = min(best.get(key, float("inf")), seconds)

    clusters = {}
    for workers in (1, 2):
        start = time.monotonic()
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
        client.wait_for_workers(workers)
        clusters[workers] = (cluster, client)
        note(f"T0 {workers}", time.monotonic() - start)

    def quiet(line):
        pass

    for _ in range(args.repeats):
        for threads in (1, 2):
            note(f"stereo 1p t{threads}", timed(lambda: run(
                [bin_dir / "stereodet-vision", "stereo", "--data", data, "--out",
                 fresh(work / "s1p"), "--threads", threads, "--quiet"])))
            note(f"eval 1p t{threads}", timed(lambda: run(
                [bin_dir / "stereodet", "eval", "--gt", gt, "--det", det, "--out",
                 fresh(work / "e1p"), "--threads", threads])))
        for workers, (_, client) in clusters.items():
            tasks = scale.stereo_tasks(bin_dir, data, fresh(work / "sdask"), None,
                                       (sf + 3) // 4, ["--threads", "1"])
            note(f"stereo dask w{workers}", timed(lambda: scale.run_tasks(client, tasks, quiet)))
            etasks = scale.eval_tasks(bin_dir, gt, det, fresh(work / "edask"), None,
                                      (ef + 3) // 4, ["--threads", "1"])
            note(f"eval dask w{workers}", timed(lambda: scale.run_tasks(client, etasks, quiet)))
            itasks = scale.eval_tasks(bin_dir, gt, det, fresh(work / "edask"), None,
                                      (ef + 3) // 4, ["--threads", "1"], in_process=True)
            note(f"eval inproc w{workers}", timed(lambda: scale.run_tasks(client, itasks, quiet)))
            note(f"eval merge w{workers}", timed(lambda: scale.eval_merge(
                bin_dir, work / "edask", len(etasks), ["--threads", "1"])))
        client = clusters[1][1]
        split = work / "first12.txt"
        split.write_text("".join(f"{i:06d}\n" for i in range(12)))
        for task_frames, key in ((12, "1 task"), (1, "12 tasks")):
            tasks = scale.stereo_tasks(bin_dir, data, fresh(work / "sover"), str(split),
                                       task_frames, ["--threads", "1"])
            assert len(tasks) == (1 if task_frames == 12 else 12)
            note(f"overhead {key}", timed(lambda: scale.run_tasks(client, tasks, quiet)))
    for cluster, client in clusters.values():
        client.close()
        cluster.close()

    def row(name, frames, key, base):
        s = best[key]
        return f"| {name} | {s:.2f} | {frames / s:.1f} | {best[base] / s:.2f}x |"

    print(f"stereo: {sf} frames 621 x 188 (BM, RGB-H); eval: {ef} frames (kitti matcher); "
          f"best of {args.repeats}; {os.cpu_count()} cores, load average {load_before:.1f} at "
          f"the start, {os.getloadavg()[0]:.1f} at the end")
    print("| run | seconds | frames/s | vs one process, 1 thread |")
    print("|---|---|---|---|")
    for what, frames in (("stereo", sf), ("eval", ef)):
        base = f"{what} 1p t1"
        print(row(f"{what}: one process, --threads 1", frames, base, base))
        print(row(f"{what}: one process, --threads 2", frames, f"{what} 1p t2", base))
        for w in (1, 2):
            print(row(f"{what}: Dask, {w} worker(s), 4 tasks of --threads 1", frames,
                      f"{what} dask w{w}", base))
            if what == "eval":
                print(row(f"eval: Dask, {w} worker(s), 4 tasks in process (--in-process)", frames,
                          f"eval inproc w{w}", base))
    for w in (1, 2):
        print(f"| eval merge after {w} worker(s) (serial) | {best[f'eval merge w{w}']:.2f} | "
              f"{ef / best[f'eval merge w{w}']:.0f} | |")
    over = (best["overhead 12 tasks"] - best["overhead 1 task"]) / 11
    print(f"| overhead per task (1 worker, 12 one-frame stereo tasks {best['overhead 12 tasks']:.2f}"
          f" s vs one 12-frame task {best['overhead 1 task']:.2f} s) | {over:.3f} | | |")
    for w in (1, 2):
        print(f"| T0: LocalCluster of {w} worker(s) | {best[f'T0 {w}']:.2f} | | |")
    shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
