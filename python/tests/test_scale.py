"""stereodet.scale on a local Dask cluster of 2 workers (docs/scale.md): sharded synth output is byte
for byte that of one process, the merged sharded evaluation is the single-process evaluation, and
a worker killed in the middle of a run changes nothing; sharded stereo writes one process's
files."""

import json
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest

distributed = pytest.importorskip(
    "distributed", reason="Dask distributed is not installed (Debian python3-distributed, "
    "scripts/install-deps.sh): stereodet.scale is not tested")

from stereodet import scale  # noqa: E402

SYNTH_FLAGS = ["--width", "160", "--height", "48", "--threads", "1"]


def folder_bytes(root: Path, skip_hidden: bool = False) -> dict:
    """relative path -> bytes of every file under root, the driver's .scale/ markers aside, and
    with skip_hidden every hidden file (the temporaries .NAME.tmp-PID-N.EXT of a killed writer,
    which no reader takes for a frame)."""
    out = {}
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root)
        if not p.is_file() or rel.parts[0] == ".scale":
            continue
        if skip_hidden and any(part.startswith(".") for part in rel.parts):
            continue
        out[str(rel)] = p.read_bytes()
    return out


def without_provenance(path: Path) -> dict:
    j = json.loads(path.read_text())
    for key in ("command_line", "seconds", "tool"):
        j.pop(key, None)
    return j


@pytest.fixture(scope="module")
def client():
    # Nannies restart a killed worker; one thread per worker, as stereodet.scale starts them.
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def bin_dir(build):
    return scale.find_bin_dir(str(build / "bin"))


def one_process_synth(bin_dir, out, frames, seed, flags=SYNTH_FLAGS):
    subprocess.run([str(bin_dir / "stereodet-vision"), "synth", "--out", str(out), "--frames",
                    str(frames), "--seed", str(seed), "--quiet", *flags], check=True)


# in_process: each task runs in its worker through stereodet._stereo._run_cli (GIL released),
# not as a subprocess of stereodet-vision; the bytes must be the same either way.
@pytest.mark.parametrize("in_process", [False, True])
def test_sharded_synth_is_one_process_byte_for_byte_and_resumes(client, bin_dir, tmp_path,
                                                                in_process):
    flags = SYNTH_FLAGS + ["--no-lidar"]
    one_process_synth(bin_dir, tmp_path / "one", 7, 3, flags)
    tasks = scale.synth_tasks(bin_dir, tmp_path / "sharded", 7, 3, 3, flags,
                              in_process=in_process)
    assert [t.count for t in tasks] == [3, 3, 3]
    assert all(t.in_process == in_process for t in tasks)
    lines = []
    results = scale.run_tasks(client, tasks, lines.append)
    assert [r["skipped"] for r in results] == [False] * 3
    assert len(lines) == 3 and lines[-1].startswith("[3/3] task ")
    one, sharded = folder_bytes(tmp_path / "one"), folder_bytes(tmp_path / "sharded")
    assert len(one) == 7 * 7 + 4  # seven files a frame, three splits, synth_settings.txt
    assert one.keys() == sharded.keys()
    assert [k for k in one if one[k] != sharded[k]] == []
    # Resume: every task's outputs are there, so every task is skipped.
    assert [r["skipped"] for r in scale.run_tasks(client, tasks, lines.append)] == [True] * 3


# in_process: each task runs in its worker through stereodet._core._run_cli (GIL released), not
# as a subprocess; the shards and the merge must be the same bytes either way.
@pytest.mark.parametrize("matcher,in_process", [("kitti", False), ("optimal", False),
                                                ("kitti", True), ("optimal", True)])
def test_merged_sharded_eval_is_the_single_process_eval(client, bin_dir, cli, data, tmp_path,
                                                        matcher, in_process):
    gt, det = data / "eval_small", data / "eval_small" / "det"
    flags = ["--matcher", matcher, "--filter", "min-area=300", "--overlaps", "strict,loose",
             "--records"]
    cli("eval", "--gt", gt, "--det", det, "--out", tmp_path / "one", *flags)
    tasks = scale.eval_tasks(bin_dir, gt, det, tmp_path / "sharded", None, 5, flags,
                             in_process=in_process)
    assert len(tasks) == 3 and all(t.in_process == in_process for t in tasks)
    scale.run_tasks(client, tasks, lambda line: None)
    scale.eval_merge(bin_dir, tmp_path / "sharded", len(tasks), flags)
    merged = tmp_path / "sharded" / "merged"
    one, got = folder_bytes(tmp_path / "one"), folder_bytes(merged)
    assert one.keys() == got.keys()
    assert "matches_strict.csv" in one and "summary.csv" in one
    assert [k for k in one if k != "results.json" and one[k] != got[k]] == []
    a, b = without_provenance(tmp_path / "one" / "results.json"), without_provenance(
        merged / "results.json")
    assert a["results"]  # not vacuous
    assert a == b
    # A shard's provenance is its own command line, also in process (not the worker's).
    shard = json.loads((scale.eval_shard_dir(tmp_path / "sharded", 0, 3) / "results.json")
                       .read_text())
    assert shard["command_line"].startswith(("stereodet eval --gt", str(bin_dir / "stereodet")))
    assert "--shard 0/3" in shard["command_line"]
    # The same resumes: every shard is there, so every task is skipped.
    assert [r["skipped"] for r in scale.run_tasks(client, tasks, lambda line: None)] == [True] * 3


def test_an_eval_that_fits_one_task_merges_as_the_single_process_eval(client, bin_dir, cli, data,
                                                                      tmp_path):
    # One task runs `eval --shard 0/1`, which must write its shard record like any other shard
    # (it wrote none, and the merge refused it, whenever the frames fit in one task).
    gt, det = data / "eval_small", data / "eval_small" / "det"
    flags = ["--metrics", "2d", "--classes", "Car"]
    cli("eval", "--gt", gt, "--det", det, "--out", tmp_path / "one", *flags)
    tasks = scale.eval_tasks(bin_dir, gt, det, tmp_path / "sharded", None, 100000, flags)
    assert len(tasks) == 1
    scale.run_tasks(client, tasks, lambda line: None)
    assert (scale.eval_shard_dir(tmp_path / "sharded", 0, 1) / "eval_shard.json").is_file()
    scale.eval_merge(bin_dir, tmp_path / "sharded", 1, flags)
    assert (tmp_path / "one" / "summary.csv").read_bytes() == (
        tmp_path / "sharded" / "merged" / "summary.csv").read_bytes()


def test_an_in_process_task_of_another_executable_is_refused():
    from stereodet import _core, _stereo
    assert _core._run_cli(["synth", "--out", "/nonexistent/never-written"]) == 1
    assert not os.path.exists("/nonexistent/never-written")
    assert _stereo._run_cli(["train", "ssd", "--out", "/nonexistent/never-written"]) == 1
    assert not os.path.exists("/nonexistent/never-written")
    # The front end's own commands are handed back too, not run by the vision module.
    assert _stereo._run_cli(["eval", "--gt", "/nonexistent", "--det", "/nonexistent"]) == 1


def run_killing_one_worker(client, tasks, name):
    """Runs `tasks` (retried), SIGKILLs a worker while it runs one of them, waits for all and
    for the nanny to bring the worker back; asserts that every task finished."""
    futures = [client.submit(scale.run_task, t, key=f"{name}-{t.index}", pure=False, retries=3)
               for t in tasks]
    pids = client.run(os.getpid)  # worker address -> pid
    killed = None
    deadline = time.monotonic() + 30
    while killed is None and time.monotonic() < deadline:
        for address, keys in client.processing().items():
            if keys and address in pids:
                os.kill(pids[address], signal.SIGKILL)
                killed = (address, list(keys))
                break
        time.sleep(0.01)
    assert killed is not None, "no task was seen running"
    distributed.wait(futures, timeout=180)
    errors = [f"{f.key}: {f.exception()!r}" for f in futures if f.status != "finished"]
    assert errors == [], f"killed {killed}"
    # The nanny brought the worker back: the cluster still has 2 workers for the next test. A
    # liveness wait, not a speed check: the restarted worker imports Dask and stereodet again,
    # which took over 60 s beside other tests on the loaded 2-core machine.
    client.wait_for_workers(2, timeout=240)


def test_a_worker_killed_mid_run_changes_nothing(client, bin_dir, tmp_path):
    frames = 8
    one_process_synth(bin_dir, tmp_path / "one", frames, 5)
    # One frame a task, LiDAR on: each task lasts long enough to be killed in the middle.
    tasks = scale.synth_tasks(bin_dir, tmp_path / "sharded", frames, 5, 1, SYNTH_FLAGS)
    run_killing_one_worker(client, tasks, "kill-test")
    one = folder_bytes(tmp_path / "one")
    sharded = folder_bytes(tmp_path / "sharded", skip_hidden=True)
    assert one.keys() == sharded.keys()
    assert [k for k in one if one[k] != sharded[k]] == []


@pytest.mark.parametrize("in_process", [False, True])
def test_sharded_stereo_writes_the_files_of_one_process(client, bin_dir, tmp_path, in_process):
    data = tmp_path / "data"
    one_process_synth(bin_dir, data, 4, 9, SYNTH_FLAGS + ["--no-lidar"])
    subprocess.run([str(bin_dir / "stereodet-vision"), "stereo", "--data", str(data), "--out",
                    str(tmp_path / "one"), "--threads", "1", "--quiet"], check=True)
    tasks = scale.stereo_tasks(bin_dir, data, tmp_path / "sharded", None, 2, ["--threads", "1"],
                               in_process=in_process)
    assert len(tasks) == 2 and all(t.in_process == in_process for t in tasks)
    scale.run_tasks(client, tasks, lambda line: None)
    one, sharded = folder_bytes(tmp_path / "one"), folder_bytes(tmp_path / "sharded")
    assert one.keys() == sharded.keys() and "rgbh/000003.png" in one
    assert [k for k in one if k != "run.json" and one[k] != sharded[k]] == []
    a, b = (json.loads(one["run.json"]), json.loads(sharded["run.json"]))
    a.pop("command_line"), b.pop("command_line")
    assert a == b and len(a["frames"]) == 4


def one_process_detect(bin_dir, tmp_path, frames, seed, batch_size):
    """A synthetic set of `frames` frames (tmp_path/data), its split file of every frame, and the
    committed ssd-rgb's one-process detections of it (tmp_path/one), every box (score threshold 0:
    up to 100 a frame, compared to the last digit). Returns (model, data, split, flags)."""
    models = bin_dir / "stereodet-models"
    if not models.exists():
        pytest.skip("stereodet-models is not built (STEREODET_BUILD_MODELS=OFF)")
    model = Path(__file__).resolve().parents[2] / "models" / "ssd-rgb"
    data = tmp_path / "data"
    one_process_synth(bin_dir, data, frames, seed, SYNTH_FLAGS + ["--no-lidar"])
    split = tmp_path / "all.txt"
    split.write_text("".join(f"{i:06d}\n" for i in range(frames)))
    flags = ["--threads", "1", "--score-threshold", "0", "--batch-size", str(batch_size)]
    subprocess.run([str(models), "detect", "ssd", "--model", str(model), "--data", str(data),
                    "--split", str(split), "--out", str(tmp_path / "one"), "--quiet", *flags],
                   check=True)
    return model, data, split, flags


def test_sharded_detect_merged_is_one_process_folder_and_resumes(client, bin_dir, tmp_path):
    model, data, split, flags = one_process_detect(bin_dir, tmp_path, 5, 11, 3)
    tasks = scale.detect_tasks(bin_dir, model, data, tmp_path / "sharded", str(split), 2, flags)
    # 5 frames in tasks of 2 would be 3 tasks, but there are 2 batches of 3 (frames 0-2, 3-4),
    # and a shard is whole batches: 2 tasks.
    assert [t.count for t in tasks] == [2, 2]
    assert [r["skipped"] for r in scale.run_tasks(client, tasks, lambda line: None)] == [False] * 2
    scale.detect_merge(bin_dir, tmp_path / "sharded", len(tasks))
    one, merged = folder_bytes(tmp_path / "one"), folder_bytes(tmp_path / "sharded" / "merged")
    assert one.keys() == merged.keys() and len(one) == 6  # five frames and run.json
    assert sum(len(v) for v in one.values()) > 5000  # not vacuous: many boxes
    assert [k for k in one if k != "run.json" and one[k] != merged[k]] == []
    a, b = json.loads(one["run.json"]), json.loads(merged["run.json"])
    a.pop("command_line"), b.pop("command_line")
    assert a == b and len(a["frames"]) == 5
    # Resume: every task is skipped; a task of another command line (other flags) is not done.
    assert [r["skipped"] for r in scale.run_tasks(client, tasks, lambda line: None)] == [True] * 2
    other = scale.detect_tasks(bin_dir, model, data, tmp_path / "sharded", str(split), 1,
                               flags + ["--max-frames", "4"])
    assert [t.count for t in other] == [2, 2]  # 4 frames: 2 batches
    changed = scale.detect_tasks(bin_dir, model, data, tmp_path / "sharded", str(split), 2,
                                 ["--threads", "1"])
    assert [scale.task_is_done(t) for t in changed] == [False] * 3


def test_a_worker_killed_mid_detect_changes_nothing(client, bin_dir, tmp_path):
    model, data, split, flags = one_process_detect(bin_dir, tmp_path, 4, 13, 1)
    # One frame a task: each loads LibTorch and the model (about a second), long enough to be
    # killed in the middle; a killed task's shard folder is staged, so it leaves nothing that
    # looks complete, and its rerun replaces it.
    tasks = scale.detect_tasks(bin_dir, model, data, tmp_path / "sharded", str(split), 1, flags)
    assert len(tasks) == 4
    run_killing_one_worker(client, tasks, "kill-detect")
    scale.detect_merge(bin_dir, tmp_path / "sharded", len(tasks))
    one, merged = folder_bytes(tmp_path / "one"), folder_bytes(tmp_path / "sharded" / "merged")
    assert one.keys() == merged.keys() and len(one) == 5  # four frames and run.json
    assert [k for k in one if k != "run.json" and one[k] != merged[k]] == []


# Errors are one line on stderr and exit 1, not a traceback (STEREODET_DEBUG=1 keeps it).
def skip_without_training_group(build: Path):
    """A build without Gloo's headers refuses `train --world-size` (models/CMakeLists.txt)."""
    cache = build / "CMakeCache.txt"
    if cache.exists() and "STEREODET_HAVE_GLOO:INTERNAL=1" not in cache.read_text():
        pytest.skip("this build has no Gloo process group (libgloo-dev): no data-parallel training")


def train_log(model: Path) -> list:
    import csv  # noqa: PLC0415

    with open(model / "train_log.csv") as f:
        return list(csv.DictReader(f))


def test_a_training_on_two_workers_follows_one_process(client, bin_dir, build, tmp_path):
    """`stereodet.scale train`: one rank per worker, the rendezvous on rank 0's host; the losses
    of every step are the one-process training's (issue 39)."""
    skip_without_training_group(build)
    if not (bin_dir / "stereodet-models").exists():
        pytest.skip("stereodet-models is not built (STEREODET_BUILD_MODELS=OFF)")
    data = tmp_path / "data"
    one_process_synth(bin_dir, data, 10, 3)
    flags = ["--input", "rgb", "--width", "128", "--height", "40", "--epochs", "2",
             "--max-frames", "4", "--batch-size", "4", "--threads", "1", "--quiet"]
    subprocess.run([str(bin_dir / "stereodet-models"), "train", "ssd", "--data", str(data),
                    "--out", str(tmp_path / "one"), *flags], check=True)
    lines = []
    scale.run_training(client, bin_dir, "ssd", data, tmp_path / "two", flags,
                       progress=lines.append)
    assert lines and "2 ranks, rendezvous tcp://127.0.0.1:" in lines[0]
    one, two = train_log(tmp_path / "one"), train_log(tmp_path / "two")
    assert len(one) == len(two) == 2
    for a, b in zip(one, two):
        for key in ("loss", "localization_loss", "confidence_loss"):
            assert float(b[key]) == pytest.approx(float(a[key]), rel=1e-4), key


def test_a_failed_rank_is_named_with_its_cause(client, bin_dir, build, tmp_path, monkeypatch):
    """Rank 1 alone is given a split that does not exist: the error names rank 1 and its cause,
    not the other rank's "training group ... failed"."""
    skip_without_training_group(build)
    if not (bin_dir / "stereodet-models").exists():
        pytest.skip("stereodet-models is not built (STEREODET_BUILD_MODELS=OFF)")
    data = tmp_path / "data"
    one_process_synth(bin_dir, data, 4, 3)
    original = scale.train_rank_argv

    def argv(bin_dir_, family, data_, out, extra, rank, world, rendezvous):
        more = list(extra) + (["--split", "no_such_split"] if rank == 1 else [])
        return original(bin_dir_, family, data_, out, more, rank, world, rendezvous)

    monkeypatch.setattr(scale, "train_rank_argv", argv)
    with pytest.raises(RuntimeError, match="rank 1: exit 1: .*no_such_split"):
        scale.run_training(client, bin_dir, "ssd", data, tmp_path / "model",
                           ["--input", "rgb", "--width", "128", "--height", "40", "--epochs", "1",
                            "--batch-size", "2", "--threads", "1", "--quiet",
                            "--group-timeout", "20"], progress=lambda line: None)
    assert not (tmp_path / "model" / "model.pt").exists()


def test_errors_are_one_line(build, tmp_path):
    env = dict(os.environ, PYTHONPATH=str(build / "python"))
    env.pop("STEREODET_DEBUG", None)

    def scale_cli(*args, **extra_env):
        return subprocess.run(["/usr/bin/python3", "-m", "stereodet.scale", *args],
                              capture_output=True, text=True, cwd=tmp_path,
                              env=dict(env, **extra_env))

    done = scale_cli("--bin", str(build / "bin"), "eval", "--gt", str(tmp_path / "none"), "--det",
                     "b", "--out", "c")
    assert done.returncode == 1
    assert done.stderr == f"stereodet.scale: error: --gt {tmp_path / 'none'}: no label folder\n"
    done = scale_cli("--bin", str(build / "bin"), "eval", "--gt", str(tmp_path / "none"), "--det",
                     "b", "--out", "c", STEREODET_DEBUG="1")
    assert done.returncode == 1 and "Traceback" in done.stderr


def test_last_line_is_the_commands_error_line():
    assert scale.last_line("progress\nstereodet: error: no --det\n\n") == "stereodet: error: no --det"
    assert scale.last_line("") == "(no message)"
