"""stereodet.coco: COCO-format bbox evaluation from Python, equal to the CLI's COCO mode (which
equals pycocotools: tests/data/coco_small/pycocotools_expected.txt is pycocotools' printout)."""

import json

import numpy as np
import pytest

import stereodet
import stereodet.coco as coco


def expected_summary(data):
    return (data / "coco_small" / "pycocotools_expected.txt").read_text()


def test_paths_dicts_and_coco_objects_give_pycocotools_numbers(data, cli, tmp_path):
    gt_path, dt_path = data / "coco_small" / "gt.json", data / "coco_small" / "det.json"
    from_paths = coco.evaluate(gt_path, dt_path)
    assert str(from_paths) == expected_summary(data)
    # The loaded JSON, and pycocotools-like objects (a .dataset dict; loadRes' holds the
    # detections as "annotations", with numpy numbers in them).
    gt, dt = json.loads(gt_path.read_text()), json.loads(dt_path.read_text())
    from_dicts = coco.evaluate(gt, dt)
    assert np.array_equal(from_dicts.stats, from_paths.stats)

    class FakeCoco:
        def __init__(self, dataset):
            self.dataset = dataset

    dt_numpy = [dict(d, bbox=np.array(d["bbox"]), score=np.float32(d["score"]).item())
                for d in dt]
    from_objects = coco.evaluate(FakeCoco(gt), FakeCoco({"annotations": dt_numpy}))
    assert np.array_equal(from_objects.precision, from_paths.precision)
    # The CLI's arrays (its .npy files) are these.
    cli("eval", "--coco-gt", gt_path, "--coco-det", dt_path, "--out", tmp_path / "cli")
    assert np.array_equal(np.load(tmp_path / "cli" / "precision.npy"), from_paths.precision)
    assert from_paths.precision.shape == (10, 101, 5, 4, 3)
    assert from_paths.recall.shape == (10, 5, 4, 3)
    assert from_paths.stats.shape == (12,)
    assert from_paths.category_ids == sorted(from_paths.category_ids)


def test_cocoeval_drop_in(data, capsys):
    gt = json.loads((data / "coco_small" / "gt.json").read_text())
    dt = json.loads((data / "coco_small" / "det.json").read_text())
    E = coco.COCOeval(gt, dt, "bbox")
    E.evaluate()
    E.accumulate()
    E.summarize()
    assert capsys.readouterr().out == expected_summary(data)
    assert E.stats[0] == pytest.approx(0.409, abs=5e-4)
    assert E.eval["precision"].shape == (10, 101, 5, 4, 3)
    with pytest.raises(NotImplementedError, match="bbox only"):
        coco.COCOeval(gt, dt, "segm")
    with pytest.raises(RuntimeError, match="evaluate"):
        coco.COCOeval(gt, dt).accumulate()


def test_bad_input_names_the_element(data):
    gt = json.loads((data / "coco_small" / "gt.json").read_text())
    with pytest.raises(stereodet.ParseError, match=r"image 999 is not in the ground truth"):
        coco.evaluate(gt, [{"image_id": 999, "category_id": 1, "bbox": [0, 0, 1, 1],
                            "score": 1.0}])
    with pytest.raises(TypeError, match="expected a path"):
        coco.evaluate(42, [])


def test_optimal_matcher_and_brier_equal_the_cli(data, cli, tmp_path):
    gt_path, dt_path = data / "coco_small" / "gt.json", data / "coco_small" / "det.json"
    greedy = coco.evaluate(gt_path, dt_path)
    assert greedy.matcher == "coco" and greedy.score_stats is None and greedy.cells == {}
    optimal = coco.evaluate(gt_path, dt_path, matcher="optimal", brier=True, score_threshold=0.1)
    assert optimal.matcher == "optimal"
    # Never fewer true positives than the greedy matching, at any threshold, range or max_dets.
    assert np.all(optimal.recall >= greedy.recall)
    cli("eval", "--coco-gt", gt_path, "--coco-det", dt_path, "--matcher", "optimal",
        "--score-threshold", "0.1", "--out", tmp_path / "cli")
    assert np.array_equal(np.load(tmp_path / "cli" / "precision.npy"), optimal.precision)
    results = json.loads((tmp_path / "cli" / "results.json").read_text())
    assert optimal.score_stat_names[0] == "BL" and len(optimal.score_stats) == 12
    for name, value in zip(optimal.score_stat_names, optimal.score_stats):
        assert results["score_stats"][name] == value
    assert optimal.probability_metrics is True
    cells = optimal.cells
    assert cells["tp"].shape == (10, 5, 4)
    assert np.array_equal(cells["tp"] + cells["fn"], cells["num_valid_gt"])
    # The drop-in takes the matcher too.
    E = coco.COCOeval(json.loads(gt_path.read_text()), json.loads(dt_path.read_text()),
                      matcher="optimal")
    E.evaluate()
    assert np.array_equal(E.result.precision, optimal.precision)
    with pytest.raises(ValueError, match="matcher"):
        coco.evaluate(gt_path, dt_path, matcher="kitti")


def test_bootstrap_and_compare_equal_the_cli(data, cli, tmp_path):
    gt_path, dt_path = data / "coco_small" / "gt.json", data / "coco_small" / "det.json"
    r = coco.evaluate(gt_path, dt_path, bootstrap=40, bootstrap_seed=3)
    cli("eval", "--coco-gt", gt_path, "--coco-det", dt_path, "--bootstrap", "40",
        "--bootstrap-seed", "3", "--out", tmp_path / "cli")
    results = json.loads((tmp_path / "cli" / "results.json").read_text())
    estimate, lower, upper = r.intervals["AP"]
    assert estimate == r.stats[0]
    assert results["bootstrap"]["stats"]["AP"]["lower"] == lower
    assert results["bootstrap"]["stats"]["AP"]["upper"] == upper
    assert r.bootstrap_samples.shape == (40, 12)
    # A against itself: every difference exactly 0.
    c = coco.compare(gt_path, dt_path, dt_path, bootstrap=20)
    assert c.intervals["AP"] == (0.0, 0.0, 0.0)
    assert np.array_equal(c.b_stats, c.a.stats)
    assert c.difference[0] == 0.0 and np.isnan(c.difference[5]) == (c.a.stats[5] < 0)


def test_bca_intervals_equal_the_cli(data, cli, tmp_path):
    gt_path, dt_path = data / "coco_small" / "gt.json", data / "coco_small" / "det.json"
    r = coco.evaluate(gt_path, dt_path, bootstrap=60, bootstrap_method="bca")
    cli("eval", "--coco-gt", gt_path, "--coco-det", dt_path, "--bootstrap", "60",
        "--bootstrap-method", "bca", "--out", tmp_path / "cli")
    results = json.loads((tmp_path / "cli" / "results.json").read_text())
    assert results["bootstrap"]["method"] == "bca"
    _, lower, upper = r.intervals["AP"]
    assert results["bootstrap"]["stats"]["AP"]["lower"] == lower
    assert results["bootstrap"]["stats"]["AP"]["upper"] == upper
    with pytest.raises(ValueError, match="bootstrap_method"):
        coco.evaluate(gt_path, dt_path, bootstrap=5, bootstrap_method="basic")


def test_category_stats_equal_the_cli(data, cli, tmp_path):
    gt_path, dt_path = data / "coco_small" / "gt.json", data / "coco_small" / "det.json"
    r = coco.evaluate(gt_path, dt_path)
    out = cli("eval", "--coco-gt", gt_path, "--coco-det", dt_path, "--coco-per-category",
              "--out", tmp_path / "cli")
    results = json.loads((tmp_path / "cli" / "results.json").read_text())
    assert r.category_stats.shape == (5, 12)
    for k, category in enumerate(results["categories"]):
        assert category["stats"]["AP"] == r.category_stats[k, 0]
    # The mean of the categories that have ground truth is the AP here (same-sized slices).
    defined = r.category_stats[:, 0][r.category_stats[:, 0] >= 0]
    assert defined.mean() == pytest.approx(r.stats[0], abs=1e-12)
    assert "category" in out.stdout and "AR100" in out.stdout


def test_brier_intervals_with_bootstrap(data, cli, tmp_path):
    gt_path, dt_path = data / "coco_small" / "gt.json", data / "coco_small" / "det.json"
    r = coco.evaluate(gt_path, dt_path, brier=True, bootstrap=30)
    cli("eval", "--coco-gt", gt_path, "--coco-det", dt_path, "--coco-brier", "--bootstrap", "30",
        "--out", tmp_path / "cli")
    results = json.loads((tmp_path / "cli" / "results.json").read_text())
    estimate, lower, upper = r.intervals["BL"]
    assert estimate == r.score_stats[0]
    assert results["bootstrap"]["score_stats"]["BL"]["lower"] == lower
    assert results["bootstrap"]["score_stats"]["BL"]["upper"] == upper
    assert results["bootstrap"]["score_stats"]["ECE"]["lower"] is None  # not resampled


def test_stable_area_ranges_equal_the_cli(data, cli, tmp_path):
    gt_path, dt_path = data / "coco_small" / "gt.json", data / "coco_small" / "det.json"
    r = coco.evaluate(gt_path, dt_path, area_ranges="stable")
    cli("eval", "--coco-gt", gt_path, "--coco-det", dt_path, "--coco-area-ranges", "stable",
        "--out", tmp_path / "cli")
    results = json.loads((tmp_path / "cli" / "results.json").read_text())
    assert results["options"]["area_ranges_mode"] == "stable"
    assert list(r.stats) == list(results["stats"].values())
    assert np.array_equal(r.precision, np.load(tmp_path / "cli" / "precision.npy"))
    # Range "all" is pycocotools' own under both.
    p = coco.evaluate(gt_path, dt_path)
    assert r.stats[0] == p.stats[0] and r.stats[8] == p.stats[8]
    with pytest.raises(ValueError, match="optimal matcher"):
        coco.evaluate(gt_path, dt_path, area_ranges="stable", matcher="optimal")
    with pytest.raises(ValueError, match="area_ranges"):
        coco.evaluate(gt_path, dt_path, area_ranges="naive")
