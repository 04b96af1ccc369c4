"""mmdetection3d's KITTI evaluation, as a drop-in.

    from stereodet.mmdet3d import kitti_eval
    result_str, ret_dict = kitti_eval(gt_annos, dt_annos, ["Car", "Pedestrian", "Cyclist"])

The same call and return value as mmdet3d.evaluation.functional.kitti_utils.eval.kitti_eval (the
function KittiMetric calls): the text it logs (AP11 then AP40, per class the strict and the loose
overlap set, bbox / bev / 3d and aos, then the overall means over the classes) and its dict
("KITTI/Car_3D_AP40_moderate_strict", ..., "KITTI/Overall_BEV_AP11_hard"; numpy float64). The
numbers come from `stereodet eval --compat openpcdet` (mmdetection3d's kitti_utils and OpenPCDet's
kitti_object_eval_python are the same algorithm; docs/metrics.md), computed in C++ with the GIL
released; the 41-slot precision arrays are summed here exactly as mmdetection3d sums them.
"""

from __future__ import annotations

from typing import Any, Dict, List, Sequence, Tuple

import numpy as np

from . import _core
from .evaluation import Annos

__all__ = ["kitti_eval"]

# mmdetection3d's class numbering and overlaps (min_overlaps[set, metric, class]: bbox, bev, 3d).
_CLASSES = {0: "Car", 1: "Pedestrian", 2: "Cyclist", 3: "Van", 4: "Person_sitting"}
_STRICT = {"Car": 0.7, "Pedestrian": 0.5, "Cyclist": 0.5, "Van": 0.7, "Person_sitting": 0.5}
_LOOSE = {"Car": (0.7, 0.5, 0.5), "Pedestrian": (0.5, 0.25, 0.25), "Cyclist": (0.5, 0.25, 0.25),
          "Van": (0.7, 0.5, 0.5), "Person_sitting": (0.5, 0.25, 0.25)}
_LEVELS = ("easy", "moderate", "hard")


def _class_names(current_classes: Any) -> List[str]:
    if not isinstance(current_classes, (list, tuple)):
        current_classes = [current_classes]
    names = []
    by_name = {v: v for v in _CLASSES.values()}
    for c in current_classes:
        if isinstance(c, str) and c in by_name:
            names.append(c)
        elif isinstance(c, (int, np.integer)) and not isinstance(c, bool) and int(c) in _CLASSES:
            names.append(_CLASSES[int(c)])
        else:
            raise ValueError(f"current_classes: unknown class {c!r} (a name or 0..4 of "
                             f"{', '.join(_CLASSES.values())}, as mmdetection3d numbers them)")
    return names


def _computes_aos(gt_annos: Sequence[Annos], dt_annos: Sequence[Annos]) -> bool:
    """mmdetection3d's rule: some detection has alpha != -10, and the first label of the first
    label frame that decides it has alpha != -10 (mmdetection3d raises IndexError on a frame without
    labels before that one; this skips it)."""
    pred_alpha = any(np.any(np.asarray(a["alpha"]) != -10) for a in dt_annos)
    valid_alpha_gt = False
    for a in gt_annos:
        alpha = np.asarray(a["alpha"])
        if alpha.shape[0] != 0 and alpha[0] != -10:
            valid_alpha_gt = True
            break
    return pred_alpha and valid_alpha_gt


def kitti_eval(gt_annos: Sequence[Annos], dt_annos: Sequence[Annos], current_classes: Any,
               eval_types: Sequence[str] = ("bbox", "bev", "3d")) -> Tuple[str, Dict[str, Any]]:
    """A drop-in for mmdetection3d's kitti_eval (mmdet3d/evaluation/functional/kitti_utils/eval.py).

    gt_annos, dt_annos: annotation dicts, one per frame (stereodet.kitti's, mmdetection3d's layout).
    current_classes: a name, a class index 0..4 (Car, Pedestrian, Cyclist, Van, Person_sitting), or
    a list of either. eval_types: any of "bbox", "bev", "3d" ("aos" is added, as mmdetection3d does,
    when the alphas are valid; unlike mmdetection3d the caller's list is not modified).
    Returns (result_str, ret_dict) as mmdetection3d does.
    """
    eval_types = list(eval_types)
    if not eval_types:
        raise ValueError("eval_types: must contain at least one evaluation type")
    unknown = [t for t in eval_types if t not in ("bbox", "bev", "3d", "aos")]
    if unknown:
        raise ValueError(f"eval_types: unknown {unknown} (bbox, bev, 3d)")
    if "aos" in eval_types and "bbox" not in eval_types:
        raise ValueError("eval_types: must evaluate bbox when evaluating aos")
    names = _class_names(current_classes)
    compute_aos = _computes_aos(gt_annos, dt_annos)
    frames = _core._frames_from_annos(gt_annos, dt_annos)
    _, strict, loose = _core._openpcdet_eval(frames, names, 0)
    if compute_aos and not strict.aos_computed:
        # stereodet's OpenPCDet rule decides AOS on the first detection's alpha alone.
        raise ValueError("kitti_eval: the first detection has alpha -10 but others have a valid "
                         "alpha; mmdetection3d computes AOS here and stereodet does not: give "
                         "every detection its alpha, or -10 to all")

    # precision[metric][class, difficulty, set, 41] as mmdetection3d's eval_class returns them.
    def precision(metric: str, aos: bool = False) -> np.ndarray:
        out = np.zeros((len(names), 3, 2, 41))
        for j, name in enumerate(names):
            for k, result in enumerate((strict, loose)):
                for d, level in enumerate(_LEVELS):
                    cell = result.find(name, metric, level)
                    values = cell.kitti_aos if aos else cell.kitti_precision
                    out[j, d, k, :len(values)] = values
        return out

    def map11(prec: np.ndarray) -> np.ndarray:  # mmdetection3d's get_mAP11
        sums = 0
        for i in range(0, prec.shape[-1], 4):
            sums = sums + prec[..., i]
        return sums / 11 * 100

    def map40(prec: np.ndarray) -> np.ndarray:  # mmdetection3d's get_mAP40
        sums = 0
        for i in range(1, prec.shape[-1]):
            sums = sums + prec[..., i]
        return sums / 40 * 100

    prec = {t: precision(m) for t, m in (("bbox", "2d"), ("bev", "bev"), ("3d", "3d"))
            if t in eval_types}
    if compute_aos and "bbox" in eval_types:
        prec["aos"] = precision("2d", aos=True)
    result = ""
    ret_dict: Dict[str, Any] = {}
    for tag, summed in (("AP11", map11), ("AP40", map40)):
        maps = {t: summed(p) for t, p in prec.items()}  # [class, difficulty, set]
        result += f"\n----------- {tag} Results ------------\n\n"
        for j, name in enumerate(names):
            for i in range(2):
                overlaps = (_STRICT[name],) * 3 if i == 0 else _LOOSE[name]
                result += "{} {}@{:.2f}, {:.2f}, {:.2f}:\n".format(name, tag, *overlaps)
                for t, label, digits in (("bbox", "bbox", 4), ("bev", "bev ", 4),
                                         ("3d", "3d  ", 4), ("aos", "aos ", 2)):
                    if t in maps:
                        result += f"{label} {tag}:" + ", ".join(
                            f"{v:.{digits}f}" for v in maps[t][j, :, i]) + "\n"
                for d, level in enumerate(_LEVELS):
                    postfix = f"{level}_strict" if i == 0 else f"{level}_loose"
                    for t, key in (("3d", "3D"), ("bev", "BEV"), ("bbox", "2D")):
                        if t in maps:
                            ret_dict[f"KITTI/{name}_{key}_{tag}_{postfix}"] = maps[t][j, d, i]
        if len(names) > 1:
            result += "\nOverall {}@{}, {}, {}:\n".format(tag, *_LEVELS)
            means = {t: m.mean(axis=0) for t, m in maps.items()}
            for t, label, digits in (("bbox", "bbox", 4), ("bev", "bev ", 4), ("3d", "3d  ", 4),
                                     ("aos", "aos ", 2)):
                if t in means:
                    result += f"{label} {tag}:" + ", ".join(
                        f"{v:.{digits}f}" for v in means[t][:, 0]) + "\n"
            for d, level in enumerate(_LEVELS):
                for t, key in (("3d", "3D"), ("bev", "BEV"), ("bbox", "2D")):
                    if t in means:
                        ret_dict[f"KITTI/Overall_{key}_{tag}_{level}"] = means[t][d, 0]
    return result, ret_dict
