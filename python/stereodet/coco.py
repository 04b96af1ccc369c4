"""COCO-format bbox evaluation equal to pycocotools' COCOeval, in C++ (`stereodet eval --coco-gt`).

    import stereodet.coco
    result = stereodet.coco.evaluate("instances_val2017.json", "detections.json")
    result.stats          # summarize()'s 12 numbers, numpy float64
    result.precision      # (T, R, K, A, M), as COCOeval.eval["precision"]
    print(result)         # summarize()'s printout, line for line

    # A drop-in for pycocotools in a training loop (torchvision's, detectron2's evaluators):
    from stereodet.coco import COCOeval          # instead of pycocotools.cocoeval's
    E = COCOeval(coco_gt, coco_dt, "bbox")       # pycocotools COCO objects, dicts or paths
    E.evaluate(); E.accumulate(); E.summarize()
    E.stats, E.eval["precision"]

The numbers are pycocotools 2.0's to the last digit (docs/metrics.md, "COCO mode": which of its
quirks are kept, and --coco-honor-ignore's fix of the iscrowd one); segm and keypoints are not
evaluated.
"""
import json
import math
import os
from typing import Any, Dict, Iterable, List, Optional, Sequence, Union

import numpy as np

from . import _core

PathLike = Union[str, "os.PathLike[str]"]


def _text(source: Any, what: str) -> "tuple[str, str]":
    """(JSON text, name for messages) of a path, a loaded dict / list, or a pycocotools COCO."""
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        with open(path, "rb") as f:
            return f.read().decode("utf-8"), path
    dataset = getattr(source, "dataset", None)  # pycocotools.coco.COCO
    if isinstance(dataset, dict):
        if what == "results":
            # loadRes' COCO: its dataset holds the detections as "annotations".
            return (json.dumps(dataset.get("annotations", []), default=_json_number),
                    f"<{what}: COCO object>")
        return json.dumps(dataset, default=_json_number), f"<{what}: COCO object>"
    if isinstance(source, (dict, list)):
        return json.dumps(source, default=_json_number), f"<{what}>"
    raise TypeError(f"{what}: expected a path, a dict / list as json.load gives it, or a "
                    f"pycocotools COCO object; got {type(source).__name__}")


def _json_number(value: Any) -> Any:
    """numpy numbers and arrays in loaded data (loadRes keeps numpy scalars) as JSON numbers."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON: {type(value).__name__}")


class CocoResult:
    """COCOeval's numbers for bbox: stats (12), precision (T, R, K, A, M), recall (T, K, A, M),
    scores (T, R, K, A, M), the image and category ids, and summary (the printout)."""

    def __init__(self, d: dict):
        self.stats: np.ndarray = d["stats"]
        self.precision: np.ndarray = d["precision"]
        # (K, 12): each category's own 12 numbers (COCOeval with params.catIds = [id]), in
        # category_ids' order; [:, 0] is detectron2's per-category AP.
        self.category_stats: np.ndarray = d["category_stats"]
        self.recall: np.ndarray = d["recall"]
        self.scores: np.ndarray = d["scores"]
        self.image_ids = list(d["image_ids"])
        self.category_ids = list(d["category_ids"])
        self.category_names = list(d["category_names"])
        self.iou_thresholds = np.array(d["iou_thresholds"])
        self.recall_thresholds = np.array(d["recall_thresholds"])
        self.max_dets = list(d["max_dets"])
        self.area_ranges = list(d["area_ranges"])
        self.summary: str = d["summary"]
        self.num_gt = d["num_gt"]
        self.num_detections = d["num_detections"]
        self.seconds = d["seconds"]
        self.matcher: str = d["matcher"]
        # With brier=True: the 12 operating-point numbers (score_stat_names: BL, BL50, BL75, BD,
        # ..., ECE75; -1 where undefined), whether the scores were probabilities, and the cells:
        # a dict of (T, K, A) arrays num_valid_gt, tp, fp, fn, brier_labels, brier_detections,
        # brier_all, ece (NaN where undefined).
        self.score_stats: Optional[np.ndarray] = d.get("score_stats")
        self.score_stat_names: List[str] = list(d.get("score_stat_names", []))
        self.probability_metrics: Optional[bool] = d.get("probability_metrics")
        self.cells: Dict[str, np.ndarray] = dict(d.get("cells", {}))
        # With bootstrap=N: {"AP": (estimate, lower, upper), ...} over images, and every
        # resample's 12 numbers ((N, 12), NaN where a slice has no ground truth).
        boot = d.get("bootstrap")
        self.intervals: Dict[str, tuple] = dict(boot["intervals"]) if boot else {}
        self.bootstrap_samples: Optional[np.ndarray] = boot["samples"] if boot else None

    def __str__(self) -> str:
        return self.summary

    def __repr__(self) -> str:
        return f"CocoResult(AP={self.stats[0]:.3f}, AP50={self.stats[1]:.3f}, " \
               f"{len(self.image_ids)} images, {len(self.category_ids)} categories)"


class CocoComparison:
    """compare()'s result: a and b (CocoResult each), difference = a.stats - b.stats (NaN where
    either is -1), and with bootstrap the paired intervals of A - B ({"AP": (estimate, lower,
    upper), ...}) and their resamples."""

    def __init__(self, a: CocoResult, b_stats: np.ndarray, d: dict):
        self.a = a
        self.b_stats: np.ndarray = b_stats
        self.difference = np.where((a.stats < 0) | (b_stats < 0), np.nan, a.stats - b_stats)
        boot = d.get("bootstrap_difference")
        self.intervals: Dict[str, tuple] = dict(boot["intervals"]) if boot else {}
        self.bootstrap_samples: Optional[np.ndarray] = boot["samples"] if boot else None

    def __repr__(self) -> str:
        return f"CocoComparison(AP A={self.a.stats[0]:.3f}, B={self.b_stats[0]:.3f})"


def evaluate(gt: Any, dt: Any, *, honor_ignore_flag: bool = False,
             max_dets: Sequence[int] = (1, 10, 100), num_threads: int = 0,
             matcher: str = "coco", brier: bool = False,
             score_threshold: Optional[float] = None, score_transform: str = "none",
             calibration_bins: int = 10, bootstrap: int = 0, bootstrap_seed: int = 1,
             confidence: float = 0.95, bootstrap_method: str = "percentile",
             area_ranges: str = "pycocotools") -> CocoResult:
    """COCOeval(gt, gt.loadRes(dt), "bbox").evaluate(); .accumulate(); .summarize().

    gt: a COCO ground-truth file's path, its loaded dict, or a pycocotools COCO object.
    dt: a results file's path, its loaded list of {image_id, category_id, bbox, score}, or the
      COCO object of loadRes.
    honor_ignore_flag: also ignore ground truths whose "ignore" is set (pycocotools overwrites it
      with "iscrowd": the CLI's --coco-honor-ignore).
    max_dets: Params.maxDets, three increasing numbers.
    matcher: "coco" (pycocotools' greedy matching, the default) or "optimal" (the most true
      positives at every score threshold; docs/metrics.md, the CLI's --matcher optimal).
    brier: also the operating point's counts, Brier scores and calibration per IoU threshold,
      category and area range (result.cells, result.score_stats; the CLI's --coco-brier), at
      score_threshold (None: every detection), with score_transform ("none" or "sigmoid", for
      logits) and calibration_bins reliability bins.
    bootstrap: N > 0 resamples of the images (seed bootstrap_seed): result.intervals holds each
      of the 12 numbers' percentile interval at `confidence` (the CLI's --bootstrap N), each
      resample exactly COCOeval on the resampled image list (docs/metrics.md);
      bootstrap_method "bca" reads bias-corrected and accelerated intervals from the same
      resamples (--bootstrap-method bca).
    area_ranges: "pycocotools" (each area range matched on its own) or "stable" (every range
      counted from the one matching of range "all", the paper's stable filter; the coco matcher
      only; the CLI's --coco-area-ranges stable).

    Raises stereodet.ParseError for a malformed file (naming the element and field), ValueError
    for a bad option, OSError for a file that cannot be read.
    """
    gt_text, gt_source = _text(gt, "ground truth")
    dt_text, dt_source = _text(dt, "results")
    threshold = -math.inf if score_threshold is None else float(score_threshold)
    return CocoResult(_core._coco_evaluate(gt_text, gt_source, dt_text, dt_source,
                                           honor_ignore_flag, list(max_dets), num_threads,
                                           matcher, brier, threshold, score_transform,
                                           calibration_bins, bootstrap, bootstrap_seed,
                                           confidence, bootstrap_method, None, "",
                                           area_ranges))


def compare(gt: Any, dt_a: Any, dt_b: Any, *, bootstrap: int = 0, bootstrap_seed: int = 1,
            confidence: float = 0.95, bootstrap_method: str = "percentile",
            matcher: str = "coco", honor_ignore_flag: bool = False,
            max_dets: Sequence[int] = (1, 10, 100), num_threads: int = 0) -> CocoComparison:
    """Two detection sets of one ground truth, number by number (the CLI's --coco-det-b): with
    bootstrap=N, the paired intervals of A - B over the same resampled images."""
    gt_text, gt_source = _text(gt, "ground truth")
    a_text, a_source = _text(dt_a, "results A")
    b_text, b_source = _text(dt_b, "results B")
    d = _core._coco_evaluate(gt_text, gt_source, a_text, a_source, honor_ignore_flag,
                             list(max_dets), num_threads, matcher, False, -math.inf, "none", 10,
                             bootstrap, bootstrap_seed, confidence, bootstrap_method, b_text,
                             b_source)
    return CocoComparison(CocoResult(d), d["stats_b"], d)


class COCOeval:
    """pycocotools.cocoeval.COCOeval's usage for iouType "bbox": construct, evaluate(),
    accumulate(), summarize(), then .stats and .eval["precision" | "recall" | "scores"]. The work
    is done once, in evaluate(); accumulate() only checks the order of the calls."""

    def __init__(self, cocoGt: Any = None, cocoDt: Any = None, iouType: str = "bbox", *,
                 matcher: str = "coco"):
        """matcher: "coco" (pycocotools' numbers) or "optimal" (the paper's matcher: the same
        arrays and stats read from the association of the most true positives)."""
        if iouType != "bbox":
            raise NotImplementedError(f"stereodet.coco.COCOeval evaluates bbox only, not {iouType}")
        self.cocoGt, self.cocoDt = cocoGt, cocoDt
        self.matcher = matcher
        self.params = _Params()
        self.stats = np.zeros(12)
        self.eval: dict = {}
        self.result: Optional[CocoResult] = None

    def evaluate(self) -> None:
        if self.cocoGt is None or self.cocoDt is None:
            raise ValueError("COCOeval needs the ground truth and the detections")
        self.result = evaluate(self.cocoGt, self.cocoDt, max_dets=self.params.maxDets,
                               matcher=self.matcher)

    def accumulate(self) -> None:
        if self.result is None:
            raise RuntimeError("call evaluate() first")
        r = self.result
        self.eval = {"params": self.params, "counts": list(r.precision.shape),
                     "precision": r.precision, "recall": r.recall, "scores": r.scores}

    def summarize(self) -> None:
        if self.result is None:
            raise RuntimeError("call evaluate() and accumulate() first")
        print(self.result.summary, end="" if self.result.summary.endswith("\n") else "\n")
        self.stats = self.result.stats.copy()


class _Params:
    """The parts of COCOeval.params that callers read or set: maxDets, iouThrs, recThrs."""

    def __init__(self):
        self.iouType = "bbox"
        self.maxDets = [1, 10, 100]
        self.iouThrs = np.linspace(.5, 0.95, int(np.round((0.95 - .5) / .05)) + 1, endpoint=True)
        self.recThrs = np.linspace(.0, 1.00, int(np.round((1.00 - .0) / .01)) + 1, endpoint=True)
        self.areaRngLbl = ["all", "small", "medium", "large"]
