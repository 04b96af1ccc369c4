#!/usr/bin/env python3
"""Data-parallel training through the CLI (issue 39): 2 ranks on the loopback against 1 process.

    train_distributed_test.py BIN_DIR WORK_DIR [FAMILY...]

On 4 synthetic frames (320 x 96), for each family (ssd, rpn, det3d; all by default):
  - one process with --batch-size 4 and 2 ranks (--world-size 2, 2 frames each) follow the same
    training: every step's loss, loss terms and counts in train_log.csv agree to float tolerance
    (3 epochs of one step each, so each line is one step);
  - rank 1 writes nothing: its --out names a folder that must not exist afterwards;
  - a 2-rank training stopped after one epoch and resumed (--resume) ends with the model.pt bytes
    of an uninterrupted 2-rank training;
and once: a rank that fails (its --data missing) stops the other with an error naming the group,
and a rank left alone gives up after --group-timeout.
Prints one line per check and "ok" at the end; exits 1 on the first failure.
"""
import csv
import os
import shutil
import subprocess
import sys

BIN = os.path.abspath(sys.argv[1])
WORK = os.path.abspath(sys.argv[2])
FAMILIES = sys.argv[3:] or ["ssd", "rpn", "det3d"]
STEREODET = os.path.join(BIN, "stereodet")
FRAMES = 4

# Each family's smallest flags (those of the cli.*.train tests).
FAMILY_FLAGS = {
    "ssd": ["--input", "rgb", "--width", "128", "--height", "40"],
    # At the frames' own size, the only one where these small objects match anchors.
    "rpn": ["--input", "rgbd", "--width", "320", "--height", "96", "--image-width", "4",
            "--geometry-width", "4", "--num-disparities", "32"],
    "det3d": ["--input", "lidar", "--width", "8"],
}
# The resume check's input per family where it differs from FAMILY_FLAGS' (none: rpn's rgbd
# resumes bit for bit since its samples stopped mirroring the stored geometry in place, a bug this
# test found).
RESUME_INPUT = {}

# Relative tolerance of the losses: float32 sums in another order (batch-norm statistics, the
# reductions over two slices, the all-reduce) over 3 steps of AdamW.
TOLERANCE = 2e-3


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def run(args, expect_ok=True):
    p = subprocess.run(args, capture_output=True, text=True, timeout=600)
    if expect_ok and p.returncode != 0:
        fail("%s exited %d:\n%s%s" % (" ".join(args), p.returncode, p.stdout, p.stderr))
    return p


def train_args(family, data, out, extra=()):
    return [STEREODET, "train", family, "--data", data, "--split", "train", "--out", out,
            "--epochs", "3", "--max-frames", str(FRAMES), "--batch-size", str(FRAMES),
            "--threads", "1", "--quiet"] + FAMILY_FLAGS[family] + list(extra)


def run_ranks(family, data, outs, rendezvous, extra=(), datas=None, timeout=120, input_=None):
    """Starts one process per entry of `outs` (rank r writes to outs[r]); returns them finished."""
    procs = []
    for rank, out in enumerate(outs):
        args = train_args(family, (datas or [data] * len(outs))[rank], out, extra)
        if input_:
            args[args.index("--input") + 1] = input_
        args += [
            "--world-size", str(len(outs)), "--rank", str(rank), "--rendezvous", rendezvous,
            "--group-timeout", "60"]
        procs.append(subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                      text=True))
    results = []
    for p in procs:
        out, err = p.communicate(timeout=timeout)
        results.append((p.returncode, out + err))
    return results


def log_rows(model):
    with open(os.path.join(model, "train_log.csv")) as f:
        return list(csv.DictReader(f))


def compare_logs(family, one, two):
    a, b = log_rows(one), log_rows(two)
    if len(a) != 3 or len(b) != 3:
        fail("%s: %d and %d log lines, expected 3" % (family, len(a), len(b)))
    worst = 0.0
    for row_a, row_b in zip(a, b):
        for key, value in row_a.items():
            if key in ("learning_rate", "epoch", "steps", "frames") or key.startswith("positive") \
                    or key.startswith("foreground"):
                if row_b[key] != value:
                    fail("%s: %s differs: %s (1 process) vs %s (2 ranks)"
                         % (family, key, value, row_b[key]))
            elif key.endswith("loss"):
                x, y = float(value), float(row_b[key])
                error = abs(x - y) / max(abs(x), 1e-3)
                worst = max(worst, error)
                if error > TOLERANCE:
                    fail("%s: epoch %s %s: %s (1 process) vs %s (2 ranks)"
                         % (family, row_a["epoch"], key, value, row_b[key]))
    return worst, a[0]["loss"], b[0]["loss"]


def main():
    shutil.rmtree(WORK, ignore_errors=True)
    os.makedirs(WORK)
    data = os.path.join(WORK, "data")
    run([STEREODET, "synth", "--out", data, "--frames", "10", "--width", "320", "--height", "96",
         "--seed", "3", "--threads", "2"])
    store = 0

    def rendezvous():
        nonlocal store
        store += 1
        return "file://" + os.path.join(WORK, "store%d" % store)

    for family in FAMILIES:
        one = os.path.join(WORK, family + "_one")
        run(train_args(family, data, one))
        two = os.path.join(WORK, family + "_two")
        never = os.path.join(WORK, family + "_rank1_never_written")
        results = run_ranks(family, data, [two, never], rendezvous())
        for rank, (code, output) in enumerate(results):
            if code != 0:
                fail("%s rank %d exited %d:\n%s" % (family, rank, code, output))
        if os.path.exists(never):
            fail("%s: rank 1 wrote %s" % (family, never))
        worst, first_one, first_two = compare_logs(family, one, two)
        print("%s: 2 ranks follow 1 process: first loss %s vs %s, largest relative difference "
              "%.1e" % (family, first_one, first_two, worst))

        # Stopped after one epoch and resumed, against uninterrupted (both 2 ranks).
        split = os.path.join(WORK, family + "_split")
        resume_input = RESUME_INPUT.get(family)
        if resume_input:
            two = os.path.join(WORK, family + "_two_" + resume_input)
            results = run_ranks(family, data, [two, never], rendezvous(), input_=resume_input)
            for rank, (code, output) in enumerate(results):
                if code != 0:
                    fail("%s rank %d exited %d:\n%s" % (family, rank, code, output))
        for extra in (["--stop-after", "1"], ["--resume"]):
            results = run_ranks(family, data, [split, never], rendezvous(), extra,
                                input_=resume_input)
            for rank, (code, output) in enumerate(results):
                if code != 0:
                    fail("%s split rank %d exited %d:\n%s" % (family, rank, code, output))
        with open(os.path.join(two, "model.pt"), "rb") as f:
            whole = f.read()
        with open(os.path.join(split, "model.pt"), "rb") as f:
            resumed = f.read()
        if whole != resumed:
            fail("%s: the resumed 2-rank training's model.pt differs from the uninterrupted one"
                 % family)
        print("%s: resumed 2 ranks = uninterrupted 2 ranks, model.pt byte for byte%s"
              % (family, " (--input %s)" % resume_input if resume_input else ""))

    # A rank that fails stops the other.
    family = FAMILIES[0]
    results = run_ranks(family, data, [os.path.join(WORK, "dead0"), os.path.join(WORK, "dead1")],
                        rendezvous(), datas=[data, os.path.join(WORK, "no_such_data")])
    if results[1][0] == 0 or "no_such_data" not in results[1][1]:
        fail("rank 1 with a missing --data: exit %d:\n%s" % results[1])
    if results[0][0] == 0 or "training group (rank 0 of 2)" not in results[0][1]:
        fail("rank 0 beside a failed rank 1: exit %d:\n%s" % results[0])
    print("a failed rank stops the other: " + results[0][1].strip().splitlines()[-1])

    # A rank alone gives up after --group-timeout.
    p = run(train_args(family, data, os.path.join(WORK, "alone")) + [
        "--world-size", "2", "--rank", "0", "--rendezvous", rendezvous(), "--group-timeout", "2"],
        expect_ok=False)
    if p.returncode == 0 or "cannot meet the other ranks" not in p.stderr:
        fail("a rank alone: exit %d:\n%s" % (p.returncode, p.stderr))
    print("a rank alone gives up: " + p.stderr.strip().splitlines()[-1])
    print("ok")


if __name__ == "__main__":
    main()
