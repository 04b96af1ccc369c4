"""stereodet.mmdet3d.kitti_eval against mmdetection3d's own kitti_eval.

tests/data/eval_small/mmdet3d_expected.json holds what mmdetection3d's
mmdet3d/evaluation/functional/kitti_utils/eval.py (commit fe25f7a, run unmodified from a scratch
copy with NUMBA_ENABLE_CUDASIM=1, never committed) returned on tests/data/eval_small for three calls:
the text, and every dict value as repr(float) (exact).
"""

import json

import numpy as np
import pytest

from stereodet import kitti
from stereodet.mmdet3d import kitti_eval


@pytest.fixture(scope="module")
def annos(data):
    root = data / "eval_small"
    ids = sorted(p.stem for p in (root / "label_2").glob("*.txt"))
    return ([kitti.read_objects(root / "label_2" / f"{i}.txt", "label") for i in ids],
            [kitti.read_objects(root / "det" / f"{i}.txt", "detection") for i in ids])


@pytest.fixture(scope="module")
def expected(data):
    return json.loads((data / "eval_small" / "mmdet3d_expected.json").read_text())


@pytest.mark.parametrize("call", ["all", "car_bbox_bev", "ped_cyc_bbox3d"])
def test_kitti_eval_returns_mmdetection3ds_text_and_dict(annos, expected, call):
    e = expected[call]
    eval_types = list(e["eval_types"])
    text, ret = kitti_eval(*annos, e["classes"], eval_types=eval_types)
    assert eval_types == e["eval_types"]  # not modified (mmdetection3d appends "aos")
    assert text == e["text"]
    assert list(ret) == list(e["ret_dict"])  # its keys, in its order
    for key, value in e["ret_dict"].items():
        assert isinstance(ret[key], np.float64), key
        assert repr(float(ret[key])) == value, key


def test_kitti_eval_overall_is_the_mean_of_the_classes(annos):
    _, ret = kitti_eval(*annos, ["Car", "Pedestrian", "Cyclist"])
    for level in ("easy", "moderate", "hard"):
        for kind in ("3D", "BEV", "2D"):
            per_class = [ret[f"KITTI/{c}_{kind}_AP40_{level}_strict"]
                         for c in ("Car", "Pedestrian", "Cyclist")]
            assert ret[f"KITTI/Overall_{kind}_AP40_{level}"] == pytest.approx(np.mean(per_class),
                                                                              abs=1e-12)
    _, one = kitti_eval(*annos, "Car")
    assert not any("Overall" in k for k in one)
    assert one["KITTI/Car_3D_AP40_moderate_strict"] == ret["KITTI/Car_3D_AP40_moderate_strict"]


def test_kitti_eval_without_alpha_has_no_aos_and_checks_its_arguments(annos):
    gt, dt = annos
    no_alpha = [dict(d, alpha=np.full(len(d["name"]), -10.0)) for d in dt]
    text, _ = kitti_eval(gt, no_alpha, [0, 2])
    assert "aos" not in text and "Cyclist AP40@0.50, 0.25, 0.25:" in text
    with pytest.raises(ValueError, match="unknown class 5"):
        kitti_eval(gt, dt, 5)  # Truck is OpenPCDet's, not mmdetection3d's
    with pytest.raises(ValueError, match="at least one"):
        kitti_eval(gt, dt, "Car", eval_types=[])
    with pytest.raises(ValueError, match="bbox when evaluating aos"):
        kitti_eval(gt, dt, "Car", eval_types=["bev", "aos"])
