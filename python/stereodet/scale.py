"""Running stereodet past one machine on Dask distributed (docs/scale.md).

    python3 -m stereodet.scale [--workers N | --scheduler tcp://HOST:8786] [--task-frames 200]
        synth  --out DIR --frames N [--seed S] [-- more `stereodet synth` flags]
        stereo --data DIR --out DIR [--split val] [-- more `stereodet stereo` flags]
        eval   --gt DIR --det DIR --out DIR [--split val] [-- more `stereodet eval` flags]
        detect --model DIR --data DIR --out DIR [--split val] [--family ssd|det3d|rpn]
               [-- more `stereodet detect FAMILY` flags]
        train  --family ssd|rpn|det3d --data DIR --out DIR [--ranks N] [--port P]
               [-- more `stereodet train FAMILY` flags]

The work is cut into tasks of about --task-frames frames: task K of N runs the command line's
engine-agnostic contract, `stereodet CMD ... --shard K/N`, as a subprocess on a Dask worker (one
thread per worker: each task uses the worker's cores through the command's own threads). Each
task's outputs are whole files written atomically, and a task whose outputs are complete is
skipped, so an interrupted run resumes and a task that dies with its worker is simply run again
by the scheduler (same bytes: every shard's output is a function of its frames alone).

- synth: the shards write disjoint frames into one data set folder (the same bytes as one
  `stereodet synth`); a task is done when OUT/.scale/synth-K-of-N.done exists.
- stereo: the shards write disjoint frames into one output folder, merging their frames into
  OUT/run.json under a short lock; done marker OUT/.scale/stereo-K-of-N.done.
- eval: shard K of N writes OUT/shards/K-of-N/ (a results folder with the shard's frame bytes);
  when every shard is there, `stereodet eval merge` writes OUT/merged/, exactly the results
  folder of one `stereodet eval` run.
- detect: shard K of N writes OUT/shards/K-of-N/ (a detection folder of its frames, committed
  whole, with detect_shard.json); when every shard is there, `stereodet detect merge` writes
  OUT/merged/, byte for byte the detection folder of one `stereodet detect` run (run.json but
  its command line). Done marker OUT/.scale/detect-K-of-N.done, which holds the task's command
  line: a task whose command line changed (another model, other flags) runs again.

- train: one data-parallel training (`stereodet train FAMILY --world-size N --rank R
  --rendezvous tcp://HOST:PORT`, models/distributed.h), rank R a long task pinned to the R-th
  worker, all N running at once; rank 0 runs on a worker of the scheduler's host when there is one,
  and the rendezvous is on rank 0's host at a port free there (or --port). Rank 0 writes --out.
  Not retried: a rank that fails stops the group (its error is reported); run it again with
  `-- --resume` to continue from the last epoch.

Without --scheduler a LocalCluster of --workers processes is started and closed; with it the
driver joins a running scheduler (`dask scheduler` and `dask worker --nthreads 1` on each node,
all seeing the same file system at the same paths).
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, List, Optional, Sequence

# What a task needs: the command line and where its done marker goes. Plain data, so that it
# pickles to any worker.


@dataclass
class Task:
    index: int  # K
    count: int  # N
    argv: List[str]  # the full command line, binary first
    done: str  # the file whose presence means the task's outputs are complete
    # True: run_task writes `done` after the command succeeds; False: the command writes it.
    write_done: bool = True
    # With write_done: the task is done only when `done` holds this task's command line (a marker
    # of another command line, e.g. another model into the same folder, does not count).
    same_argv: bool = False
    env: dict = field(default_factory=dict)
    # True: the command runs inside the worker's process through the Python module, not as a
    # subprocess: no process start per task. The extension is the executable's: stereodet's
    # commands (eval) through stereodet._core._run_cli, stereodet-vision's (synth, stereo)
    # through stereodet._stereo._run_cli, the GIL released. Its output goes to the worker's
    # stdout.
    in_process: bool = False


def last_line(text: str) -> str:
    """The last non-empty line of a command's stderr: its error line ("stereodet: error: ...")."""
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    return lines[-1] if lines else "(no message)"


def find_bin_dir(given: Optional[str] = None) -> Path:
    """The folder of the stereodet executables: --bin, $STEREODET_BIN, the package's own bin/ (a
    pip install carries them there), the build tree this package was built in
    (build/python/stereodet -> build/bin), or the folder of `stereodet` on PATH."""
    candidates = []
    if given:
        candidates.append(Path(given))
    if os.environ.get("STEREODET_BIN"):
        candidates.append(Path(os.environ["STEREODET_BIN"]))
    if os.environ.get("STEREODET_BUILD_DIR"):
        candidates.append(Path(os.environ["STEREODET_BUILD_DIR"]) / "bin")
    candidates.append(Path(__file__).resolve().parent / "bin")
    candidates.append(Path(__file__).resolve().parents[2] / "bin")
    on_path = shutil.which("stereodet")
    if on_path:
        candidates.append(Path(on_path).parent)
    for c in candidates:
        if (c / "stereodet").exists():
            return c.resolve()
    raise FileNotFoundError("stereodet executables not found (tried " +
                            ", ".join(str(c) for c in candidates) + "); pass --bin DIR")


def _with_parent_death_signal(argv: List[str]) -> List[str]:
    # The task's process ends when its worker dies (SIGKILL included), so a rerun of the task
    # never races an orphan of the first try: util-linux's setpriv (Essential in Debian) sets
    # PR_SET_PDEATHSIG and execs the command, with no Python code between fork and exec (a
    # preexec_fn is unsafe in a threaded worker). Left open: a worker that dies in the few ms
    # between the fork and setpriv's prctl leaves an orphan. Without setpriv the command runs as
    # it is.
    setpriv = shutil.which("setpriv")
    return [setpriv, "--pdeathsig", "KILL", *argv] if setpriv else list(argv)


def _marker_text(task: Task) -> str:
    return " ".join(task.argv) + "\n"


def task_is_done(task: Task) -> bool:
    """Whether the task's done marker is there (and, with same_argv, holds its command line)."""
    if not os.path.exists(task.done):
        return False
    if not task.same_argv:
        return True
    try:
        return Path(task.done).read_text() == _marker_text(task)
    except OSError:
        return False


def run_task(task: Task) -> dict:
    """Runs one task on this machine (what a Dask worker calls); returns what it did. Skips the
    task when it is done (task_is_done). Raises RuntimeError with the command's stderr on
    failure."""
    if task_is_done(task):
        return {"index": task.index, "skipped": True, "seconds": 0.0}
    start = time.monotonic()
    if task.in_process:
        # The worker imports the extension on its first task (_stereo loads OpenCV).
        if Path(task.argv[0]).name == "stereodet-vision":
            from stereodet import _stereo as extension  # noqa: PLC0415
        else:
            from stereodet import _core as extension  # noqa: PLC0415
        code = extension._run_cli(list(task.argv[1:]))
        if code != 0:
            raise RuntimeError(f"task {task.index}/{task.count} failed (exit {code}) in process: "
                               f"{' '.join(task.argv)} (its error is on the worker's stderr)")
    else:
        env = dict(os.environ)
        env.update(task.env)
        result = subprocess.run(_with_parent_death_signal(task.argv), capture_output=True,
                                text=True, env=env)
        if result.returncode != 0:
            raise RuntimeError(f"task {task.index}/{task.count} failed (exit {result.returncode}): "
                               f"{last_line(result.stderr)} (its command: {' '.join(task.argv)})")
    if not task.write_done:
        return {"index": task.index, "skipped": False, "seconds": time.monotonic() - start}
    Path(task.done).parent.mkdir(parents=True, exist_ok=True)
    tmp = f"{task.done}.tmp-{os.getpid()}"
    with open(tmp, "w") as f:
        f.write(_marker_text(task))
    os.replace(tmp, task.done)
    return {"index": task.index, "skipped": False, "seconds": time.monotonic() - start}


def num_tasks(frames: int, task_frames: int) -> int:
    """N: tasks of at most task_frames frames (at least one task, at most one per frame)."""
    if task_frames < 1:
        raise ValueError(f"--task-frames must be >= 1, got {task_frames}")
    return max(1, math.ceil(frames / task_frames))


def _read_ids(root: Path, split: str) -> List[str]:
    path = Path(split)
    if not path.is_file():
        path = root / "ImageSets" / f"{split}.txt"
    if not path.is_file():
        raise FileNotFoundError(f"split {split}: neither a file nor {path}")
    return [line.strip() for line in path.read_text().splitlines() if line.strip()]


def count_stereo_frames(data: Path, split: Optional[str]) -> int:
    """The frames `stereodet stereo --data DATA [--split S]` would encode (the split, or every
    left image)."""
    if split:
        return len(_read_ids(data, split))
    images = data / "training" / "image_2"
    if not images.is_dir():
        images = data / "image_2"
    return sum(1 for p in images.glob("*.png") if p.stem.isdigit())


def count_eval_frames(gt: Path, split: Optional[str]) -> int:
    """The frames `stereodet eval --gt GT [--split S]` would read (the split, or every label)."""
    if split:
        return len(_read_ids(gt, split))
    for labels in (gt / "training" / "label_2", gt / "label_2", gt):
        if labels.is_dir():
            return sum(1 for p in labels.glob("*.txt") if p.stem.isdigit())
    raise FileNotFoundError(f"--gt {gt}: no label folder")


def synth_tasks(bin_dir: Path, out: Path, frames: int, seed: int, task_frames: int,
                extra: Sequence[str], in_process: bool = False) -> List[Task]:
    n = num_tasks(frames, task_frames)
    return [Task(k, n, [str(bin_dir / "stereodet-vision"), "synth", "--out", str(out),
                        "--frames", str(frames), "--seed", str(seed), "--shard", f"{k}/{n}",
                        "--quiet", *extra],
                 str(out / ".scale" / f"synth-{k}-of-{n}.done"), in_process=in_process)
            for k in range(n)]


def stereo_tasks(bin_dir: Path, data: Path, out: Path, split: Optional[str], task_frames: int,
                 extra: Sequence[str], in_process: bool = False) -> List[Task]:
    n = num_tasks(count_stereo_frames(data, split), task_frames)
    split_args = ["--split", split] if split else []
    return [Task(k, n, [str(bin_dir / "stereodet-vision"), "stereo", "--data", str(data),
                        "--out", str(out), *split_args, "--shard", f"{k}/{n}", "--quiet",
                        *extra],
                 str(out / ".scale" / f"stereo-{k}-of-{n}.done"), in_process=in_process)
            for k in range(n)]


def eval_shard_dir(out: Path, k: int, n: int) -> Path:
    return out / "shards" / f"{k}-of-{n}"


def eval_tasks(bin_dir: Path, gt: Path, det: Path, out: Path, split: Optional[str],
               task_frames: int, extra: Sequence[str], in_process: bool = False) -> List[Task]:
    n = num_tasks(count_eval_frames(gt, split), task_frames)
    split_args = ["--split", split] if split else []
    tasks = []
    for k in range(n):
        shard = eval_shard_dir(out, k, n)
        # The shard's results folder is committed whole (StagedFolder): its eval_shard.json is
        # the done marker.
        tasks.append(Task(k, n, [str(bin_dir / "stereodet"), "eval", "--gt", str(gt), "--det",
                                 str(det), *split_args, "--shard", f"{k}/{n}", "--out",
                                 str(shard), *extra], str(shard / "eval_shard.json"),
                          write_done=False, in_process=in_process))
    return tasks


def eval_merge(bin_dir: Path, out: Path, n: int, extra: Sequence[str]) -> str:
    """`stereodet eval merge` of the N shards into OUT/merged; returns its printout."""
    argv = [str(bin_dir / "stereodet"), "eval", "merge",
            *[str(eval_shard_dir(out, k, n)) for k in range(n)], "--out", str(out / "merged"),
            *extra]
    result = subprocess.run(argv, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"eval merge failed (exit {result.returncode}): "
                           f"{last_line(result.stderr)}")
    return result.stdout


def int_flag(extra: Sequence[str], name: str) -> int:
    """The value of `name N` (or `name=N`) among the command's flags, the last one given; 0 when
    absent."""
    value = 0
    for i, a in enumerate(extra):
        if a == name and i + 1 < len(extra):
            value = int(extra[i + 1])
        elif a.startswith(name + "="):
            value = int(a.split("=", 1)[1])
    return value


def count_detect_frames(data: Path, split: str, extra: Sequence[str] = ()) -> int:
    """The frames `stereodet detect ... --data DATA --split S [--max-frames M]` would run on."""
    frames = len(_read_ids(data, split))
    limit = int_flag(extra, "--max-frames")
    return min(frames, limit) if limit > 0 else frames


def detect_shard_dir(out: Path, k: int, n: int) -> Path:
    return out / "shards" / f"{k}-of-{n}"


def detect_tasks(bin_dir: Path, model: Path, data: Path, out: Path, split: str, task_frames: int,
                 extra: Sequence[str], family: str = "ssd") -> List[Task]:
    """Task K of N runs `stereodet-models detect FAMILY ... --shard K/N --out
    OUT/shards/K-of-N`. A detection shard is a range of whole batches (docs/scale.md), so with
    --batch-size B among the flags there are at most ceil(frames / B) tasks (more would be
    empty); choose --task-frames a multiple of B for tasks of equal size."""
    if family not in ("ssd", "det3d", "rpn"):
        raise ValueError(f"--family must be ssd, det3d or rpn, got {family!r}")
    frames = count_detect_frames(data, split, extra)
    n = num_tasks(frames, task_frames)
    batch = int_flag(extra, "--batch-size")
    if batch > 0:
        n = max(1, min(n, math.ceil(frames / batch)))
    return [Task(k, n, [str(bin_dir / "stereodet-models"), "detect", family, "--model",
                        str(model), "--data", str(data), "--split", split, "--shard", f"{k}/{n}",
                        "--out", str(detect_shard_dir(out, k, n)), "--quiet", *extra],
                 str(out / ".scale" / f"detect-{k}-of-{n}.done"), same_argv=True)
            for k in range(n)]


def detect_merge(bin_dir: Path, out: Path, n: int) -> str:
    """`stereodet detect merge` of the N shards into OUT/merged; returns its printout."""
    argv = [str(bin_dir / "stereodet-models"), "detect", "merge",
            *[str(detect_shard_dir(out, k, n)) for k in range(n)], "--out", str(out / "merged")]
    result = subprocess.run(argv, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"detect merge failed (exit {result.returncode}): "
                           f"{last_line(result.stderr)}")
    return result.stderr


def _host(address: str) -> str:
    """The host of a Dask address ("tcp://10.0.0.5:8786" -> "10.0.0.5", "tcp://[::1]:8786" ->
    "::1")."""
    rest = address.split("://", 1)[-1]
    host = rest.rsplit(":", 1)[0]
    return host[1:-1] if host.startswith("[") and host.endswith("]") else host


def free_port() -> int:
    """A TCP port free on this machine now (bound to port 0 and released); run on rank 0's worker
    to choose the rendezvous port there."""
    import socket  # noqa: PLC0415

    with socket.socket() as s:
        s.bind(("", 0))
        return s.getsockname()[1]


def train_rank_argv(bin_dir: Path, family: str, data: Path, out: Path, extra: Sequence[str],
                    rank: int, world: int, rendezvous: str) -> List[str]:
    """Rank `rank`'s command line of a training of `world` ranks."""
    return [str(bin_dir / "stereodet-models"), "train", family, "--data", str(data), "--out",
            str(out), *extra, "--world-size", str(world), "--rank", str(rank), "--rendezvous",
            rendezvous]


def run_training(client, bin_dir: Path, family: str, data: Path, out: Path,
                 extra: Sequence[str], ranks: int = 0, port: int = 0,
                 progress: Callable[[str], None] = print) -> str:
    """Runs one training of `ranks` ranks (0: one per worker) on the client's workers, rank r on
    the r-th worker (rank 0 on the scheduler's host when a worker is there). Returns rank 0's
    stderr (its summary). Raises RuntimeError naming the first rank that failed, with its error
    line; a failed rank makes the others stop (the group's timeout bounds the wait)."""
    workers = sorted(client.scheduler_info()["workers"])
    if not workers:
        raise RuntimeError("the Dask cluster has no workers")
    world = ranks or len(workers)
    if world > len(workers):
        raise RuntimeError(f"--ranks {world} needs as many workers, the cluster has "
                           f"{len(workers)} (each rank is a long task of its own worker)")
    scheduler_host = _host(client.scheduler.address)
    workers.sort(key=lambda w: _host(w) != scheduler_host)  # stable: the scheduler's host first
    chosen = workers[:world]
    host = _host(chosen[0])
    if not port:
        port = client.submit(free_port, workers=[chosen[0]], allow_other_workers=False,
                             pure=False).result()
    rendezvous = f"tcp://{'[' + host + ']' if ':' in host else host}:{port}"
    run = uuid.uuid4().hex[:8]
    futures = []
    for rank, worker in enumerate(chosen):
        task = Task(index=rank, count=world, done="", write_done=False,
                    argv=train_rank_argv(bin_dir, family, data, out, extra, rank, world,
                                         rendezvous))
        futures.append(client.submit(run_training_rank, task, workers=[worker],
                                     allow_other_workers=False, pure=False,
                                     key=f"stereodet-train-rank-{rank}-of-{world}-{run}"))
    progress(f"train {family}: {world} ranks, rendezvous {rendezvous}, rank 0 on {chosen[0]}")
    from distributed import as_completed, wait  # noqa: PLC0415

    # Until every rank is done or one has failed: a rank whose worker died is not rerun elsewhere
    # (it is pinned, and could not rejoin the group), so waiting for all could wait forever.
    for future in as_completed(futures):
        if future.status == "error":
            # The other ranks stop on their own within the group's timeout; give them a little
            # while to say so, so that the rank with its own error (the cause) is the one named.
            try:
                wait(futures, timeout=10)
            except Exception:  # noqa: BLE001 - a TimeoutError: report what is known now
                pass
            break
    errors = []
    for rank, future in enumerate(futures):
        if future.status == "error":
            errors.append(f"rank {rank}: {future.exception()}")
    if errors:
        for future in futures:
            future.cancel()
        # The ranks that only saw the group stop say "training group"; the cause says more.
        cause = next((e for e in errors if "training group" not in e), errors[0])
        raise RuntimeError(f"the training failed: {cause}")
    return futures[0].result()["stderr"]


def run_training_rank(task: Task) -> dict:
    """One rank of a training on this worker: its command as a subprocess; returns its stderr.
    Raises RuntimeError with the command's error line when it fails."""
    start = time.monotonic()
    result = subprocess.run(_with_parent_death_signal(task.argv), capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"exit {result.returncode}: {last_line(result.stderr)} (its command: "
                           f"{' '.join(task.argv)})")
    return {"index": task.index, "seconds": time.monotonic() - start, "stderr": result.stderr}


def run_tasks(client, tasks: Sequence[Task], progress: Callable[[str], None] = print,
              retries: int = 3) -> List[dict]:
    """Submits every task to the Dask client and waits; reports each finished task through
    `progress`. A task whose worker dies is rerun by the scheduler (up to its allowed failures,
    distributed.scheduler.allowed-failures) and, here, up to `retries` more times after an error.
    Returns the tasks' results in task order."""
    from distributed import as_completed

    # A fresh key per submission: a key the scheduler still holds from an earlier call would hand
    # back that call's result instead of running the task (and skipping it) again.
    run = uuid.uuid4().hex[:8]
    futures = {client.submit(run_task, t, key=f"stereodet-{t.index}-of-{t.count}-{run}",
                             retries=retries, pure=False): t for t in tasks}
    results = {}
    done = 0
    start = time.monotonic()
    for future in as_completed(list(futures)):
        task = futures[future]
        r = future.result()  # raises the task's error after its retries
        results[task.index] = r
        done += 1
        state = "skipped (done before)" if r["skipped"] else f"{r['seconds']:.1f} s"
        progress(f"[{done}/{len(tasks)}] task {task.index}/{task.count} {state}; "
                 f"{time.monotonic() - start:.1f} s elapsed")
    return [results[t.index] for t in tasks]


def make_client(workers: int, scheduler: Optional[str]):
    """A client of the given scheduler, or of a new LocalCluster of `workers` processes with one
    thread each. Returns (client, cluster or None)."""
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler), None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=None)
    return Client(cluster), cluster


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python3 -m stereodet.scale", description=__doc__.split(
        "\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--workers", type=int, default=2,
                   help="local cluster size (processes, one thread each); default 2")
    p.add_argument("--scheduler", help="join this Dask scheduler (tcp://HOST:8786) instead")
    p.add_argument("--task-frames", type=int, default=200, help="frames per task; default 200")
    p.add_argument("--bin", help="folder of the stereodet executables (default: found)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.add_argument("--in-process", action="store_true",
                   help="synth, stereo, eval: run each task inside its worker through the Python "
                        "module (the GIL released) instead of as a subprocess")
    sub = p.add_subparsers(dest="command", required=True)
    s = sub.add_parser("synth", help="sharded `stereodet synth`")
    s.add_argument("--out", required=True, type=Path)
    s.add_argument("--frames", required=True, type=int)
    s.add_argument("--seed", type=int, default=0)
    st = sub.add_parser("stereo", help="sharded `stereodet stereo`")
    st.add_argument("--data", required=True, type=Path)
    st.add_argument("--out", required=True, type=Path)
    st.add_argument("--split")
    e = sub.add_parser("eval", help="sharded `stereodet eval`, then `eval merge`")
    e.add_argument("--gt", required=True, type=Path)
    e.add_argument("--det", required=True, type=Path)
    e.add_argument("--out", required=True, type=Path)
    e.add_argument("--split")
    d = sub.add_parser("detect", help="sharded `stereodet detect ssd|det3d|rpn`, then `detect merge`")
    d.add_argument("--model", required=True, type=Path)
    d.add_argument("--data", required=True, type=Path)
    d.add_argument("--out", required=True, type=Path)
    d.add_argument("--split", default="val", help="split name or file; default val")
    d.add_argument("--family", default="ssd", choices=["ssd", "det3d", "rpn"],
                   help="the detector family; default ssd")
    t = sub.add_parser("train", help="one data-parallel `stereodet train FAMILY`, a rank per worker")
    t.add_argument("--family", required=True, choices=["ssd", "rpn", "det3d"])
    t.add_argument("--data", required=True, type=Path)
    t.add_argument("--out", required=True, type=Path)
    t.add_argument("--ranks", type=int, default=0,
                   help="ranks (processes); default: one per worker of the cluster")
    t.add_argument("--port", type=int, default=0,
                   help="rendezvous port on rank 0's host; default: one free there")
    for parser in (s, st, e, d, t):
        parser.add_argument("extra", nargs=argparse.REMAINDER,
                            help="after --: more flags of the stereodet command")
    return p


def main(argv: Optional[Sequence[str]] = None) -> int:
    args = build_parser().parse_args(argv)
    extra = [a for a in args.extra if a != "--"] if args.extra else []
    bin_dir = find_bin_dir(args.bin)
    if args.command == "train":
        progress = (lambda line: None) if args.quiet else (lambda line: print(line, flush=True))
        if args.in_process:
            raise SystemExit("stereodet.scale: --in-process is for synth, stereo and eval; "
                             "training ranks run as subprocesses (docs/scale.md)")
        client, cluster = make_client(args.ranks or args.workers, args.scheduler)
        try:
            start = time.monotonic()
            summary = run_training(client, bin_dir, args.family, args.data.resolve(),
                                   args.out.resolve(), extra, args.ranks, args.port, progress)
            progress(f"train {args.family}: done in {time.monotonic() - start:.1f} s")
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
        if not args.quiet:
            print(summary, end="")
        return 0
    if args.command == "synth":
        tasks = synth_tasks(bin_dir, args.out.resolve(), args.frames, args.seed, args.task_frames,
                            extra, in_process=args.in_process)
    elif args.command == "stereo":
        tasks = stereo_tasks(bin_dir, args.data.resolve(), args.out.resolve(), args.split,
                             args.task_frames, extra, in_process=args.in_process)
    elif args.command == "detect":
        if args.in_process:
            raise SystemExit("stereodet.scale: --in-process is for synth, stereo and eval; detect "
                             "tasks run as subprocesses (docs/scale.md)")
        split = str(Path(args.split).resolve()) if Path(args.split).is_file() else args.split
        tasks = detect_tasks(bin_dir, args.model.resolve(), args.data.resolve(),
                             args.out.resolve(), split, args.task_frames, extra, args.family)
    else:
        tasks = eval_tasks(bin_dir, args.gt.resolve(), args.det.resolve(), args.out.resolve(),
                           args.split, args.task_frames, extra, in_process=args.in_process)
    progress = (lambda line: None) if args.quiet else (lambda line: print(line, flush=True))
    client, cluster = make_client(args.workers, args.scheduler)
    try:
        start = time.monotonic()
        progress(f"{args.command}: {len(tasks)} tasks on {len(client.scheduler_info()['workers'])}"
                 f" workers")
        results = run_tasks(client, tasks, progress)
        ran = sum(1 for r in results if not r["skipped"])
        progress(f"{args.command}: {ran} tasks run, {len(tasks) - ran} skipped, "
                 f"{time.monotonic() - start:.1f} s")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    if args.command == "eval":
        out = eval_merge(bin_dir, args.out.resolve(), tasks[0].count, extra)
        if not args.quiet:
            print(out, end="")
    elif args.command == "detect":
        out = detect_merge(bin_dir, args.out.resolve(), tasks[0].count)
        if not args.quiet:
            print(out, end="")
    return 0


def run_main(argv: Optional[Sequence[str]] = None) -> int:
    """main(), with an error as one line on stderr and exit 1 instead of a traceback (the
    traceback too with STEREODET_DEBUG=1, as the CLI's --debug)."""
    try:
        return main(argv)
    except KeyboardInterrupt:
        print("stereodet.scale: interrupted", file=sys.stderr)
        return 130
    except Exception as error:  # noqa: BLE001 - every failure becomes one line for the user
        if os.environ.get("STEREODET_DEBUG", "") not in ("", "0"):
            raise
        message = " ".join(str(error).split()) or type(error).__name__
        print(f"stereodet.scale: error: {message}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(run_main())
