#!/usr/bin/env python3
"""Data-parallel training's throughput (issue 39): 1 process x T threads against N ranks x T/N
threads on one machine, and what a step sends.

    train_distributed.py BIN_DIR WORK_DIR [--family det3d] [--frames 16] [--batch-size 4]
                         [--epochs 2] [--threads 2] [--ranks 2] [-- more train flags]

Writes synthetic frames (KITTI's size) once, then trains the same schedule three times: one
process with --threads T, one process with --threads T/ranks (what one rank would be alone), and
--ranks processes with --threads T/ranks each on the loopback (tcp://127.0.0.1). The figure is the
last epoch's frames/s from train_log.csv (the first epoch warms up); the ratios are taken in the
same call: ranks against the one T-thread process (does data parallelism pay on this machine?)
and against the one T/ranks-thread process (the ranks' scaling, what N machines would give). Also printed: the model's
parameters, the bytes one step's gradient all-reduce sends per rank (a ring all-reduce sends
2 (N - 1) / N times the float32 gradients), and the all-reduce's share of a step on a network of
--gbit Gbit/s (the scaling model of docs/BENCHMARKS.md).
"""
import argparse
import csv
import json
import os
import shutil
import socket
import subprocess
import sys
import time


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def last_epoch(model):
    with open(os.path.join(model, "train_log.csv")) as f:
        rows = list(csv.DictReader(f))
    rate = next(k for k in rows[-1] if k.endswith("_per_s"))
    return float(rows[-1][rate]), float(rows[-1]["epoch_s"]), int(rows[-1]["steps"])


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("bin")
    parser.add_argument("work")
    parser.add_argument("--family", default="det3d", choices=["ssd", "rpn", "det3d"])
    parser.add_argument("--frames", type=int, default=16)
    parser.add_argument("--batch-size", type=int, default=4)
    parser.add_argument("--epochs", type=int, default=2)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--ranks", type=int, default=2)
    parser.add_argument("--gbit", type=float, default=10.0)
    parser.add_argument("extra", nargs="*")
    args = parser.parse_args()
    stereodet = os.path.join(os.path.abspath(args.bin), "stereodet")
    work = os.path.abspath(args.work)
    data = os.path.join(work, "data")
    if not os.path.exists(os.path.join(data, "ImageSets", "train.txt")):
        subprocess.run([stereodet, "synth", "--out", data, "--frames", str(2 * args.frames),
                        "--seed", "7", "--threads", "2"], check=True, capture_output=True)
    inputs = {"ssd": ["--input", "rgb"], "rpn": ["--input", "rgb"], "det3d": ["--input", "lidar"]}

    def train(out, threads, rank=None, world=None, port=None):
        cmd = [stereodet, "train", args.family, "--data", data, "--out", out, "--epochs",
               str(args.epochs), "--max-frames", str(args.frames), "--batch-size",
               str(args.batch_size), "--threads", str(threads), "--quiet", "--force"]
        cmd += inputs[args.family] + args.extra
        if world:
            cmd += ["--world-size", str(world), "--rank", str(rank), "--rendezvous",
                    "tcp://127.0.0.1:%d" % port]
        return cmd

    one = os.path.join(work, args.family + "-one")
    start = time.time()
    subprocess.run(train(one, args.threads), check=True)
    one_wall = time.time() - start
    alone = os.path.join(work, args.family + "-alone")
    subprocess.run(train(alone, max(1, args.threads // args.ranks)), check=True)
    group = os.path.join(work, args.family + "-group")
    port = free_port()
    start = time.time()
    procs = [subprocess.Popen(train(group if r == 0 else os.path.join(work, "unused"),
                                    max(1, args.threads // args.ranks), r, args.ranks, port))
             for r in range(args.ranks)]
    if any(p.wait() != 0 for p in procs):
        sys.exit("a rank failed")
    group_wall = time.time() - start
    one_rate, one_s, steps = last_epoch(one)
    alone_rate, alone_s, _ = last_epoch(alone)
    group_rate, group_s, _ = last_epoch(group)
    with open(os.path.join(group, "run.json")) as f:
        json.load(f)
    params = None
    with open(os.path.join(group, "model.json")) as f:
        model = json.load(f)
        params = model.get("weights", {}).get("parameters") or model.get("parameters")
    result = {
        "family": args.family, "frames": args.frames, "batch_size": args.batch_size,
        "steps_per_epoch": steps, "threads": args.threads, "ranks": args.ranks,
        "one_process_frames_per_s": one_rate, "ranks_frames_per_s": group_rate,
        "ratio": group_rate / one_rate,
        "rank_alone_frames_per_s": alone_rate, "speedup_over_one_rank_alone": group_rate / alone_rate,
        "rank_alone_step_s": alone_s / steps, "one_process_wall_s": round(one_wall, 1),
        "ranks_wall_s": round(group_wall, 1),
        "one_process_step_s": one_s / steps, "ranks_step_s": group_s / steps,
    }
    if params:
        sent = 2 * (args.ranks - 1) / args.ranks * 4 * params
        result["parameters"] = params
        result["allreduce_bytes_per_rank_per_step"] = int(sent)
        result["allreduce_s_at_%g_gbit" % args.gbit] = sent * 8 / (args.gbit * 1e9)
    print(json.dumps(result, indent=1))
    shutil.rmtree(os.path.join(work, "unused"), ignore_errors=True)


if __name__ == "__main__":
    main()
