"""Stereo features from numpy images: disparity, depth, height, RGB-H / RGB-D, point clouds.

Images use OpenCV's layout: (H, W, 3) uint8 in B, G, R order (what cv2.imread returns), or (H, W)
uint8 grey where a grey image will do; a wrong dtype or shape raises ValueError. Float images are
(H, W) float32: disparity in pixels (-1 where there is none), depth and height in metres (NaN where
there is no stereo); code images (height and depth quantized for the networks) are (H, W) uint16 with
0 = no stereo. The pair is KITTI's cameras 2 (left) and 3 (right), rectified, and `calib` is a
stereodet.kitti.Calibration.

Every algorithm takes the fields of its C++ options struct as keyword arguments, with the library's
defaults (docs/stereo.md): disparity(left, right, method="sgbm", num_disparities=64,
sgbm={"block_size": 3}). The structs are classes here too (DisparityOptions, ...; repr() shows every
field), accepted wherever a dict of their fields is. The GIL is released around the C++ work.

This module loads OpenCV (stereodet._stereo); `import stereodet` alone does not.
"""

from __future__ import annotations

import os
from typing import Any, Dict, Iterable, Mapping, Optional, Tuple, Union

import numpy as np

from . import _core  # noqa: F401  (registers Calibration and the error types first)
from . import _stereo
from ._stereo import (BlockMatchingOptions, BlurOptions, DepthQuantization, DisparityOptions,
                      GroundPlaneOptions, HeightQuantization, PointCloudOptions, SemiGlobalOptions,
                      StereoOptions, WlsFilterOptions)
from .kitti import Calibration

__all__ = [
    "BlockMatchingOptions", "BlurOptions", "DepthQuantization", "DisparityOptions",
    "GroundPlaneOptions", "HeightQuantization", "PointCloudOptions", "SemiGlobalOptions",
    "StereoOptions", "WlsFilterOptions",
    "depth_from_disparity", "disparity", "encode", "fit_ground_plane", "height_from_disparity",
    "pack_rgbh", "point_cloud", "points_in_rect", "quantize_depth", "quantize_height",
    "read_image", "rgb_planar", "rgbd_planar", "rgbh_planar", "unpack_rgbh",
]

for _options in (BlockMatchingOptions, BlurOptions, DepthQuantization, DisparityOptions,
                 GroundPlaneOptions, HeightQuantization, PointCloudOptions, SemiGlobalOptions,
                 StereoOptions, WlsFilterOptions):
    _options.__module__ = __name__

Ground = Optional[Mapping[str, Any]]


def disparity(left: np.ndarray, right: np.ndarray, **options: Any) -> np.ndarray:
    """Disparity of a rectified pair with OpenCV's StereoBM (default) or StereoSGBM.

    left, right: (H, W, 3) BGR or (H, W) grey uint8 images of the same size.
    options: DisparityOptions' fields (method="bm"|"sgbm", num_disparities=128, min_disparity,
    uniqueness_ratio, speckle_window_px, speckle_range_px, left_right_max_diff_px, bm={...},
    sgbm={...} with mode="sgbm"|"hh"|"sgbm3way"|"hh4", colour=True for SGBM on the BGR images,
    p1/p2 for OpenCV's P1/P2 themselves, wls={"enabled": True, "lambda_": 8000, ...} for
    ximgproc's WLS post-filter, match_scale=0.5 to match at half the size: the result is brought
    back to (H, W) nearest-neighbour, values in full-size px).
    Returns (H, W) float32 pixels (u_left - u_right, 1/16 px steps), -1 where there is no match.
    """
    return _stereo.disparity(left, right, DisparityOptions(**options))


def depth_from_disparity(disparity: np.ndarray, calib: Calibration) -> np.ndarray:
    """(H, W) float32 depth in front of camera 2, m (f b / d), NaN where the disparity is invalid."""
    return _stereo.depth_from_disparity(disparity, calib)


def points_in_rect(disparity: np.ndarray, calib: Calibration) -> np.ndarray:
    """(H, W, 3) float32 rect-frame points (x, y, z, m) of every pixel, NaN where invalid."""
    return _stereo.points_in_rect(disparity, calib)


def fit_ground_plane(disparity: np.ndarray, calib: Calibration, **options: Any) -> Dict[str, Any]:
    """RANSAC fit of the road to the stereo points of the lower image (never raises for bad data:
    it falls back to the nominal plane).

    options: GroundPlaneOptions' fields. Returns a dict: normal_in_rect (3,), offset_m (the plane
    n . X + offset = 0, n pointing up), fitted, reason ("fitted" or why the fallback was used),
    samples, inliers, camera_height_m, tilt_deg. The dict is a `ground` for the functions below.
    """
    return _stereo.fit_ground_plane(disparity, calib, GroundPlaneOptions(**options))


def height_from_disparity(disparity: np.ndarray, calib: Calibration,
                          ground: Ground = None) -> np.ndarray:
    """(H, W) float32 height above the ground, m, NaN where the disparity is invalid.

    ground: fit_ground_plane's dict (or any dict with normal_in_rect and offset_m); None for the
    nominal plane, a flat road 1.65 m below the rect origin.
    """
    return _stereo.height_from_disparity(disparity, calib, ground)


def quantize_height(height_m: np.ndarray, **options: Any) -> np.ndarray:
    """Height codes, (H, W) uint16: 1 + round((clamp(h) - min_m) / (max_m - min_m) * 510), 0 for NaN.

    options: HeightQuantization's fields (min_m=-1, max_m=4).
    """
    return _stereo.quantize_height(height_m, HeightQuantization(**options))


def quantize_depth(depth_m: np.ndarray, **options: Any) -> np.ndarray:
    """Depth codes, (H, W) uint16 in 1..2^bits - 1, 0 for NaN.

    options: DepthQuantization's fields (min_m=0, max_m=80, bits=16).
    """
    return _stereo.quantize_depth(depth_m, DepthQuantization(**options))


def read_image(path: Union[str, "os.PathLike[str]"]) -> np.ndarray:
    """An image file (PNG, JPEG, ...) as an (H, W, 3) uint8 BGR array, decoded by OpenCV (what
    cv2.imread gives). Raises OSError naming the file when it is missing or does not decode."""
    return _stereo.read_image(str(path))


def pack_rgbh(bgr: np.ndarray, height_code: np.ndarray) -> np.ndarray:
    """RGB-H: the 5 high bits of each colour channel and the 9-bit height code in one (H, W, 3)
    uint8 image (bit layout in stereo/rgbh.h); codes above 511 raise ValueError."""
    return _stereo.pack_rgbh(bgr, height_code)


def unpack_rgbh(packed: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """The exact inverse of pack_rgbh: ((H, W, 3) uint8 5-bit colour 0..31, (H, W) uint16 codes)."""
    return _stereo.unpack_rgbh(packed)


def rgb_planar(bgr: np.ndarray) -> np.ndarray:
    """The network input "rgb": (3, H, W) float32 R, G, B = 8-bit / 255."""
    return _stereo.rgb_planar(bgr)


def rgbh_planar(packed: np.ndarray, layout: str = "rgbh") -> np.ndarray:
    """From a packed RGB-H image: "rgbh" (4, H, W) R5/31, G5/31, B5/31, H/511, or "rgbh-fixed"
    (3, H, W) Y, C, H/511 (the fixed colour compression of stereo/rgbh.h). float32."""
    return _stereo.rgbh_planar(packed, layout)


def rgbd_planar(bgr: np.ndarray, depth_code: np.ndarray, height_code: np.ndarray,
                **depth: Any) -> np.ndarray:
    """The network input "rgbd": (5, H, W) float32 R, G, B (/255), depth code / max code, H/511.

    depth: the DepthQuantization the depth codes were made with (min_m, max_m, bits).
    """
    return _stereo.rgbd_planar(bgr, depth_code, height_code, DepthQuantization(**depth))


def point_cloud(disparity: np.ndarray, left: np.ndarray, calib: Calibration, ground: Ground = None,
                **options: Any) -> np.ndarray:
    """A pseudo-LiDAR scan: (N, 4) float32 x, y, z (velo frame, m) and reflectance (the left grey
    level / 255) of the valid pixels, row-major, as a KITTI velodyne .bin holds it.

    left: the left image (BGR or grey) the disparity belongs to. ground: as height_from_disparity.
    options: PointCloudOptions' fields (max_depth_m=80, min_height_m=-1, max_height_m=3, beams=0
    for every point, or LiDAR-like subsampling with min/max_elevation_deg and azimuth_step_deg).
    """
    return _stereo.point_cloud(disparity, left, calib, ground, PointCloudOptions(**options))


def encode(left: np.ndarray, right: np.ndarray, calib: Calibration,
           outputs: Iterable[str] = ("rgbh",), **options: Any) -> Dict[str, Any]:
    """The whole per-frame pipeline in one fused pass, as `stereodet stereo` runs it: disparity ->
    ground fit -> height codes, plus what `outputs` asks for.

    left, right: (H, W, 3) BGR uint8 images. outputs: any of "rgbh", "depth", "points".
    options: StereoOptions' fields, each a dict of its struct's fields: disparity, ground,
    height, depth, points, blur (e.g. blur={"sigma_px": 2}).
    Returns a dict: network_image (the left image the network sees, blurred if blur is on),
    disparity, ground (as fit_ground_plane), height_code, and depth_code / rgbh / points when asked.
    The same numbers as the separate functions above.
    """
    wanted = set(outputs)
    unknown = wanted - {"rgbh", "depth", "points"}
    if unknown:
        raise ValueError(f"outputs: unknown {sorted(unknown)} (rgbh, depth, points)")
    return _stereo.encode(left, right, calib, StereoOptions(**options), "rgbh" in wanted,
                          "depth" in wanted, "points" in wanted)
