"""KITTI files to and from numpy: labels, detections, calibrations, velodyne scans.

Labels and detections are annotation dicts, one per file, in the layout OpenPCDet and
mmdetection3d pass around (their kitti_infos "annos" and prediction dicts):

    name        (N,)   str      class name ("Car", "DontCare", ...)
    truncated   (N,)   float64  [0, 1]
    occluded    (N,)   int64    0 visible, 1 partly, 2 largely, 3 unknown (-1 DontCare)
    alpha       (N,)   float64  observation angle, radians
    bbox        (N, 4) float64  left, top, right, bottom, px (left image)
    dimensions  (N, 3) float64  l, h, w, metres -- OpenPCDet's order, NOT the file's h, w, l
    location    (N, 3) float64  x, y, z of the bottom centre, rect (camera) frame, metres
    rotation_y  (N,)   float64  radians about the camera's y axis
    score       (N,)   float64  detections only

Reading and writing are exact: a file written by write_objects reads back to the same numbers, and
KITTI's own files round-trip byte for byte. Bad lines raise stereodet.ParseError ("FILE:LINE: field
F: message", as the command line prints it); missing files raise OSError.
"""

from __future__ import annotations

import os
from typing import Dict, List, Optional, Union

import numpy as np

from . import _core
from ._core import Calibration

Calibration.__module__ = __name__  # documented (and pickled) as stereodet.kitti.Calibration

PathLike = Union[str, "os.PathLike[str]"]
Annos = Dict[str, np.ndarray]

__all__ = [
    "Calibration",
    "format_calib",
    "format_objects",
    "parse_calib",
    "parse_objects",
    "read_calib",
    "read_objects",
    "read_velodyne",
    "write_calib",
    "write_objects",
    "write_velodyne",
]


def _collect(result, problems: Optional[List[str]]) -> Annos:
    annos, found = result
    if problems is not None:
        problems.extend(found)
    return annos


def read_objects(path: PathLike, kind: str = "label", *, lenient: bool = False,
                 problems: Optional[List[str]] = None) -> Annos:
    """Reads a KITTI label or detection file into an annotation dict (the module's docstring).

    kind: "label" (exactly 15 fields a line), "detection" (16, the score last) or "any" (either,
    line by line, as KITTI's devkit reads result files; a line without a score gets NaN).
    The dict has "score" for detections (and for "any" when a line has one).
    lenient: skip bad lines instead of raising; with a list as `problems`, one
    "FILE:LINE: field F: message" string is appended to it per skipped line.
    """
    return _collect(_core._read_objects(os.fspath(path), kind, lenient), problems)


def parse_objects(text: str, kind: str = "label", *, source: str = "<string>",
                  lenient: bool = False, problems: Optional[List[str]] = None) -> Annos:
    """Like read_objects, from the text of a file; `source` names it in error messages."""
    return _collect(_core._parse_objects(text, source, kind, lenient), problems)


def format_objects(annos: Annos, kind: Optional[str] = None) -> str:
    """The text of a label or detection file holding `annos`, one line per object.

    kind: "label" (15 fields; a "score" key is ignored, as in OpenPCDet's ground-truth dicts, whose
    scores are zeros), "detection" (16 fields; "score" required), or None: a detection file when
    the dict has "score". Numbers are written with two decimals when that reads back exactly
    (KITTI's style), otherwise with the shortest text that does. Raises ValueError for a missing
    key, a wrong shape, a non-finite number or a negative dimension other than KITTI's -1.
    """
    return _core._format_objects(annos, kind)


def write_objects(path: PathLike, annos: Annos, kind: Optional[str] = None) -> None:
    """Writes format_objects(annos, kind) to `path` atomically (temporary file, then rename)."""
    _core._write_objects(os.fspath(path), annos, kind)


def read_calib(path: PathLike) -> Calibration:
    """Reads a KITTI object-benchmark calibration file (P0..P3, R0_rect, Tr_velo_to_cam[,
    Tr_imu_to_velo]; the tracking benchmark's spellings too)."""
    return _core._read_calib(os.fspath(path))


def parse_calib(text: str, *, source: str = "<string>") -> Calibration:
    """Like read_calib, from the text of a file; `source` names it in error messages."""
    return _core._parse_calib(text, source)


def format_calib(calib: Calibration) -> str:
    """KITTI's layout, "KEY: v v v ..." (exact: it reads back to the same numbers)."""
    return _core._format_calib(calib)


def write_calib(path: PathLike, calib: Calibration) -> None:
    """Writes format_calib(calib) to `path` atomically."""
    _core._write_calib(os.fspath(path), calib)


def read_velodyne(path: PathLike) -> np.ndarray:
    """A KITTI velodyne scan as an (N, 4) float32 array: x, y, z (velo frame, m), reflectance."""
    return _core._read_velodyne(os.fspath(path))


def write_velodyne(path: PathLike, points: np.ndarray) -> None:
    """Writes an (N, 4) array (converted to float32) as a KITTI velodyne scan, atomically."""
    _core._write_velodyne(os.fspath(path), points)
