"""Evaluation: KITTI-devkit-exact AP and the corrected metrics, on folders or in memory.

    result = stereodet.evaluate("kitti", "results/data", split="val")           # folders
    result = stereodet.evaluate(gt_annos, dt_annos)                             # annotation dicts
    result.ap("Car", "3d", "moderate")         # AP_R40 in percent
    result.to_dict()                           # the CLI's results.json
    pandas.DataFrame(result.rows())            # one row per class x metric x difficulty
    stereodet.evaluate("kitti", "results/data", out="eval")   # + the CLI's results folder
    strict, loose = stereodet.evaluate(gt_annos, dt_annos, overlaps="strict,loose").runs
    text, figures = stereodet.get_official_eval_result(gt_annos, dt_annos, ["Car"])  # OpenPCDet's

Annotation dicts are those of stereodet.kitti (OpenPCDet's and mmdetection3d's layout, dimensions
l, h, w): gt_annos and dt_annos are lists of them, one per frame, in the same order. The numbers
are those of `stereodet eval` on the same data, to the last digit (docs/metrics.md defines them):
folders go through the CLI's library calls (pipelines/evaluation.h), and the options of every overlap
set come from its OverlapSetRuns.
"""

from __future__ import annotations

import inspect
import json
import math
import os
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core
from ._core import ClassResult, ClassSpec, EvalOptions, EvalResult

PathLike = Union[str, "os.PathLike[str]"]
Annos = Mapping[str, np.ndarray]
Source = Union[PathLike, Sequence[Annos]]

for _cls in (ClassResult, ClassSpec, EvalOptions, EvalResult):
    _cls.__module__ = "stereodet"

__all__ = ["ClassResult", "ClassSpec", "EvalOptions", "EvalResult", "analyze_errors", "compare",
           "evaluate", "filter_sweep", "get_official_eval_result"]

DEFAULT_CLASSES = ("Car", "Pedestrian", "Cyclist")


def _is_path(value: Any) -> bool:
    return isinstance(value, (str, os.PathLike))


def _frames(gt: Source, det: Source, split: Optional[PathLike], lenient: bool,
            num_threads: int, missing_as_empty: bool = False) -> Any:
    """Folders through the library's LoadEvalFrames, or annotation dicts."""
    if _is_path(gt) != _is_path(det):
        raise ValueError("gt and det: give two folders or two lists of annotation dicts")
    if _is_path(gt):
        return _core._frames_from_folders(os.fspath(gt), os.fspath(det),
                                          "" if split is None else os.fspath(split), lenient,
                                          num_threads, missing_as_empty=missing_as_empty)
    if split is not None:
        raise ValueError("split: only for folders (annotation lists are evaluated as given)")
    return _core._frames_from_annos(gt, det)


def _overlap_names(overlaps: Union[str, Iterable[str]]) -> List[str]:
    """"strict,loose" or ["strict", "loose"]: the names, in order (checked by _overlap_set_runs)."""
    if isinstance(overlaps, str):
        return [part.strip() for part in overlaps.split(",") if part.strip()]
    return [str(name) for name in overlaps]


def _runs(*, classes: Iterable[Union[str, ClassSpec]], metrics: Iterable[str],
          difficulties: Iterable[Union[str, int]], matcher: str, compat: str,
          overlaps: Union[str, Iterable[str]], filters: Any, filter_mode: str,
          score_threshold: float, score_transform: str, all_classes: bool, calibration_bins: int,
          distance_bin_m: float, max_distance_m: float, records: bool,
          num_threads: int, breakdowns: Union[str, Iterable[str]] = (),
          breakdown_naive: bool = False) -> List[EvalOptions]:
    """The evaluation runs of evaluate()'s keyword arguments, one per overlap set, as the CLI
    builds them (cli/eval_command.cc): the base options with the strict set's class specs
    (KittiClassSpec, or OpenPcdetClassSpec with compat="openpcdet"), then the library's
    OverlapSetRuns. ClassSpec objects keep their own thresholds (then one overlap set only)."""
    o = EvalOptions()
    o.compat = compat
    spec = _core._openpcdet_class_spec if o.compat == "openpcdet" else _core._kitti_class_spec
    if isinstance(classes, (str, ClassSpec)):
        classes = [classes]
    specs: List[ClassSpec] = []
    custom: Dict[int, ClassSpec] = {}
    for c in classes:
        s = c if isinstance(c, ClassSpec) else spec(str(c))
        for earlier in specs:
            if earlier.name.lower() == s.name.lower():
                raise ValueError(f"classes: {s.name!r} given twice (as {earlier.name!r})")
        if isinstance(c, ClassSpec):
            custom[len(specs)] = c
        specs.append(s)
    o.classes = specs
    o.metrics = [metrics] if isinstance(metrics, str) else list(metrics)
    o.difficulties = [difficulties] if isinstance(difficulties, (str, int)) else list(difficulties)
    o.matcher = matcher
    o.filters = filters
    o.filter_mode = filter_mode
    o.breakdowns = breakdowns if isinstance(breakdowns, str) else list(breakdowns)
    if breakdown_naive and not o.breakdowns:
        raise ValueError("breakdown_naive recomputes the bins of breakdowns: give breakdowns too")
    o.breakdown_naive = bool(breakdown_naive)
    o.score_threshold = float(score_threshold)
    o.score_transform = score_transform
    o.require_detections = not all_classes
    o.calibration_bins = calibration_bins
    o.distance_bin_m = distance_bin_m
    o.max_distance_m = max_distance_m
    o.keep_records = records
    o.num_threads = num_threads
    o.check()
    runs = _core._overlap_set_runs(o, _overlap_names(overlaps))
    if custom:  # OverlapSetRuns replaces every spec by KITTI's of the same name: put them back
        if len(runs) > 1:
            raise ValueError("overlaps: ClassSpec objects have their own thresholds; give one "
                             "overlap set (or class names)")
        run = runs[0]
        run.classes = [custom.get(i, s) for i, s in enumerate(run.classes)]
        run.check()
    return runs


def _single(runs: List[EvalOptions], what: str) -> EvalOptions:
    if len(runs) != 1:
        raise ValueError(f"overlaps: {what} takes one overlap set")
    return runs[0]


def evaluate(gt: Source, det: Source, split: Optional[PathLike] = None, *,
             matcher: str = "kitti", compat: str = "devkit",
             classes: Iterable[Union[str, ClassSpec]] = DEFAULT_CLASSES,
             metrics: Iterable[str] = ("2d", "bev", "3d"),
             difficulties: Iterable[Union[str, int]] = ("easy", "moderate", "hard"),
             overlaps: Union[str, Iterable[str]] = "strict", filters: Any = None,
             filter_mode: str = "stable", score_threshold: float = -math.inf,
             score_transform: str = "none", all_classes: bool = False, calibration_bins: int = 10,
             distance_bin_m: float = 5.0, max_distance_m: float = 80.0, records: bool = False,
             lenient: bool = False, missing_as_empty: bool = False, num_threads: int = 0,
             out: Optional[PathLike] = None,
             breakdowns: Union[str, Iterable[str]] = (), breakdown_naive: bool = False,
             score_if_missing: Optional[float] = None, bootstrap: int = 0,
             bootstrap_seed: int = 1, bootstrap_confidence: float = 0.95,
             bootstrap_method: str = "percentile") -> EvalResult:
    """Evaluates detections against labels; `stereodet eval` with the same options.

    gt, det: folders (gt: a KITTI root with training/label_2, a folder with label_2/, or a folder
      of label .txt files; det: a folder of detection .txt files, or one with data/ inside), or two
      lists of annotation dicts (stereodet.kitti's layout), one per frame, in the same order.
    split: folders only: a file of frame ids, or a name under ROOT/ImageSets ("val").
    matcher: "kitti" (the official devkit, quirks included), "optimal" or "voc".
    compat: "devkit" or "openpcdet" (OpenPCDet's / mmdetection3d's numbers; matcher kitti).
    classes: names (KITTI's thresholds and neighbours) or ClassSpec objects.
    metrics: of "2d", "bev", "3d", "let-bev", "let-3d" (LET-3D-AP at Waymo's tolerance, 10 % of the
      range, at least 0.5 m; the cells' apl_r40 / apl_r11 its LET-APL). difficulties: of "easy", "moderate", "hard".
    overlaps: "strict" (0.7 / 0.5 / 0.5), "loose" (KITTI's second set for BEV and 3D), or several,
      "strict,loose" or ["strict", "loose"] (the CLI's --overlaps): one run each (result.runs).
    filters: "min-area=100,max-distance=40" (the CLI's syntax), a dict {"min_area": 100}, or
      (bound, value) pairs; filter_mode "stable" (the paper's) or "naive".
    breakdowns: the CLI's --breakdown texts, e.g. ["distance=0,30,50,inf", "occlusion=0,1,2,4"]:
      every cell again per bin, from one matching (each ClassResult's .breakdown; docs/metrics.md,
      "Breakdowns"); breakdown_naive=True also each bin evaluated on its own, struck before
      matching, for comparison (each bin's "naive"; the CLI's --breakdown-naive).
    score_threshold: the operating point (TP/FP/FN, Brier, calibration, filters).
    score_transform: "none" or "sigmoid" (logit scores; Brier and ECE only).
    all_classes: evaluate classes without any detection too (the devkit skips them).
    records: keep what every detection and label counts as (EvalResult.records()); with out, also
      OUT/matches.csv (the CLI's --records).
    lenient: folders only: skip malformed lines (listed in to_dict()["input"]["skipped_lines"]).
    missing_as_empty: folders without a split only: evaluate labelled frames that have no
      detection file as frames without detections even when more than 10 % lack one (otherwise
      refused, OSError: a folder of detections for part of the frames would read as a weak
      detector; give `split` with the frames that were detected instead).
    num_threads: 0 = all hardware threads.
    bootstrap: N resamples of the frames (the CLI's --bootstrap N; 0 = none): percentile intervals
      of every cell's AP and Brier scores and of every breakdown bin's, in to_dict() as
      results.json has them (each cell's and bin's "bootstrap"), bootstrap_seed and
      bootstrap_confidence as --bootstrap-seed and --bootstrap-confidence; bootstrap_method
      "bca" as --bootstrap-method bca (bias-corrected and accelerated, the same resamples).
    score_if_missing: folders only: read detection lines without a score (15 fields: labels used
      as detections, for a sanity check) as detections of this score (the CLI's --score);
      otherwise such a line is an error (stereodet.ParseError naming it).
    out: write the results folder there, `stereodet eval --out`'s (results.json, summary.csv,
      curves/; result.files lists them): for folders through the CLI's very call (RunEvaluation),
      for annotation dicts through the same report writer. An earlier results folder there is
      replaced whole; a folder of other files is refused (OSError) before anything is read.

    Raises ValueError for a bad option or annotation dict, stereodet.ParseError for a bad line of
    a file, OSError for missing folders or files.
    """
    runs = _runs(classes=classes, metrics=metrics, difficulties=difficulties, matcher=matcher,
                 compat=compat, overlaps=overlaps, filters=filters, filter_mode=filter_mode,
                 score_threshold=score_threshold, score_transform=score_transform,
                 all_classes=all_classes, calibration_bins=calibration_bins,
                 distance_bin_m=distance_bin_m, max_distance_m=max_distance_m, records=records,
                 num_threads=num_threads, breakdowns=breakdowns,
                 breakdown_naive=breakdown_naive)
    target = "" if out is None else os.fspath(out)
    if out is not None and not target:
        raise ValueError("out: an empty path")
    if _is_path(gt) and _is_path(det):
        return _core._run_evaluation(os.fspath(gt), os.fspath(det),
                                     "" if split is None else os.fspath(split), lenient,
                                     num_threads, runs, target, records,
                                     missing_as_empty=missing_as_empty,
                                     score_if_missing=score_if_missing, bootstrap=bootstrap,
                                     bootstrap_seed=bootstrap_seed,
                                     bootstrap_confidence=bootstrap_confidence,
                                     bootstrap_method=bootstrap_method)
    if score_if_missing is not None:
        raise ValueError("score_if_missing is for detection folders; give annotation dicts a "
                         "'score' array")
    result = _core._evaluate(_frames(gt, det, split, lenient, num_threads, missing_as_empty),
                             runs, bootstrap=bootstrap, bootstrap_seed=bootstrap_seed,
                             bootstrap_confidence=bootstrap_confidence,
                             bootstrap_method=bootstrap_method)
    if out is not None:
        _core._write_report(result, target, records)
    return result


_OPENPCDET_CLASSES = {0: "Car", 1: "Pedestrian", 2: "Cyclist", 3: "Van", 4: "Person_sitting",
                      5: "Truck"}


def get_official_eval_result(gt_annos: Sequence[Annos], dt_annos: Sequence[Annos],
                             current_classes: Any,
                             PR_detail_dict: Optional[dict] = None) -> Tuple[str, Dict[str, Any]]:
    """A drop-in for OpenPCDet's kitti_object_eval_python.eval.get_official_eval_result.

    Same arguments (current_classes: a name, a class index 0..5 as OpenPCDet numbers them, or a
    list of either), same return value: the text it prints (per class, the strict and the loose
    overlap set, AP and AP_R40 for bbox / bev / 3d, and aos when the first detection has a valid
    alpha) and its dict of figures ("Car_3d/moderate_R40", "Car_bev/...", "Car_image/...", and
    "Car_aos/..." with aos: AP_R40 of the strict set, numpy float64). With PR_detail_dict, its
    "bbox", "bev", "3d" (and "aos") precision arrays [class, difficulty, set, 41] are filled too.
    The numbers are `stereodet eval --compat openpcdet`'s, which reproduces OpenPCDet's code
    (docs/metrics.md, "OpenPCDet / mmdetection3d compatibility"), in C++ with the GIL released.
    """
    if not isinstance(current_classes, (list, tuple)):
        current_classes = [current_classes]
    names = []
    for c in current_classes:
        if isinstance(c, str):
            names.append(c)
        elif isinstance(c, (int, np.integer)) and int(c) in _OPENPCDET_CLASSES:
            names.append(_OPENPCDET_CLASSES[int(c)])
        else:
            raise ValueError(f"current_classes: unknown class {c!r} (a name, or 0..5 for "
                             f"{', '.join(_OPENPCDET_CLASSES.values())})")
    frames = _core._frames_from_annos(gt_annos, dt_annos)
    text, strict, loose = _core._openpcdet_eval(frames, names, 0)
    levels = ("easy", "moderate", "hard")
    figures: Dict[str, Any] = {}
    for name in names:
        if strict.aos_computed:
            for level in levels:
                cell = strict.find(name, "2d", level)
                figures[f"{name}_aos/{level}_R40"] = np.float64(cell.aos_r40)
        for key, metric in (("3d", "3d"), ("bev", "bev"), ("image", "2d")):
            for level in levels:
                cell = strict.find(name, metric, level)
                figures[f"{name}_{key}/{level}_R40"] = np.float64(cell.ap_r40)
    if PR_detail_dict is not None:
        def precision(metric: str, aos: bool = False) -> np.ndarray:
            out = np.zeros((len(names), 3, 2, 41))
            for j, name in enumerate(names):
                for k, result in enumerate((strict, loose)):
                    for level_index, level in enumerate(levels):
                        cell = result.find(name, metric, level)
                        values = cell.kitti_aos if aos else cell.kitti_precision
                        out[j, level_index, k, :len(values)] = values
            return out

        PR_detail_dict["bbox"] = precision("2d")
        if strict.aos_computed:
            PR_detail_dict["aos"] = precision("2d", aos=True)
        PR_detail_dict["bev"] = precision("bev")
        PR_detail_dict["3d"] = precision("3d")
    return text, figures


def filter_sweep(gt: Source, det: Source, bound: str, start: float = 0.0, stop: float = 200.0,
                 step: float = 5.0, *, split: Optional[PathLike] = None, lenient: bool = False,
                 missing_as_empty: bool = False, out: Optional[PathLike] = None,
                 **options: Any) -> List[Dict[str, Any]]:
    """`stereodet eval sweep`: for each value of `bound` ("min-area", "max-distance", ...) from
    `start` to `stop` by `step`, TP/FP/FN, precision and recall under the naive and the stable
    filter, one dict per class x metric x difficulty x value (pandas.DataFrame takes the list).

    gt, det, split, lenient, missing_as_empty: as evaluate(). options: evaluate()'s (classes, metrics, matcher, ...;
    one overlap set); `filters` there are the fixed extra conditions (the CLI's --where).
    Folders go through the CLI's call (RunEvaluationSweep); out: folders only, also write
    OUT/sweep.csv, the CLI's.
    """
    merged = dict(_EVALUATE_DEFAULTS, **options)
    eval_options = _single(_runs(**merged), "filter_sweep")
    if _is_path(gt) and _is_path(det):
        return _core._run_sweep(os.fspath(gt), os.fspath(det),
                                "" if split is None else os.fspath(split), lenient, eval_options,
                                bound, start, stop, step, "" if out is None else os.fspath(out),
                                missing_as_empty=missing_as_empty)
    if out is not None:
        raise ValueError("out: only for folders (the CLI's sweep.csv)")
    frames = _frames(gt, det, split, lenient, merged["num_threads"], missing_as_empty)
    return _core._filter_sweep(frames, eval_options, bound, start, stop, step)


def analyze_errors(gt: Source, det: Source, split: Optional[PathLike] = None, *,
                   background_overlap: float = 0.1, lenient: bool = False,
                   missing_as_empty: bool = False, **options: Any) -> List[Dict[str, Any]]:
    """`stereodet eval --errors`: the TIDE-style error analysis of every cell (class x metric x
    difficulty), one dict per cell in evaluate()'s order, as each results.json cell's "errors"
    (count, delta_ap_r40 and delta_ap_r11 per type: cls, loc, both, dupe, bkg, missed; special:
    fp_r40, fn_r40, ...; the association's tp, fp, fn at score -inf; ap_r40 as is) with its
    "class", "metric", "difficulty" and "evaluated" (docs/metrics.md, "Error analysis (TIDE)").

    gt, det, split, lenient, missing_as_empty: as evaluate(). options: evaluate()'s (classes,
    metrics, matcher, ...; one overlap set, no compat "openpcdet"). background_overlap: a false
    positive overlapping every label by at most this is a background error (TIDE's 0.1).
    """
    merged = dict(_EVALUATE_DEFAULTS, **options)
    eval_options = _single(_runs(**merged), "analyze_errors")
    frames = _frames(gt, det, split, lenient, merged["num_threads"], missing_as_empty)
    return json.loads(_core._analyze_errors(frames, eval_options, background_overlap))


def compare(gt: Source, det_a: Source, det_b: Source, *, split: Optional[PathLike] = None,
            calib: Any = None, disparity_error_px: float = 1.0, lenient: bool = False,
            missing_as_empty: bool = False, out: Optional[PathLike] = None,
            **options: Any) -> List[Dict[str, Any]]:
    """`stereodet eval compare`: the 3D localization error of two detection sets on the same
    labels (e.g. stereo vs LiDAR) per label-distance bin, beside the stereo depth-error model
    dz = z^2 / (b f) * dd.

    calib: a stereodet.kitti.Calibration for b and f (default: KITTI's frame 000000), or a path to
    a calibration file. options: evaluate()'s (one overlap set). Folders with calib None or a path
    go through the CLI's call (RunEvaluationCompare); out: only then, also write OUT/compare.csv,
    the CLI's. Returns one dict per class x metric x difficulty x distance bin: counts and mean
    |dz| of A and B, B - A, centre errors, the model's dz.
    """
    from . import kitti

    merged = dict(_EVALUATE_DEFAULTS, **options)
    opts = _single(_runs(**merged), "compare")
    folders = _is_path(gt) and _is_path(det_a) and _is_path(det_b)
    if folders and (calib is None or _is_path(calib)):
        return _core._run_compare(os.fspath(gt), os.fspath(det_a), os.fspath(det_b),
                                  "" if split is None else os.fspath(split), lenient, opts,
                                  "" if calib is None else os.fspath(calib), disparity_error_px,
                                  "" if out is None else os.fspath(out),
                                  missing_as_empty=missing_as_empty)
    if out is not None:
        raise ValueError("out: only for folders with calib None or a path (the CLI's "
                         "compare.csv)")
    a = _core._evaluate(
        _frames(gt, det_a, split, lenient, merged["num_threads"], missing_as_empty), [opts])
    b = _core._evaluate(
        _frames(gt, det_b, split, lenient, merged["num_threads"], missing_as_empty), [opts])
    if calib is None:
        calib = kitti.Calibration.kitti_like()
    elif _is_path(calib):
        calib = kitti.read_calib(calib)
    return _core._compare(a, b, calib.baseline_m, calib.focal_px, disparity_error_px)


# evaluate()'s keyword options and their defaults, for filter_sweep() and compare().
_EVALUATE_DEFAULTS = {name: p.default for name, p in inspect.signature(evaluate).parameters.items()
                      if p.kind == p.KEYWORD_ONLY
                      and name not in ("lenient", "missing_as_empty", "out", "score_if_missing",
                                       "bootstrap", "bootstrap_seed", "bootstrap_confidence",
                                       "bootstrap_method")}
