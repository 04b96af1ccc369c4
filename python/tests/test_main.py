"""`python3 -m stereodet eval` on OpenPCDet-style pickles: the numbers of `stereodet eval` on the same
annotations written as KITTI files, frames matched by id, and a pickle that would build anything
but plain data and numpy arrays refused."""

import json
import os
import pickle
import subprocess
import sys

import numpy as np
import pytest
from conftest import random_annos, write_folders

from stereodet import __main__ as main_module


def run_module(build, *args):
    env = dict(os.environ, PYTHONPATH=str(build / "python"))
    env.pop("STEREODET_DEBUG", None)
    return subprocess.run([sys.executable, "-m", "stereodet", *map(str, args)],
                          capture_output=True, text=True, env=env)


def write_pickles(tmp_path, gt, dt, shuffle=False):
    """OpenPCDet's layout: infos with point_cloud.lidar_idx and annos; results with frame_id."""
    infos = [{"point_cloud": {"num_features": 4, "lidar_idx": f"{i:06d}"},
              "image": {"image_idx": f"{i:06d}"}, "annos": dict(g, difficulty=np.zeros(len(g["name"])))}
             for i, g in enumerate(gt)]
    results = [dict(d, frame_id=f"{i:06d}", boxes_lidar=np.zeros((len(d["name"]), 7)))
               for i, d in enumerate(dt)]
    if shuffle:
        results = results[::-1]
    with open(tmp_path / "infos.pkl", "wb") as f:
        pickle.dump(infos, f)
    with open(tmp_path / "result.pkl", "wb") as f:
        pickle.dump(results, f)
    return tmp_path / "infos.pkl", tmp_path / "result.pkl"


def results_json(folder):
    with open(folder / "results.json") as f:
        j = json.load(f)
    return j["results"]


@pytest.mark.parametrize("shuffle", [False, True])
def test_pickles_give_the_numbers_of_the_clis_folders(build, cli, tmp_path, shuffle):
    gt, dt = random_annos(12, seed=3)
    label_dir, det_dir = write_folders(tmp_path / "folders", gt, dt)
    infos, result = write_pickles(tmp_path, gt, dt, shuffle=shuffle)
    cli("eval", "--gt", label_dir, "--det", det_dir, "--out", tmp_path / "cli")
    done = run_module(build, "eval", "--gt", infos, "--det", result, "--out", tmp_path / "py")
    assert done.returncode == 0, done.stderr
    assert "Car" in done.stdout and "AP_R40" in done.stdout
    assert results_json(tmp_path / "py") == results_json(tmp_path / "cli")
    # A label folder against the results pickle: the same numbers again.
    done = run_module(build, "eval", "--gt", label_dir, "--det", result, "--out",
                      tmp_path / "mixed")
    assert done.returncode == 0, done.stderr
    assert results_json(tmp_path / "mixed") == results_json(tmp_path / "cli")


def test_a_pickle_that_would_build_other_objects_is_refused(build, tmp_path):
    gt, dt = random_annos(2, seed=4)
    infos, _ = write_pickles(tmp_path, gt, dt)
    evil = tmp_path / "evil.pkl"
    with open(evil, "wb") as f:
        pickle.dump([{"name": os.system}], f)  # would import os.system when loaded
    done = run_module(build, "eval", "--gt", infos, "--det", evil)
    assert done.returncode == 1
    assert done.stderr.startswith(f"stereodet: error: {evil}: the pickle holds a posix.system "
                                  "object; only plain data and numpy arrays are read")
    assert "Traceback" not in done.stderr


def test_results_of_frames_the_ground_truth_lacks_and_unmatched_lengths(build, tmp_path):
    gt, dt = random_annos(3, seed=5)
    infos, _ = write_pickles(tmp_path, gt, dt)
    extra = tmp_path / "extra.pkl"
    with open(extra, "wb") as f:
        pickle.dump([dict(d, frame_id=f"{i + 7:06d}") for i, d in enumerate(dt)], f)
    done = run_module(build, "eval", "--gt", infos, "--det", extra)
    assert done.returncode == 1
    assert "3 result(s) of frames the ground truth does not have, e.g. 000007" in done.stderr
    # Without ids on the results, frames pair by position, and their counts must agree.
    unnamed = tmp_path / "unnamed.pkl"
    with open(unnamed, "wb") as f:
        pickle.dump(dt[:2], f)
    done = run_module(build, "eval", "--gt", infos, "--det", unnamed)
    assert done.returncode == 1
    assert "2 frames of results for 3 of ground truth, and no frame ids" in done.stderr


def test_a_frame_without_results_has_no_detections():
    gt_ids = (["a", "b"], ["000000", "000001"])
    det = ([{"name": np.array(["Car"])}], ["000001"])
    aligned = main_module.align(gt_ids, det, "r.pkl")
    assert len(aligned) == 2 and len(aligned[0]["name"]) == 0 and aligned[1] is det[0][0]
