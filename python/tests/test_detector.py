"""stereodet.Detector: the trained detectors on numpy frames, against `stereodet detect`.

The frames are the 3 fresh synthetic frames of the models.detector_data fixture
(build/detector_data, with its stereo points in build/detector_points)."""

import subprocess
import sys
import threading

import numpy as np
import pytest

import stereodet
from conftest import REPO, build_dir

DATA = build_dir() / "detector_data"
POINTS = build_dir() / "detector_points"
IDS = ["000000", "000001", "000002"]


def read_png(path):
    return stereodet.stereo.read_image(path)


@pytest.fixture(scope="module")
def frames():
    if not (DATA / "training" / "image_2" / "000000.png").exists():
        pytest.fail(f"{DATA} is missing: run the models.detector_data fixture (ctest)")
    out = []
    for i in IDS:
        out.append(dict(
            frame_id=i,
            left=read_png(DATA / "training" / "image_2" / f"{i}.png"),
            right=read_png(DATA / "training" / "image_3" / f"{i}.png"),
            calib=stereodet.kitti.read_calib(DATA / "training" / "calib" / f"{i}.txt"),
            points=stereodet.kitti.read_velodyne(DATA / "training" / "velodyne" / f"{i}.bin")))
    return out


def detect_files(cli, tmp_path, model, extra=()):
    out = tmp_path / model
    cli("detect", "--model", REPO / "models" / model, "--data", DATA, "--split", "val", "--out",
        out, "--batch-size", "1", "--threads", "2", "--quiet", *extra)
    return {i: (out / f"{i}.txt").read_text() for i in IDS}


@pytest.mark.parametrize("model", ["ssd-rgbh-learned", "rpn-rgbd", "det3d-lidar"])
def test_the_objects_of_detect(cli, tmp_path, frames, model):
    detector = stereodet.Detector(str(REPO / "models" / model), threads=2)
    assert detector.family == model.split("-")[0]
    files = detect_files(cli, tmp_path, model)
    for f in frames:
        needs = detector.needs
        annos = detector.detect(f["left"], f["right"] if needs["right"] else None,
                                f["calib"] if needs["calib"] else None,
                                points=f["points"] if needs["points"] else None,
                                frame_id=f["frame_id"])
        assert annos["frame_id"] == f["frame_id"]
        assert set(annos["times"]) == {"stereo_s", "encode_s", "network_s", "decode_s"}
        kind = "detection"
        assert stereodet.kitti.format_objects(annos, kind) == files[f["frame_id"]], f["frame_id"]
    assert sum(len(stereodet.kitti.parse_objects(t, "detection")["name"])
               for t in files.values()) > 0  # not vacuous


def test_a_batch_gives_what_detect_batch_of_the_cli_gives(cli, tmp_path, frames):
    detector = stereodet.Detector(str(REPO / "models" / "ssd-rgb"), threads=2)
    out = tmp_path / "batch"
    cli("detect", "--model", REPO / "models" / "ssd-rgb", "--data", DATA, "--split", "val",
        "--out", out, "--batch-size", "3", "--threads", "2", "--quiet")
    results = detector.detect_batch([{"left": f["left"], "frame_id": f["frame_id"]}
                                     for f in frames])
    assert [r["frame_id"] for r in results] == IDS
    for r in results:
        assert stereodet.kitti.format_objects(r, "detection") == \
            (out / f"{r['frame_id']}.txt").read_text()


def test_calibration_gives_what_detect_calibration_writes(cli, tmp_path, frames):
    calibration = REPO / "tests" / "data" / "calibration" / "car_platt.json"
    detector = stereodet.Detector(str(REPO / "models" / "ssd-rgb"), threads=2,
                                  calibration=str(calibration))
    files = detect_files(cli, tmp_path, "ssd-rgb", ("--calibration", calibration))
    raw = stereodet.Detector(str(REPO / "models" / "ssd-rgb"), threads=2)
    changed = 0
    for f in frames:
        annos = detector.detect(f["left"], frame_id=f["frame_id"])
        assert stereodet.kitti.format_objects(annos, "detection") == files[f["frame_id"]]
        plain = raw.detect(f["left"], frame_id=f["frame_id"])
        changed += int(np.sum(annos["score"] != plain["score"]))
    assert changed > 0  # the Cars' scores moved: not vacuous
    with pytest.raises(ValueError, match="not JSON"):
        stereodet.Detector(str(REPO / "models" / "ssd-rgb"),
                           calibration=str(REPO / "tests" / "data" / "eval_small" / "README.md"))


def test_p2_p3_matrices_stand_for_a_calibration(frames):
    detector = stereodet.Detector(str(REPO / "models" / "ssd-rgbh-learned"), threads=2)
    f = frames[0]
    with_calib = detector.detect(f["left"], f["right"], f["calib"])
    p = f["calib"].projection
    with_matrices = detector.detect(f["left"], f["right"], (p[2], p[3]))
    assert stereodet.kitti.format_objects(with_matrices, "detection") == \
        stereodet.kitti.format_objects(with_calib, "detection")


def test_bad_frames_raise_value_error_naming_what(frames):
    detector = stereodet.Detector(str(REPO / "models" / "ssd-rgbh-learned"), threads=2)
    f = frames[0]
    with pytest.raises(ValueError, match="needs the right image"):
        detector.detect(f["left"])
    with pytest.raises(ValueError, match="left: expected a uint8 array"):
        detector.detect(f["left"].astype(np.float32), f["right"], f["calib"])
    with pytest.raises(ValueError, match="left and right differ in size"):
        detector.detect(f["left"], f["right"][:, :-2], f["calib"])
    with pytest.raises(ValueError, match=r"calib P2: expected a \(3, 4\) matrix"):
        detector.detect(f["left"], f["right"], (np.eye(3), np.eye(3)))
    with pytest.raises(OSError, match="model.json"):
        stereodet.Detector(str(REPO / "no-such-model"))


def test_two_detectors_run_on_two_threads(frames):
    """The GIL is released: both threads' calls are inside C++ at once at some point."""
    from stereodet import _detector
    detectors = [stereodet.Detector(str(REPO / "models" / "ssd-rgb"), threads=1) for _ in range(2)]
    seen = []
    stop = threading.Event()

    def watch():
        while not stop.is_set():
            seen.append(_detector._calls_in_progress())

    watcher = threading.Thread(target=watch)
    watcher.start()
    workers = [threading.Thread(target=lambda d=d: [d.detect(f["left"]) for f in frames * 2])
               for d in detectors]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    stop.set()
    watcher.join()
    assert max(seen) >= 1  # the watcher ran while a detector was inside C++ (GIL released)


def test_import_loads_no_libtorch_until_detector_is_used():
    def maps(code):
        script = code + "\nprint(open('/proc/self/maps').read())"
        return subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                              check=True).stdout
    assert "libtorch" not in maps("import stereodet")
    assert "libtorch" in maps("import stereodet; stereodet.Detector")
