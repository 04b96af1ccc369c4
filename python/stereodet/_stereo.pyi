# Type stubs of the C++ extension stereodet._stereo (python/src/stereo_module.cc), used through
# stereodet.stereo (which documents every function).
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple

import numpy as np

from ._core import Calibration

def _calls_in_progress() -> int: ...
def _run_cli(args: Sequence[str]) -> int: ...
def read_image(path: str) -> np.ndarray: ...

class _Options:
    _fields: Tuple[str, ...]
    def __init__(self, fields: Optional[Dict[str, Any]] = None, **kwargs: Any) -> None: ...
    def check(self) -> None: ...

class BlockMatchingOptions(_Options):
    block_size: int
    xsobel_prefilter: bool
    prefilter_size: int
    prefilter_cap: int
    texture_threshold: int

class SemiGlobalOptions(_Options):
    block_size: int
    p1_per_pixel: int
    p2_per_pixel: int
    prefilter_cap: int
    full_8_directions: bool

class DisparityOptions(_Options):
    method: str
    num_disparities: int
    min_disparity: int
    uniqueness_ratio: int
    speckle_window_px: int
    speckle_range_px: int
    left_right_max_diff_px: int
    bm: BlockMatchingOptions
    sgbm: SemiGlobalOptions
    match_scale: float

class GroundPlaneOptions(_Options):
    roi_fraction: float
    sample_step_px: int
    min_depth_m: float
    max_depth_m: float
    max_lateral_m: float
    max_samples: int
    iterations: int
    inlier_threshold_m: float
    seed: int
    min_inliers: int
    min_inlier_fraction: float
    max_tilt_deg: float
    min_camera_height_m: float
    max_camera_height_m: float
    nominal_camera_height_m: float
    enabled: bool

class HeightQuantization(_Options):
    min_m: float
    max_m: float

class DepthQuantization(_Options):
    min_m: float
    max_m: float
    bits: int

class PointCloudOptions(_Options):
    max_depth_m: float
    min_height_m: float
    max_height_m: float
    beams: int
    min_elevation_deg: float
    max_elevation_deg: float
    azimuth_step_deg: float

class BlurOptions(_Options):
    sigma_px: float
    mode: str

class StereoOptions(_Options):
    disparity: DisparityOptions
    ground: GroundPlaneOptions
    height: HeightQuantization
    depth: DepthQuantization
    points: PointCloudOptions
    blur: BlurOptions

Ground = Optional[Mapping[str, Any]]

def disparity(left: np.ndarray, right: np.ndarray, options: DisparityOptions) -> np.ndarray: ...
def depth_from_disparity(disparity: np.ndarray, calib: Calibration) -> np.ndarray: ...
def points_in_rect(disparity: np.ndarray, calib: Calibration) -> np.ndarray: ...
def fit_ground_plane(disparity: np.ndarray, calib: Calibration,
                     options: GroundPlaneOptions) -> Dict[str, Any]: ...
def height_from_disparity(disparity: np.ndarray, calib: Calibration, ground: Ground) -> np.ndarray: ...
def quantize_height(height_m: np.ndarray, quantization: HeightQuantization) -> np.ndarray: ...
def quantize_depth(depth_m: np.ndarray, quantization: DepthQuantization) -> np.ndarray: ...
def pack_rgbh(bgr: np.ndarray, height_code: np.ndarray) -> np.ndarray: ...
def unpack_rgbh(packed: np.ndarray) -> Tuple[np.ndarray, np.ndarray]: ...
def rgb_planar(bgr: np.ndarray) -> np.ndarray: ...
def rgbh_planar(packed: np.ndarray, layout: str) -> np.ndarray: ...
def rgbd_planar(bgr: np.ndarray, depth_code: np.ndarray, height_code: np.ndarray,
                depth: DepthQuantization) -> np.ndarray: ...
def point_cloud(disparity: np.ndarray, left: np.ndarray, calib: Calibration, ground: Ground,
                options: PointCloudOptions) -> np.ndarray: ...
def encode(left: np.ndarray, right: np.ndarray, calib: Calibration, options: StereoOptions,
           rgbh: bool, depth: bool, points: bool) -> Dict[str, Any]: ...
