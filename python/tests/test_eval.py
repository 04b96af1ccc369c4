"""stereodet.evaluate and friends: the same numbers as the CLI, folders and annotation dicts alike."""

import csv
import json
import math

import numpy as np
import pytest

import stereodet
from conftest import random_annos, write_folders
from stereodet import kitti


def read_annos(folder, kind, ids):
    return [kitti.read_objects(folder / f"{i}.txt", kind) for i in ids]


@pytest.fixture(scope="module")
def small(data):
    """tests/data/eval_small as folders and as annotation lists."""
    root = data / "eval_small"
    ids = sorted(p.stem for p in (root / "label_2").glob("*.txt"))
    return (root / "label_2", root / "det", read_annos(root / "label_2", "label", ids),
            read_annos(root / "det", "detection", ids))


@pytest.fixture(scope="module")
def random_set(tmp_path_factory):
    """300 random KITTI-like frames, written as folders (the CLI reads them) and kept in memory."""
    gt, dt = random_annos(300, seed=11)
    label_dir, det_dir = write_folders(tmp_path_factory.mktemp("random"), gt, dt)
    return label_dir, det_dir, gt, dt


def cli_results(cli, tmp_path, *args):
    out = tmp_path / "cli"
    cli("eval", *args, "--out", out)
    return json.loads((out / "results.json").read_text())


def same_as_cli(result, expected):
    got = result.to_dict()
    # Everything but what describes the run itself (command line, wall time) and the tool's
    # version, which the CLI's eval command records as "unknown" (STEREODET_VERSION is not
    # defined for cli/eval_command.cc), while Python's is stereodet.__version__.
    for key in expected:
        if key not in ("command_line", "seconds", "tool"):
            assert got[key] == expected[key], key
    assert got["tool"]["name"] == expected["tool"]["name"]
    assert got["tool"]["version"] == stereodet.__version__
    assert set(got) == set(expected)


# --- Folders, against the CLI ---

def test_folders_give_the_clis_numbers_to_the_last_digit(cli, small, random_set, tmp_path):
    for label_dir, det_dir in (small[:2], random_set[:2]):
        expected = cli_results(cli, tmp_path / label_dir.parent.name, "--gt", label_dir,
                               "--det", det_dir)
        same_as_cli(stereodet.evaluate(str(label_dir), str(det_dir)), expected)


@pytest.mark.parametrize("python, flags", [
    (dict(matcher="optimal", classes=["Car", "Pedestrian"], metrics=["bev", "3d"]),
     ["--matcher", "optimal", "--classes", "Car,Pedestrian", "--metrics", "bev,3d"]),
    (dict(filters={"min_area": 400, "max-distance": 40}, filter_mode="naive",
          score_threshold=0.3, overlaps="loose"),
     ["--filter", "min-area=400,max-distance=40", "--filter-mode", "naive",
      "--score-threshold", "0.3", "--overlaps", "loose"]),
    (dict(compat="openpcdet", difficulties=["moderate"], all_classes=True,
          classes=["Car", "Van"]),
     ["--compat", "openpcdet", "--difficulties", "moderate", "--all-classes", "--classes",
      "Car,Van"]),
    (dict(matcher="voc", score_transform="sigmoid", calibration_bins=4, distance_bin_m=10,
          max_distance_m=60),
     ["--matcher", "voc", "--score-transform", "sigmoid", "--calibration-bins", "4",
      "--distance-bin", "10", "--max-distance", "60"]),
])
def test_options_give_the_clis_numbers(cli, random_set, tmp_path, python, flags):
    label_dir, det_dir = random_set[:2]
    expected = cli_results(cli, tmp_path, "--gt", label_dir, "--det", det_dir, *flags)
    same_as_cli(stereodet.evaluate(label_dir, det_dir, **python), expected)


def test_a_kitti_root_with_a_split(cli, data, tmp_path):
    root = data / "kitti_mini"
    labels = root / "training" / "label_2"
    det = tmp_path / "det"
    det.mkdir()
    for path in labels.glob("*.txt"):  # the labels themselves as detections of score 0.5
        annos = kitti.read_objects(path)
        annos["score"] = np.full(len(annos["name"]), 0.5)
        kitti.write_objects(det / path.name, annos)
    expected = cli_results(cli, tmp_path, "--gt", root, "--det", det, "--split", "val")
    result = stereodet.evaluate(root, det, split="val")
    same_as_cli(result, expected)
    assert result.num_frames == 2


# --- Annotation dicts ---

def test_annotation_dicts_give_the_numbers_of_their_files(small, random_set):
    for label_dir, det_dir, gt, dt in (small, random_set):
        files = stereodet.evaluate(label_dir, det_dir, matcher="optimal").to_dict()
        memory = stereodet.evaluate(gt, dt, matcher="optimal").to_dict()
        assert memory["results"] == files["results"]
        assert memory["scores"] == files["scores"]
        assert memory["options"] == files["options"]


def test_openpcdet_prediction_dtypes_are_accepted(random_set):
    _, _, gt, dt = random_set
    # OpenPCDet's predictions: float32 arrays, zero truncation/occlusion, extra keys.
    preds = []
    for d in dt:
        p = {k: (v.astype(np.float32) if v.dtype.kind == "f" else v) for k, v in d.items()}
        p["truncated"] = np.zeros(len(d["name"]))
        p["occluded"] = np.zeros(len(d["name"]))
        p["boxes_lidar"] = np.zeros((len(d["name"]), 7))
        preds.append(p)
    ref = [{k: v.astype(np.float32).astype(np.float64) if v.dtype.kind == "f" else v
            for k, v in d.items()} for d in dt]
    got = stereodet.evaluate(gt, preds).to_dict()["results"]
    assert got == stereodet.evaluate(gt, ref).to_dict()["results"]


def test_records_are_the_clis_matches_csv(cli, small, tmp_path):
    label_dir, det_dir = small[:2]
    out = tmp_path / "cli"
    cli("eval", "--gt", label_dir, "--det", det_dir, "--out", out, "--records")
    with open(out / "matches.csv") as f:
        rows = list(csv.DictReader(f))
    rec = stereodet.evaluate(label_dir, det_dir, records=True).records()
    assert len(rec["frame"]) == len(rows) > 100
    assert all(len(column) == len(rows) for column in rec.values())
    assert rec["frame_id"].tolist() == [r["frame"] for r in rows]
    for key in ("class", "metric", "difficulty", "outcome"):
        assert rec[key].tolist() == [r[key] for r in rows], key
    for key in ("detection", "label"):
        assert rec[key].tolist() == [int(r[key]) for r in rows], key
    assert rec["iou"].tolist() == [float(r["iou"]) for r in rows]
    scores = [float(r["score"]) if r["score"] else math.nan for r in rows]
    assert np.array_equal(rec["score"], scores, equal_nan=True)
    assert rec["label_valid"].tolist() == [r["label_valid"] == "1" for r in rows]
    assert rec["frame"].dtype == np.int32 and rec["iou"].dtype == np.float64
    with pytest.raises(ValueError, match="records=True"):
        stereodet.evaluate(label_dir, det_dir).records()


def test_rows_are_flat_and_agree_with_the_cells(small):
    result = stereodet.evaluate(small[0], small[1])
    rows = result.rows()
    assert len(rows) == len(result.cells) == 27
    keys = set(rows[0])
    for row, cell in zip(rows, result.cells):
        assert set(row) == keys
        assert all(isinstance(v, (str, int, float, bool)) for v in row.values())
        assert (row["class"], row["metric"], row["difficulty"]) == \
               (cell.class_name, cell.metric, cell.difficulty)
        assert row["ap_r40"] == cell.ap_r40 and row["tp"] == cell.at_threshold["tp"]
    # A table of columns, as pandas.DataFrame(rows) builds it.
    table = np.rec.fromrecords([tuple(r.values()) for r in rows], names=list(rows[0]))
    assert table["ap_r40"].dtype == np.float64


def test_cells_find_and_ap(small):
    result = stereodet.evaluate(small[0], small[1])
    cell = result.find("car", "3D", "Moderate")
    assert cell.class_name == "Car" and cell.metric == "3d" and cell.difficulty == "Moderate"
    assert result.ap("Car", "3d", "moderate") == cell.ap_r40
    assert result.ap("Car", "3d", 1, recall="r11") == cell.ap_r11
    assert result.find("Truck") is None
    curve = cell.curve
    assert curve["threshold"].shape == curve["precision"].shape and len(curve["tp"]) > 0
    assert cell.kitti_precision.shape == (41,)
    entry = result.to_dict()["results"][7]  # class-major, then metric, then difficulty
    assert (entry["class"], entry["metric"], entry["difficulty"]) == ("Car", "3d", "Moderate")
    assert entry["ap_r40"] == cell.ap_r40
    assert "Car" in str(result) and "AP_R40" in result.table()


def test_the_result_outlives_its_inputs(small):
    cells = stereodet.evaluate(list(small[2]), list(small[3]), records=True).cells
    assert cells[0].class_name == "Car"  # the result object is kept alive by its cells


# --- OpenPCDet's get_official_eval_result ---

def test_get_official_eval_result_prints_openpcdets_table(data, small, cli, tmp_path):
    gt, dt = small[2], small[3]
    text, figures = stereodet.get_official_eval_result(gt, dt, ["Car", "Pedestrian", "Cyclist"])
    assert text == (data / "eval_small" / "openpcdet_expected.txt").read_text()
    # Its keys, in its order: per class aos (alpha is valid here), 3d, bev, image, R40, strict.
    expected_keys = [f"{c}_{k}/{level}_R40" for c in ("Car", "Pedestrian", "Cyclist")
                     for k in ("aos", "3d", "bev", "image")
                     for level in ("easy", "moderate", "hard")]
    assert list(figures) == expected_keys
    assert all(isinstance(v, np.float64) for v in figures.values())
    # The figures are `stereodet eval --compat openpcdet`'s AP_R40 (strict set), exactly.
    json_results = cli_results(cli, tmp_path, "--gt", small[0], "--det", small[1],
                               "--compat", "openpcdet")["results"]
    kinds = {"3d": "3d", "bev": "bev", "image": "2d"}
    for key, value in figures.items():
        name, rest = key.split("_", 1)
        kind, level = rest.split("/")
        level = level[:-4].capitalize()
        entry = next(e for e in json_results if e["class"] == name and e["difficulty"] == level
                     and e["metric"] == kinds.get(kind, "2d"))
        assert value == (entry["aos_r40"] if kind == "aos" else entry["ap_r40"]), key


def test_get_official_eval_result_fills_pr_details(small):
    details = {}
    _, figures = stereodet.get_official_eval_result(small[2], small[3], [0, 1], details)
    assert set(details) == {"bbox", "aos", "bev", "3d"}
    assert details["3d"].shape == (2, 3, 2, 41)
    # OpenPCDet's get_mAP_R40 of the strict set gives its figures back.
    r40 = details["3d"][..., 1:].sum(axis=-1) / 40 * 100
    assert r40[0, 1, 0] == pytest.approx(figures["Car_3d/moderate_R40"], abs=1e-9)
    assert r40[1, 2, 0] == pytest.approx(figures["Pedestrian_3d/hard_R40"], abs=1e-9)


def test_get_official_eval_result_without_alpha_has_no_aos(small):
    dt = [dict(d, alpha=np.full(len(d["name"]), -10.0)) for d in small[3]]
    text, figures = stereodet.get_official_eval_result(small[2], dt, "Car")
    assert "aos" not in text and not any("aos" in k for k in figures)
    with pytest.raises(ValueError, match="current_classes: unknown class 9"):
        stereodet.get_official_eval_result(small[2], dt, 9)


# --- Sweep and compare, against the CLI's CSVs ---

def test_filter_sweep_is_the_clis(cli, small):
    label_dir, det_dir = small[:2]
    out = cli("eval", "sweep", "--gt", label_dir, "--det", det_dir, "--filter", "min-area",
              "--from", "0", "--to", "2000", "--step", "500", "--where", "max-distance=40").stdout
    expected = list(csv.DictReader(out.splitlines()))
    rows = stereodet.filter_sweep(label_dir, det_dir, "min-area", 0, 2000, 500,
                                  filters="max-distance=40")
    assert len(rows) == len(expected) == 27 * 5
    for row, want in zip(rows, expected):
        assert set(row) == set(want)
        for key, value in want.items():
            if isinstance(row[key], str):
                assert row[key] == value, key
            else:  # the CSV has the shortest text that reads back exactly
                assert row[key] == float(value), key


def test_compare_is_the_clis(cli, data, tmp_path):
    root = data / "eval_compare"
    cli("eval", "compare", "--gt", root / "label_2", "--det", root / "det_a", "--det-b",
        root / "det_b", "--metrics", "2d", "--classes", "Car", "--out", tmp_path)
    with open(tmp_path / "compare.csv") as f:
        expected = list(csv.DictReader(f))
    rows = stereodet.compare(root / "label_2", root / "det_a", root / "det_b", metrics=["2d"],
                             classes=["Car"])
    assert len(rows) == len(expected) > 0
    bins = [(r["lower_m"], r["count_a"], round(r["abs_depth_error_mean_a_m"], 9),
             round(r["abs_depth_error_mean_b_m"], 9)) for r in rows
            if r["count_a"] and r["difficulty"] == "Moderate"]
    assert bins == [(10.0, 1, 0.5, 0.2), (20.0, 1, 1.0, 2.0)]  # eval_compare/README.md
    for row, want in zip(rows, expected):
        assert row["count_b"] == int(want["count_b"])
        if want["abs_dz_mean_b"] != "-":
            assert row["abs_depth_error_mean_b_m"] == pytest.approx(float(want["abs_dz_mean_b"]),
                                                                    abs=5e-7)


# --- Bad input ---

def test_bad_input_raises_value_and_os_errors(small, data, tmp_path, cli):
    gt, dt = small[2], small[3]
    with pytest.raises(ValueError, match="differ in length: 12 vs 11 frames"):
        stereodet.evaluate(gt, dt[:-1])
    broken = [dict(d) for d in dt]
    del broken[3]["score"]
    with pytest.raises(ValueError, match=r"dt_annos\[3\]: missing key 'score'"):
        stereodet.evaluate(gt, broken)
    broken[3] = dict(dt[3], bbox=dt[3]["bbox"][:, :3])
    with pytest.raises(ValueError, match=r"dt_annos\[3\]\['bbox'\]: expected shape"):
        stereodet.evaluate(gt, broken)
    with pytest.raises(ValueError, match="gt_annos: expected a list"):
        stereodet.evaluate(gt[0], dt)
    with pytest.raises(ValueError, match="two folders or two lists"):
        stereodet.evaluate(small[0], dt)
    with pytest.raises(ValueError, match="split: only for folders"):
        stereodet.evaluate(gt, dt, split="val")
    with pytest.raises(ValueError, match="matcher: unknown 'hungarian'"):
        stereodet.evaluate(gt, dt, matcher="hungarian")
    with pytest.raises(ValueError, match="metric: unknown '4d'"):
        stereodet.evaluate(gt, dt, metrics=["4d"])
    with pytest.raises(ValueError, match="'car' given twice"):
        stereodet.evaluate(gt, dt, classes=["Car", "car"])
    with pytest.raises(ValueError, match="needs matcher kitti"):
        stereodet.evaluate(gt, dt, matcher="optimal", compat="openpcdet")
    with pytest.raises(ValueError, match="filter"):
        stereodet.evaluate(gt, dt, filters="min-size=3")
    with pytest.raises(OSError, match="no_such_folder"):
        stereodet.evaluate(tmp_path / "no_such_folder", small[1])
    # A bad detection line: the CLI's message, as a ParseError.
    bad = data / "eval_bad_det"
    with pytest.raises(stereodet.ParseError) as caught:
        stereodet.evaluate(bad / "label_2", bad / "det")
    out = cli("eval", "--gt", bad / "label_2", "--det", bad / "det", check=False)
    assert out.returncode != 0 and f"stereodet: error: {caught.value}" in out.stderr
    assert stereodet.evaluate(bad / "label_2", bad / "det", lenient=True).to_dict()[
        "input"]["num_skipped_lines"] == 1
