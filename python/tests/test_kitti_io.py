"""stereodet.kitti: every reader and writer round-trips; bad input raises, never crashes."""

import pickle

import numpy as np
import pytest

import stereodet
from stereodet import kitti

CAR = "Car 0.00 0 1.85 387.63 181.54 423.81 203.12 1.67 1.87 3.69 -16.53 2.39 58.49 1.57\n"


def test_a_label_line_becomes_openpcdet_arrays():
    annos = kitti.parse_objects(CAR)
    assert annos["name"].tolist() == ["Car"]
    assert annos["truncated"].tolist() == [0.0]
    assert annos["occluded"].dtype == np.int64 and annos["occluded"].tolist() == [0]
    assert annos["alpha"].tolist() == [1.85]
    assert annos["bbox"].tolist() == [[387.63, 181.54, 423.81, 203.12]]
    # The file says h w l = 1.67 1.87 3.69; OpenPCDet's dimensions are l h w.
    assert annos["dimensions"].tolist() == [[3.69, 1.67, 1.87]]
    assert annos["location"].tolist() == [[-16.53, 2.39, 58.49]]
    assert annos["rotation_y"].tolist() == [1.57]
    assert "score" not in annos


def test_shapes_of_an_empty_file():
    annos = kitti.parse_objects("")
    assert annos["name"].shape == (0,)
    assert annos["bbox"].shape == (0, 4)
    assert annos["dimensions"].shape == (0, 3)
    assert kitti.format_objects(annos) == ""


def test_kitti_files_round_trip_byte_for_byte(data, tmp_path):
    for path in sorted((data / "kitti_mini" / "training" / "label_2").glob("*.txt")):
        annos = kitti.read_objects(path)
        assert kitti.format_objects(annos) == path.read_text(), path
        kitti.write_objects(tmp_path / "out.txt", annos)
        assert (tmp_path / "out.txt").read_bytes() == path.read_bytes(), path


def test_files_round_trip_number_for_number(data, tmp_path):
    for folder, kind in [(data / "eval_small" / "label_2", "label"),
                         (data / "eval_small" / "det", "detection")]:
        for path in sorted(folder.glob("*.txt")):
            annos = kitti.read_objects(path, kind)
            kitti.write_objects(tmp_path / "out.txt", annos)
            back = kitti.read_objects(tmp_path / "out.txt", kind)
            assert annos.keys() == back.keys()
            for key in annos:
                assert np.array_equal(annos[key], back[key]), (path, key)
            # ... and the file's numbers, field by field.
            rows = [line.split() for line in path.read_text().splitlines()]
            assert annos["name"].tolist() == [r[0] for r in rows]
            assert annos["bbox"].tolist() == [[float(v) for v in r[4:8]] for r in rows]
            assert annos["dimensions"].tolist() == [[float(r[10]), float(r[8]), float(r[9])]
                                                    for r in rows]


def test_detections_carry_scores_and_write_16_fields(data):
    path = data / "eval_small" / "det" / "000000.txt"
    annos = kitti.read_objects(path, "detection")
    lines = path.read_text().splitlines()
    assert annos["score"].tolist() == [float(line.split()[15]) for line in lines]
    assert all(len(line.split()) == 16 for line in kitti.format_objects(annos).splitlines())
    # The same dict written as labels (OpenPCDet's ground truth has zero scores): 15 fields.
    assert all(len(line.split()) == 15
               for line in kitti.format_objects(annos, "label").splitlines())
    with pytest.raises(ValueError, match="missing key 'score'"):
        kitti.format_objects(kitti.parse_objects(CAR), "detection")


def test_any_kind_mixes_labels_and_detections():
    annos = kitti.parse_objects(CAR + CAR.strip() + " 0.5\n", "any")
    assert np.isnan(annos["score"][0]) and annos["score"][1] == 0.5


def test_arbitrary_numbers_round_trip_exactly():
    rng = np.random.default_rng(7)
    n = 50
    annos = {
        "name": np.array(["Car", "Pedestrian", "Cyclist", "Van", "DontCare"] * 10),
        "truncated": rng.uniform(0, 1, n),
        "occluded": rng.integers(0, 4, n),
        "alpha": rng.uniform(-np.pi, np.pi, n),
        "bbox": rng.uniform(0, 1242, (n, 4)),
        "dimensions": rng.uniform(0.3, 5, (n, 3)),
        "location": rng.uniform(-40, 80, (n, 3)),
        "rotation_y": rng.uniform(-np.pi, np.pi, n),
        "score": rng.uniform(0, 1, n),
    }
    back = kitti.parse_objects(kitti.format_objects(annos), "detection")
    for key, value in annos.items():
        assert np.array_equal(back[key], value), key


def test_openpcdet_prediction_dicts_write_as_kitti_detections():
    # generate_prediction_dicts: float32 boxes, zero truncated/occluded, extra keys.
    pred = {
        "name": np.array(["Car"]),
        "truncated": np.zeros(1), "occluded": np.zeros(1),
        "alpha": np.array([-1.5], dtype=np.float32),
        "bbox": np.array([[1, 2, 3, 4]], dtype=np.float32),
        "dimensions": np.array([[3.9, 1.5, 1.6]], dtype=np.float32),
        "location": np.array([[1, 1.5, 20]], dtype=np.float32),
        "rotation_y": np.array([0.25], dtype=np.float32),
        "score": np.array([0.875], dtype=np.float32),
        "boxes_lidar": np.zeros((1, 7)), "frame_id": "000001",
    }
    line = kitti.format_objects(pred).split()
    assert line[0] == "Car" and line[15] == "0.875"
    assert [float(v) for v in line[8:11]] == [float(np.float32(v)) for v in (1.5, 1.6, 3.9)]
    # An empty prediction (np.zeros(0) names, as OpenPCDet makes them).
    empty = {k: np.zeros((0, 4) if k == "bbox" else (0, 3) if k in ("dimensions", "location")
                        else 0) for k in pred if k not in ("boxes_lidar", "frame_id")}
    assert kitti.format_objects(empty) == ""


def test_bad_lines_raise_parse_errors_like_the_cli(data, cli, tmp_path):
    path = data / "kitti_broken" / "training" / "label_2" / "000001.txt"
    with pytest.raises(stereodet.ParseError) as caught:
        kitti.read_objects(path)
    error = caught.value
    assert isinstance(error, ValueError)
    assert (error.file, error.line, error.field) == (str(path), 2, "dimensions.h")
    assert str(error) == f"{path}:2: field dimensions.h: '-2.85' is negative (dimensions are >= 0, " \
                         "or -1 for KITTI's \"not estimated\")"
    # The command line prints the same message after "stereodet: error: ".
    for name in ("000000.txt", "000001.txt"):
        (tmp_path / name).write_text("")
    out = cli("eval", "--gt", path.parent, "--det", tmp_path, check=False)
    assert out.returncode != 0
    assert f"stereodet: error: {error}" in out.stderr


def test_lenient_reading_lists_the_skipped_lines(data):
    path = data / "kitti_broken" / "training" / "label_2" / "000001.txt"
    problems = []
    annos = kitti.read_objects(path, lenient=True, problems=problems)
    assert annos["name"].tolist() == ["Car"]
    assert problems == [f"{path}:2: field dimensions.h: '-2.85' is negative (dimensions are >= 0, "
                        "or -1 for KITTI's \"not estimated\")"]
    assert kitti.read_objects(path, lenient=True)["bbox"].shape == (1, 4)


def test_missing_files_raise_os_error(tmp_path):
    with pytest.raises(OSError, match="nothing.txt"):
        kitti.read_objects(tmp_path / "nothing.txt")
    with pytest.raises(OSError, match="nothing.txt"):
        kitti.read_calib(tmp_path / "nothing.txt")
    with pytest.raises(OSError, match="nothing.bin"):
        kitti.read_velodyne(tmp_path / "nothing.bin")


@pytest.mark.parametrize("change, message", [
    (lambda a: a.pop("bbox"), "missing key 'bbox'"),
    (lambda a: a.update(bbox=np.zeros((1, 3))), r"\['bbox'\]: expected shape \(1, 4\)"),
    (lambda a: a.update(bbox=np.zeros((2, 4))), r"\['bbox'\]: expected shape \(1, 4\)"),
    (lambda a: a.update(alpha=np.array(["x"])), r"\['alpha'\]: expected numbers, got <U1"),
    (lambda a: a.update(alpha=None), r"\['alpha'\]: expected numbers"),
    (lambda a: a.update(alpha=np.array([np.nan])), r"\['alpha'\]\[0\]: nan is not a finite"),
    (lambda a: a.update(occluded=np.array([0.5])), r"\['occluded'\]\[0\]: 0.5.* not an integer"),
    (lambda a: a.update(dimensions=np.array([[-2.0, 1, 1]])), r"\[0, 0\]: -2.0* is negative"),
    (lambda a: a.update(name=np.array([1.0])), r"\['name'\]\[0\]: expected a class name"),
    (lambda a: a.update(name="Car"), r"\['name'\]: expected a sequence of class names"),
])
def test_bad_dicts_raise_value_errors(change, message):
    annos = kitti.parse_objects(CAR)
    change(annos)
    with pytest.raises(ValueError, match=message):
        kitti.format_objects(annos)


def test_not_a_dict_raises():
    with pytest.raises(ValueError, match="expected an annotation dict"):
        kitti.format_objects([1, 2, 3])
    with pytest.raises(ValueError, match="kind: unknown 'labels'"):
        kitti.parse_objects(CAR, "labels")


def test_calibration_round_trips(data, tmp_path):
    for path in sorted((data / "kitti_mini" / "training" / "calib").glob("*.txt")):
        calib = kitti.read_calib(path)
        text = kitti.format_calib(calib)
        assert kitti.parse_calib(text) == calib
        kitti.write_calib(tmp_path / "calib.txt", calib)
        assert kitti.read_calib(tmp_path / "calib.txt") == calib
        assert pickle.loads(pickle.dumps(calib)) == calib
        assert kitti.Calibration.from_kitti_dict(calib.to_kitti_dict()) == calib
        d = calib.to_kitti_dict()
        # The file's P2 line, number for number.
        p2 = next(line for line in path.read_text().splitlines() if line.startswith("P2"))
        assert d["P2"].ravel().tolist() == [float(v) for v in p2.split()[1:]]
        assert d["Tr_velo_to_cam"].shape == (3, 4) and calib.cam0_from_velo.shape == (4, 4)


def test_calibration_geometry_matches_the_kitti_numbers():
    calib = kitti.Calibration.kitti_like()
    assert calib.focal_px == 721.5377
    assert abs(calib.baseline_m - 0.54) < 0.01
    points = np.array([[1.0, 1.5, 20.0], [-3.0, 1.0, 10.0]])
    pixels, depth = calib.project_rect_to_image(points)
    p2 = calib.projection[2]
    homogeneous = np.c_[points, np.ones(2)] @ p2.T
    assert np.allclose(pixels, homogeneous[:, :2] / homogeneous[:, 2:], rtol=0, atol=1e-9)
    assert np.allclose(calib.unproject_image_to_rect(pixels, depth), points, atol=1e-9)
    rect_from_velo = calib.rect_from_velo
    expected = np.eye(4)
    expected[:3, :3] = calib.rect_from_cam0
    assert np.allclose(rect_from_velo, expected @ calib.cam0_from_velo)


def test_calibration_setters_check_shapes():
    calib = kitti.Calibration()
    assert calib.projection.shape == (4, 3, 4) and not calib.projection.any()
    calib.cam0_from_velo = np.eye(4)[:3]
    assert np.array_equal(calib.cam0_from_velo, np.eye(4))
    with pytest.raises(ValueError, match=r"projection: expected shape \(4, 3, 4\)"):
        calib.projection = np.zeros((3, 3, 4))
    with pytest.raises(ValueError, match="last row"):
        calib.velo_from_imu = np.ones((4, 4))
    with pytest.raises(ValueError, match="camera must be 0..3"):
        calib.project_rect_to_image(np.zeros((1, 3)), camera=4)
    with pytest.raises(ValueError, match=r"expected shape \(N, 3\)"):
        calib.project_rect_to_image(np.zeros((1, 2)))
    with pytest.raises(ValueError, match="P2 has a non-positive focal length"):
        calib.check_stereo()
    with pytest.raises(stereodet.ParseError, match=r"<string>:1: field P0: expected 12 numbers"):
        kitti.parse_calib("P0: 1 2 3\n")


def test_calibration_refuses_nan_and_inf_naming_the_element():
    # A NaN calibration projected every point to NaN pixels, which every consumer dropped silently.
    projection = np.zeros((4, 3, 4))
    projection[2, 0, 0] = np.nan
    with pytest.raises(ValueError, match=r"projection: element \(2, 0, 0\) of P2 is not finite"):
        kitti.Calibration(projection=projection)
    rect = np.eye(3)
    rect[1, 2] = np.inf
    with pytest.raises(ValueError, match=r"rect_from_cam0: element \(1, 2\) is not finite"):
        kitti.Calibration(rect_from_cam0=rect)
    calib = kitti.Calibration()
    transform = np.eye(4)
    transform[0, 3] = np.nan
    with pytest.raises(ValueError, match=r"cam0_from_velo: element \(0, 3\) is not finite"):
        calib.cam0_from_velo = transform
    assert np.array_equal(calib.cam0_from_velo, np.eye(4))  # unchanged by the refused value


def test_velodyne_round_trips(tmp_path):
    rng = np.random.default_rng(3)
    points = rng.normal(size=(1000, 4)).astype(np.float32)
    kitti.write_velodyne(tmp_path / "scan.bin", points)
    assert (tmp_path / "scan.bin").read_bytes() == points.tobytes()  # KITTI's layout
    back = kitti.read_velodyne(tmp_path / "scan.bin")
    assert back.dtype == np.float32 and np.array_equal(back, points)
    # float64 converts; an empty scan is (0, 4).
    kitti.write_velodyne(tmp_path / "scan.bin", points.astype(np.float64))
    assert np.array_equal(kitti.read_velodyne(tmp_path / "scan.bin"), points)
    kitti.write_velodyne(tmp_path / "empty.bin", np.zeros((0, 4)))
    assert kitti.read_velodyne(tmp_path / "empty.bin").shape == (0, 4)


def test_bad_velodyne_input_raises(tmp_path):
    with pytest.raises(ValueError, match=r"expected shape \(N, 4\)"):
        kitti.write_velodyne(tmp_path / "scan.bin", np.zeros((10, 3)))
    with pytest.raises(ValueError, match="expected numbers"):
        kitti.write_velodyne(tmp_path / "scan.bin", "points")
    (tmp_path / "odd.bin").write_bytes(b"\0" * 17)
    with pytest.raises(OSError, match="odd.bin"):
        kitti.read_velodyne(tmp_path / "odd.bin")
