"""stereodet.evaluate and friends: the same numbers as the CLI, folders and annotation dicts alike."""

import csv
import json
import math
import os

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
#Everything but what describes the run itself(command line, wall time); the tool's name and
#version too(both StereodetVersion(), the CMake project's).
    for key in expected:
        if key not in ("command_line", "seconds"):
            assert got[key] == expected[key], key
    assert got["tool"] == {"name": "stereodet eval", "version": stereodet.__version__}
    assert set(got) == set(expected)

#-- - Folders, against the CLI -- -

def test_folders_give_the_clis_numbers_to_the_last_digit(cli, small, random_set, tmp_path):
    for label_dir, det_dir in (small[:2], random_set[:2]):
        expected = cli_results(cli, tmp_path / label_dir.parent.name, "--gt", label_dir,
                               "--det", det_dir)
        same_as_cli(stereodet.evaluate(str(label_dir), str(det_dir)), expected)


@pytest.mark.parametrize("python, flags", [
    (dict(matcher="optimal", classes=["Car", "Pedestrian"], metrics=["bev", "3d"]),
     ["--matcher", "optimal", "--classes", "Car,Pedestrian", "--metrics", "bev,3d"]),
    (dict(matcher="optimal", classes=["Car"], metrics=["3d", "let-3d", "let-bev"]),
     ["--matcher", "optimal", "--classes", "Car", "--metrics", "3d,let-3d,let-bev"]),
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

#-- - Several overlap sets, as the CLI's --overlaps ---

def test_overlap_sets_are_the_clis_runs(cli, random_set, tmp_path):
    label_dir, det_dir = random_set[:2]
    both = stereodet.evaluate(label_dir, det_dir, overlaps="strict,loose")
    same_as_cli(both, cli_results(cli, tmp_path / "both", "--gt", label_dir, "--det", det_dir,
                                  "--overlaps", "strict,loose"))
    assert both.overlaps == ["strict", "loose"] and len(both.runs) == 2
#Each run is the CLI's run of that set alone.
    strict, loose = both.runs
    same_as_cli(strict, cli_results(cli, tmp_path / "strict", "--gt", label_dir, "--det",
                                    det_dir))
    same_as_cli(loose, cli_results(cli, tmp_path / "loose", "--gt", label_dir, "--det", det_dir,
                                   "--overlaps", "loose"))
    assert strict.overlaps == ["strict"] and loose.overlaps == ["loose"]
#KITTI's thresholds: Car 0.7 / 0.7 / 0.7 strict, 0.7 / 0.5 / 0.5 loose.
    assert strict.find("Car", "3d").min_overlap == 0.7
    assert loose.find("Car", "3d").min_overlap == 0.5
    assert loose.find("Car", "2d").min_overlap == 0.7
#The whole : every run 's cells in run order, rows tagged, the CLI' s table.
    assert len(both.cells) == len(strict.cells) + len(loose.cells) == 54
    assert [r["overlaps"] for r in both.rows()] == ["strict"] * 27 + ["loose"] * 27
    assert both.find("Car", "bev", overlaps="loose").ap_r40 == loose.ap("Car", "bev")
    assert both.ap("Car", "bev", overlaps="strict") == strict.ap("Car", "bev")
    out = cli("eval", "--gt", label_dir, "--det", det_dir, "--overlaps", "strict,loose").stdout
    assert both.table() in out and "overlaps loose" in both.table()
    assert both.num_frames == 300 and both.seconds == strict.seconds + loose.seconds
#A list works as the text does; one set is the result as before.
    listed = stereodet.evaluate(label_dir, det_dir, overlaps=["strict", "loose"]).to_dict()
    assert listed["results"] == both.to_dict()["results"]
    one = stereodet.evaluate(label_dir, det_dir)
    assert one.overlaps == ["strict"] and len(one.runs) == 1
    assert one.runs[0].to_dict()["results"] == one.to_dict()["results"]
    assert one.find("Car") is not None  # no overlaps= needed with one set


def test_overlap_sets_refuse_what_is_ambiguous(small):
    label_dir, det_dir, gt, dt = small
    both = stereodet.evaluate(gt, dt, overlaps="loose, strict", records=True)
    assert both.overlaps == ["loose", "strict"]
    with pytest.raises(ValueError, match="give overlaps="):
        both.find("Car")
    with pytest.raises(ValueError, match="no run 'custom'"):
        both.ap("Car", overlaps="custom")
    with pytest.raises(ValueError, match=r"runs\[i\].records"):
        both.records()
    assert len(both.runs[1].records()["frame"]) > 0
    with pytest.raises(ValueError, match="'strict' given twice"):
        stereodet.evaluate(gt, dt, overlaps="strict,strict")
    with pytest.raises(ValueError, match="overlaps: unknown 'medium'"):
        stereodet.evaluate(gt, dt, overlaps="strict,medium")
    with pytest.raises(ValueError, match="no overlap set"):
        stereodet.evaluate(gt, dt, overlaps=[])
    spec = stereodet.ClassSpec("Car", ["Van"], [0.6, 0.6, 0.6])
    with pytest.raises(ValueError, match="ClassSpec objects have their own thresholds"):
        stereodet.evaluate(gt, dt, classes=[spec], overlaps="strict,loose")
#One set : a ClassSpec keeps its thresholds, names beside it get the set's.
    custom = stereodet.evaluate(gt, dt, classes=[spec, "Pedestrian"], overlaps="loose")
    assert custom.find("Car", "3d").min_overlap == 0.6
    assert custom.find("Pedestrian", "3d").min_overlap == 0.25
    truck = stereodet.ClassSpec("Truck", [], [0.4, 0.3, 0.2])
    assert stereodet.evaluate(gt, dt, classes=[truck], all_classes=True).options.classes[0] \
        .min_overlap == [0.4, 0.3, 0.2, 0.3, 0.2]
    with pytest.raises(ValueError, match="filter_sweep takes one overlap set"):
        stereodet.filter_sweep(label_dir, det_dir, "min-area", overlaps="strict,loose")
    with pytest.raises(ValueError, match="compare takes one overlap set"):
        stereodet.compare(label_dir, det_dir, det_dir, overlaps="strict,loose")

#-- - out = : the CLI's results folder ---

def files_under(folder):
    return sorted(p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file())


def without_run_lines(text):
    """results.json without what describes the run itself: the command line and the wall time."""
    return [line for line in text.splitlines()
            if not line.lstrip().startswith(('"command_line":', '"seconds":'))]


def assert_same_folder(cli_dir, py_dir, *, results_json=True):
    """Every file the CLI wrote, Python wrote too; the report's files byte for byte (results.json
    but for its command line and wall time). Files are listed from the CLI's folder, so that a
    file the report gains later is checked to be there as well."""
    cli_files = files_under(cli_dir)
    assert files_under(py_dir) == cli_files
    assert "results.json" in cli_files and "summary.csv" in cli_files
    curves = [f for f in cli_files if f.startswith("curves/")]
    assert len(curves) > 100
    for name in ["summary.csv"] + curves + [f for f in cli_files if f.startswith("matches")]:
        assert (py_dir / name).read_bytes() == (cli_dir / name).read_bytes(), name
    if results_json:
        cli_text = (cli_dir / "results.json").read_text()
        assert without_run_lines((py_dir / "results.json").read_text()) == \
            without_run_lines(cli_text)
        assert len(without_run_lines(cli_text)) == len(cli_text.splitlines()) - 2
    return cli_files


@pytest.mark.parametrize("python, flags", [
    ({}, []),
    (dict(overlaps="strict,loose", records=True, filters="max-distance=40"),
     ["--overlaps", "strict,loose", "--records", "--filter", "max-distance=40"]),
])
def test_out_writes_the_clis_results_folder(cli, random_set, tmp_path, python, flags):
    label_dir, det_dir = random_set[:2]
    cli("eval", "--gt", label_dir, "--det", det_dir, "--out", tmp_path / "cli", *flags)
    result = stereodet.evaluate(label_dir, det_dir, out=tmp_path / "py", **python)
    files = assert_same_folder(tmp_path / "cli", tmp_path / "py")
    assert sorted(os.path.relpath(f, tmp_path / "py") for f in result.files) == files
    if python.get("records"):
        assert {"matches_strict.csv", "matches_loose.csv"} <= set(files)
#An earlier results folder is replaced whole; a folder of other files is refused.
    stereodet.evaluate(label_dir, det_dir, out=tmp_path / "py", **python)
    assert files_under(tmp_path / "py") == files
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine" / "notes.txt").write_text("keep me")
    with pytest.raises(OSError, match="mine"):
        stereodet.evaluate(label_dir, det_dir, out=tmp_path / "mine")
    assert files_under(tmp_path / "mine") == ["notes.txt"]
    assert stereodet.evaluate(label_dir, det_dir).files == []


def test_out_of_annotation_dicts_is_the_same_report(cli, random_set, tmp_path):
    label_dir, det_dir, gt, dt = random_set
    cli("eval", "--gt", label_dir, "--det", det_dir, "--out", tmp_path / "cli", "--records")
    result = stereodet.evaluate(gt, dt, out=tmp_path / "py", records=True)
#The numbers and curves byte for byte; results.json differs in what was read(no folders).
    assert_same_folder(tmp_path / "cli", tmp_path / "py", results_json=False)
    written = json.loads((tmp_path / "py" / "results.json").read_text())
    expected = json.loads((tmp_path / "cli" / "results.json").read_text())
    assert written["results"] == expected["results"] and written["tool"] == expected["tool"]
    assert written == result.to_dict()
    assert len(result.files) == len(files_under(tmp_path / "py"))
    stereodet.evaluate(gt, dt, out=tmp_path / "plain")
    assert "matches.csv" not in files_under(tmp_path / "plain")
    assert "summary.csv" in files_under(tmp_path / "plain")


def test_sweep_and_compare_out_are_the_clis_csvs(cli, small, data, tmp_path):
    label_dir, det_dir = small[:2]
    cli("eval", "sweep", "--gt", label_dir, "--det", det_dir, "--filter", "max-distance",
        "--from", "10", "--to", "50", "--step", "20", "--out", tmp_path / "cli_sweep")
    rows = stereodet.filter_sweep(label_dir, det_dir, "max-distance", 10, 50, 20,
                                  out=tmp_path / "py_sweep")
    assert len(rows) == 27 * 3
    assert (tmp_path / "py_sweep" / "sweep.csv").read_bytes() == \
        (tmp_path / "cli_sweep" / "sweep.csv").read_bytes()
    root = data / "eval_compare"
    args = ["--gt", root / "label_2", "--det", root / "det_a", "--det-b", root / "det_b",
            "--classes", "Car", "--disparity-error-px", "0.5"]
    cli("eval", "compare", *args, "--out", tmp_path / "cli_compare")
    stereodet.compare(root / "label_2", root / "det_a", root / "det_b", classes="Car",
                      disparity_error_px=0.5, out=tmp_path / "py_compare")
    assert (tmp_path / "py_compare" / "compare.csv").read_bytes() == \
        (tmp_path / "cli_compare" / "compare.csv").read_bytes()
#A Calibration object is the in - memory path : the same rows as the CLI's call.
    in_memory = stereodet.compare(root / "label_2", root / "det_a", root / "det_b",
                                  classes="Car", disparity_error_px=0.5,
                                  calib=kitti.Calibration.kitti_like())
    through_cli = stereodet.compare(root / "label_2", root / "det_a", root / "det_b",
                                    classes="Car", disparity_error_px=0.5)
    assert len(in_memory) == len(through_cli) > 0
    assert repr(in_memory) == repr(through_cli)  # exact, NaN of empty bins included
    with pytest.raises(ValueError, match="only for folders"):
        stereodet.filter_sweep(small[2], small[3], "min-area", out=tmp_path / "x")

#-- - Annotation dicts -- -

def test_annotation_dicts_give_the_numbers_of_their_files(small, random_set):
    for label_dir, det_dir, gt, dt in (small, random_set):
        files = stereodet.evaluate(label_dir, det_dir, matcher="optimal").to_dict()
        memory = stereodet.evaluate(gt, dt, matcher="optimal").to_dict()
        assert memory["results"] == files["results"]
        assert memory["scores"] == files["scores"]
        assert memory["options"] == files["options"]


def test_openpcdet_prediction_dtypes_are_accepted(random_set):
    _, _, gt, dt = random_set
#OpenPCDet's predictions: float32 arrays, zero truncation/occlusion, extra keys.
    preds = []
    for d in dt:
        p = {k: (v.astype(np.float32) if v.dtype.kind == "f" else v) for k, v in d.items()}
        p["truncated"] = np.zeros(len(d["name"]))
        p["occluded"] = np.zeros(len(d["name"]))
        p["boxes_lidar"] = np.zeros((len(d["name"]), 7))
        preds.append(p)
    ref = [{
k: v.astype(np.float32).astype(np.float64) if v.dtype.kind == "f" else v
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
#A table of columns, as pandas.DataFrame(rows) builds it.
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
    assert math.isnan(cell.apl_r40) and not cell.has_apl
    let = stereodet.evaluate(small[0], small[1], classes=["Car"], metrics=["let-3d"]) \
        .find("Car", "let-3d", "Moderate")
    assert let.has_apl and not let.has_aos and 0 <= let.apl_r40 <= let.ap_r40


def test_the_result_outlives_its_inputs(small):
    cells = stereodet.evaluate(list(small[2]), list(small[3]), records=True).cells
    assert cells[0].class_name == "Car"  # the result object is kept alive by its cells

#-- - OpenPCDet's get_official_eval_result ---

def test_get_official_eval_result_prints_openpcdets_table(data, small, cli, tmp_path):
    gt, dt = small[2], small[3]
    text, figures = stereodet.get_official_eval_result(gt, dt, ["Car", "Pedestrian", "Cyclist"])
    assert text == (data / "eval_small" / "openpcdet_expected.txt").read_text()
#Its keys, in its order : per class aos(alpha is valid here), 3d, bev, image, R40, strict.
    expected_keys = [f"{c}_{k}/{level}_R40" for c in ("Car", "Pedestrian", "Cyclist")
                     for k in ("aos", "3d", "bev", "image")
                     for level in ("easy", "moderate", "hard")]
    assert list(figures) == expected_keys
    assert all(isinstance(v, np.float64) for v in figures.values())
#The figures are `stereodet eval-- compat openpcdet`'s AP_R40 (strict set), exactly.
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
#OpenPCDet's get_mAP_R40 of the strict set gives its figures back.
    r40 = details["3d"][..., 1:].sum(axis=-1) / 40 * 100
    assert r40[0, 1, 0] == pytest.approx(figures["Car_3d/moderate_R40"], abs=1e-9)
    assert r40[1, 2, 0] == pytest.approx(figures["Pedestrian_3d/hard_R40"], abs=1e-9)


def test_get_official_eval_result_without_alpha_has_no_aos(small):
    dt = [dict(d, alpha=np.full(len(d["name"]), -10.0)) for d in small[3]]
    text, figures = stereodet.get_official_eval_result(small[2], dt, "Car")
    assert "aos" not in text and not any("aos" in k for k in figures)
    with pytest.raises(ValueError, match="current_classes: unknown class 9"):
        stereodet.get_official_eval_result(small[2], dt, 9)


def test_breakdowns_are_the_clis(cli, small, tmp_path):
    label_dir, det_dir = small[:2]
    args = ("--gt", label_dir, "--det", det_dir, "--metrics", "2d", "--classes", "Car",
            "--breakdown", "height=0,40,inf", "--breakdown", "occlusion=0,1,4")
    expected = cli_results(cli, tmp_path, *args)
    result = stereodet.evaluate(label_dir, det_dir, metrics=["2d"], classes=["Car"],
                                breakdowns=["height=0,40,inf", "occlusion=0,1,4"])
    same_as_cli(result, expected)
    cell = result.find("Car", "2d")  # Moderate
    assert [b["bin"] for b in cell.breakdown] == ["[0, 40)", "[40, inf)", "[0, 1)", "[1, 4)"]
#The height bins partition the cell's true positives (docs/metrics.md, "Breakdowns").
    assert sum(b["at_threshold"]["tp"] for b in cell.breakdown[:2]) == cell.at_threshold["tp"]
    with pytest.raises(ValueError, match="edges must increase"):
        stereodet.evaluate(label_dir, det_dir, breakdowns="distance=30,0")


def test_error_analysis_is_the_clis(cli, small, tmp_path):
    label_dir, det_dir = small[:2]
    expected = cli_results(cli, tmp_path, "--gt", label_dir, "--det", det_dir, "--metrics", "2d",
                           "--classes", "Car", "--matcher", "optimal", "--errors")
    cells = stereodet.analyze_errors(label_dir, det_dir, metrics=["2d"], classes=["Car"],
                                     matcher="optimal")
    want = [e for e in expected["results"] if e["evaluated"]]
    assert [(c["class"], c["metric"], c["difficulty"]) for c in cells] == \
        [(e["class"], e["metric"], e["difficulty"]) for e in want]
    for got, e in zip(cells, want):
        assert got["count"] == e["errors"]["count"]
        assert got["delta_ap_r40"] == e["errors"]["delta_ap_r40"]
        assert got["special"] == e["errors"]["special"]
        assert got["ap_r40"] == e["ap_r40"]
    assert sum(sum(c["count"].values()) for c in cells) > 0  # not vacuous
    with pytest.raises(ValueError, match="background"):
        stereodet.analyze_errors(label_dir, det_dir, background_overlap=1.5)


def test_naive_breakdowns_are_the_clis(cli, small, tmp_path):
    label_dir, det_dir = small[:2]
    expected = cli_results(cli, tmp_path, "--gt", label_dir, "--det", det_dir, "--metrics", "2d",
                           "--classes", "Car", "--breakdown", "distance=0,20,inf",
                           "--breakdown-naive")
    result = stereodet.evaluate(label_dir, det_dir, metrics=["2d"], classes=["Car"],
                                breakdowns=["distance=0,20,inf"], breakdown_naive=True)
    same_as_cli(result, expected)
    cell = result.find("Car", "2d")  # Moderate
    want = [e for e in expected["results"] if e["class"] == "Car" and e["metric"] == "2d"
            and e["difficulty"] == "Moderate"][0]["breakdown"]
    for got, bin_ in zip(cell.breakdown, want):
        assert got["naive"]["at_threshold"]["tp"] == bin_["naive"]["at_threshold"]["tp"]
        assert got["naive"]["at_threshold"]["fp"] == bin_["naive"]["at_threshold"]["fp"]
        assert got["naive"]["curve"]["ap_r40"] == pytest.approx(bin_["naive"]["ap_r40"])
    plain = stereodet.evaluate(label_dir, det_dir, metrics=["2d"], classes=["Car"],
                               breakdowns=["distance=0,20,inf"])
    assert plain.find("Car", "2d").breakdown[0]["naive"] is None
    with pytest.raises(ValueError, match="give breakdowns"):
        stereodet.evaluate(label_dir, det_dir, breakdown_naive=True)

#-- - Sweep and compare, against the CLI's CSVs ---

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
#An empty cell where a bin has no pair; else the shortest text that reads back exactly.
        if want["abs_dz_mean_b"] == "":
            assert math.isnan(row["abs_depth_error_mean_b_m"])
        else:
            assert row["abs_depth_error_mean_b_m"] == float(want["abs_dz_mean_b"])

#-- - Bad input -- -

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
#A bad detection line : the CLI's message, as a ParseError.
    bad = data / "eval_bad_det"
    with pytest.raises(stereodet.ParseError) as caught:
        stereodet.evaluate(bad / "label_2", bad / "det")
    out = cli("eval", "--gt", bad / "label_2", "--det", bad / "det", check=False)
    assert out.returncode != 0 and f"stereodet: error: {caught.value}" in out.stderr
    assert stereodet.evaluate(bad / "label_2", bad / "det", lenient=True).to_dict()[
        "input"]["num_skipped_lines"] == 1


def test_labels_as_detections_with_score_if_missing(data, cli, tmp_path):
    labels = data / "eval_compare" / "label_2"
    with pytest.raises(stereodet.ParseError, match=r"a label line: to evaluate labels as"):
        stereodet.evaluate(labels, labels, classes=["Car"], metrics=["2d"])
    result = stereodet.evaluate(labels, labels, classes=["Car"], metrics=["2d"],
                                matcher="optimal", score_if_missing=1.0, out=tmp_path / "py")
    assert result.ap("Car", "2d", "moderate") == 100.0
    assert result.to_dict()["input"]["score_if_missing"] == 1.0
    cli("eval", "--gt", labels, "--det", labels, "--classes", "Car", "--metrics", "2d",
        "--matcher", "optimal", "--score", "1", "--out", tmp_path / "cli")
    with open(tmp_path / "cli" / "results.json") as f:
        assert json.load(f)["input"] == result.to_dict()["input"]
    with pytest.raises(ValueError, match="score_if_missing is for detection folders"):
        stereodet.evaluate([], [], score_if_missing=1.0)


def test_bootstrap_intervals_are_the_clis(data, cli, tmp_path):
    small = data / "eval_small"
    cli("eval", "--gt", small, "--det", small / "det", "--classes", "Car", "--metrics", "2d,bev",
        "--breakdown", "distance=0,30,inf", "--bootstrap", "40", "--bootstrap-seed", "3",
        "--out", tmp_path / "cli")
    with open(tmp_path / "cli" / "results.json") as f:
        expected = json.load(f)
    from_folders = stereodet.evaluate(small, small / "det", classes=["Car"], metrics=["2d", "bev"],
                                      breakdowns=["distance=0,30,inf"], bootstrap=40,
                                      bootstrap_seed=3).to_dict()
    gt = [stereodet.kitti.read_objects(p) for p in sorted((small / "label_2").glob("*.txt"))]
    dt = [stereodet.kitti.read_objects(small / "det" / p.name, "detection")
          for p in sorted((small / "label_2").glob("*.txt"))]
    from_annos = stereodet.evaluate(gt, dt, classes=["Car"], metrics=["2d", "bev"],
                                    breakdowns=["distance=0,30,inf"], bootstrap=40,
                                    bootstrap_seed=3).to_dict()
    expected["bootstrap"].pop("seconds")
    for got in (from_folders, from_annos):
        got["bootstrap"].pop("seconds")  # the one field that is a clock's
        assert got["bootstrap"] == expected["bootstrap"]
        for a, b in zip(got["results"], expected["results"]):
            assert a.get("bootstrap") == b.get("bootstrap")
            for bin_a, bin_b in zip(a.get("breakdown", []), b.get("breakdown", [])):
                assert bin_a["bootstrap"] == bin_b["bootstrap"]
    assert "bootstrap" in expected["results"][0]
    with pytest.raises(ValueError, match="bootstrap_confidence"):
        stereodet.evaluate(gt, dt, bootstrap=10, bootstrap_confidence=1.5)


def test_bca_intervals_are_the_clis(data, cli, tmp_path):
    small = data / "eval_small"
    cli("eval", "--gt", small, "--det", small / "det", "--classes", "Car", "--metrics", "2d",
        "--bootstrap", "40", "--bootstrap-method", "bca", "--out", tmp_path / "cli")
    with open(tmp_path / "cli" / "results.json") as f:
        expected = json.load(f)
    got = stereodet.evaluate(small, small / "det", classes=["Car"], metrics=["2d"], bootstrap=40,
                             bootstrap_method="bca").to_dict()
    assert expected["bootstrap"]["method"] == got["bootstrap"]["method"] == "bca"
    for a, b in zip(got["results"], expected["results"]):
        assert a.get("bootstrap") == b.get("bootstrap")
    with pytest.raises(ValueError, match="bootstrap_method"):
        stereodet.evaluate(small, small / "det", bootstrap=10, bootstrap_method="basic")
