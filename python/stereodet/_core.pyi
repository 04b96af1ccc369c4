# Type stubs of the C++ extension stereodet._core (python/src/*.cc). The documented interface is the
# pure-Python package; these names are its internals unless re-exported there.
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

__version__: str

class ParseError(ValueError):
    file: str
    line: int
    field: str
    message: str

def _calls_in_progress() -> int: ...
def _run_cli(args: Sequence[str]) -> int: ...

# --- KITTI I/O (python/src/kitti_bindings.cc; documented in stereodet.kitti) ---
Annos = Dict[str, np.ndarray]

def _parse_objects(text: str, source: str, kind: str, lenient: bool) -> Tuple[Annos, List[str]]: ...
def _read_objects(path: str, kind: str, lenient: bool) -> Tuple[Annos, List[str]]: ...
def _format_objects(annos: Annos, kind: Optional[str]) -> str: ...
def _write_objects(path: str, annos: Annos, kind: Optional[str]) -> None: ...

class Calibration:
    projection: np.ndarray  # (4, 3, 4)
    rect_from_cam0: np.ndarray  # (3, 3)
    cam0_from_velo: np.ndarray  # (4, 4)
    velo_from_imu: np.ndarray  # (4, 4)
    def __init__(self, *, projection: Optional[np.ndarray] = None,
                 rect_from_cam0: Optional[np.ndarray] = None,
                 cam0_from_velo: Optional[np.ndarray] = None,
                 velo_from_imu: Optional[np.ndarray] = None) -> None: ...
    @property
    def focal_px(self) -> float: ...
    @property
    def principal_point_px(self) -> np.ndarray: ...
    @property
    def baseline_m(self) -> float: ...
    @property
    def rect_from_velo(self) -> np.ndarray: ...
    def camera_centre_in_rect(self, camera: int) -> np.ndarray: ...
    def project_rect_to_image(self, points_in_rect: np.ndarray,
                              camera: int = 2) -> Tuple[np.ndarray, np.ndarray]: ...
    def unproject_image_to_rect(self, pixels: np.ndarray, depth_m: np.ndarray,
                                camera: int = 2) -> np.ndarray: ...
    def check_stereo(self) -> None: ...
    def to_kitti_dict(self) -> Dict[str, np.ndarray]: ...
    @staticmethod
    def from_kitti_dict(kitti: Dict[str, np.ndarray]) -> "Calibration": ...
    @staticmethod
    def kitti_like() -> "Calibration": ...

def _parse_calib(text: str, source: str) -> Calibration: ...
def _read_calib(path: str) -> Calibration: ...
def _format_calib(calib: Calibration) -> str: ...
def _write_calib(path: str, calib: Calibration) -> None: ...
def _read_velodyne(path: str) -> np.ndarray: ...
def _write_velodyne(path: str, points: np.ndarray) -> None: ...

# --- Evaluation (python/src/eval_bindings.cc; documented in stereodet.evaluation) ---
class ClassSpec:
    name: str
    neighbours: List[str]
    min_overlap: Tuple[float, float, float]
    def __init__(self, name: str, neighbours: List[str] = ...,
                 min_overlap: Tuple[float, float, float] = ...) -> None: ...

def _kitti_class_spec(name: str, loose: bool = False) -> ClassSpec: ...
def _openpcdet_class_spec(name: str, loose: bool = False) -> ClassSpec: ...

class EvalOptions:
    classes: List[ClassSpec]
    metrics: List[str]
    difficulties: List[str]
    matcher: str
    compat: str
    score_transform: str
    filters: Any  # set: str, dict or (bound, value) pairs; get: the CLI's text
    filter_mode: str
    breakdowns: Any  # set: str or list of the CLI's --breakdown texts; get: list of str
    score_threshold: float
    require_detections: bool
    compute_aos: bool
    calibration_bins: int
    distance_bin_m: float
    max_distance_m: float
    keep_records: bool
    num_threads: int
    def __init__(self) -> None: ...
    def check(self) -> None: ...

class ClassResult:
    class_name: str
    metric: str
    difficulty: str
    min_overlap: float
    evaluated: bool
    num_valid_labels: int
    num_detections: int
    ap_r40: float
    ap_r11: float
    ap_voc: float
    aos_r40: float
    aos_r11: float
    has_aos: bool
    small_sample: bool
    at_threshold: Dict[str, float]
    best_f1: Dict[str, float]
    curve: Dict[str, np.ndarray]
    kitti_precision: np.ndarray
    kitti_aos: np.ndarray
    kitti_thresholds: np.ndarray
    filtered: Optional[Dict[str, Any]]
    breakdown: List[Dict[str, Any]]
    brier: Dict[str, float]
    ece: float

class EvalResult:
    num_frames: int
    aos_computed: bool
    probability_metrics: bool
    seconds: float
    options: EvalOptions  # with several runs the first run's
    overlaps: List[str]  # per run: "strict", "loose" (or "custom")
    runs: List["EvalResult"]  # one per overlap set
    files: List[Any]  # pathlib.Path of every file written with out=
    cells: List[ClassResult]
    def find(self, class_name: str, metric: str = "3d", difficulty: Any = "moderate", *,
             overlaps: Optional[str] = None) -> Optional[ClassResult]: ...
    def ap(self, class_name: str, metric: str = "3d", difficulty: Any = "moderate",
           recall: str = "r40", *, overlaps: Optional[str] = None) -> float: ...
    def to_dict(self) -> Dict[str, Any]: ...
    def rows(self) -> List[Dict[str, Any]]: ...
    def records(self) -> Dict[str, np.ndarray]: ...
    def table(self) -> str: ...

class _Frames:
    num_frames: int
    notices: List[str]
    ids: List[str]

def _frames_from_annos(gt_annos: Sequence[Annos], dt_annos: Sequence[Annos]) -> _Frames: ...
def _frames_from_folders(gt: str, det: str, split: str, lenient: bool, num_threads: int,
                         missing_as_empty: bool = ...,
                         score_if_missing: Optional[float] = ...) -> _Frames: ...
def _evaluate(frames: _Frames, options: List[EvalOptions], bootstrap: int = ...,
              bootstrap_seed: int = ..., bootstrap_confidence: float = ...,
              bootstrap_method: str = ...) -> EvalResult: ...
def _overlap_set_runs(base: EvalOptions, overlaps: List[str]) -> List[EvalOptions]: ...
def _run_evaluation(gt: str, det: str, split: str, lenient: bool, num_threads: int,
                    runs: List[EvalOptions], out: str, records: bool,
                    missing_as_empty: bool = ...,
                    score_if_missing: Optional[float] = ..., bootstrap: int = ...,
                    bootstrap_seed: int = ..., bootstrap_confidence: float = ...,
              bootstrap_method: str = ...) -> EvalResult: ...
def _write_report(result: EvalResult, out: str, records: bool) -> None: ...
def _openpcdet_eval(frames: _Frames, class_names: List[str],
                    num_threads: int) -> Tuple[str, EvalResult, EvalResult]: ...
def _analyze_errors(frames: _Frames, options: EvalOptions, background_overlap: float) -> str: ...
def _filter_sweep(frames: _Frames, options: EvalOptions, bound: str, start: float, stop: float,
                  step: float) -> List[Dict[str, Any]]: ...
def _run_sweep(gt: str, det: str, split: str, lenient: bool, options: EvalOptions, bound: str,
               start: float, stop: float, step: float, out: str) -> List[Dict[str, Any]]: ...
def _run_compare(gt: str, det_a: str, det_b: str, split: str, lenient: bool, options: EvalOptions,
                 calib: str, disparity_error_px: float, out: str) -> List[Dict[str, Any]]: ...
def _compare(a: EvalResult, b: EvalResult, baseline_m: float, focal_px: float,
             disparity_error_px: float) -> List[Dict[str, Any]]: ...
def _coco_evaluate(gt_text: str, gt_source: str, dt_text: str, dt_source: str,
                   honor_ignore_flag: bool = ..., max_dets: List[int] = ...,
                   num_threads: int = ..., matcher: str = ..., score_metrics: bool = ...,
                   score_threshold: float = ..., score_transform: str = ...,
                   calibration_bins: int = ..., bootstrap: int = ..., bootstrap_seed: int = ...,
                   bootstrap_confidence: float = ..., bootstrap_method: str = ...,
                   dt_b_text: Optional[str] = ...,
                   dt_b_source: str = ...) -> Dict[str, Any]: ...
